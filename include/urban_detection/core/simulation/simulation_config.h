/// \file simulation_config.h
/// The YAML description of a simulated drive (scene, drive, sensor), ROS-free.
///
/// Layout (every key optional; a missing key keeps the default of the params structs, an
/// unknown key is an error so that typos do not pass silently):
/// ```yaml
/// seed: 42
/// scene:   {start_x_m, slope, camber, curb_height_m, terrain_width_m,
///           sections: [{type: street|intersection, length_m, road_half_width_m,
///                       sidewalk_width_m, buildings_left, buildings_right, parking, furniture}],
///           buildings: {BuildingParams fields}, objects: {StreetObjectParams fields},
///           vegetation: {VegetationParams fields}}
/// drive:   {waypoints: [[x, y], ...], speed_mps}
/// sensor:  {SimSensorParams fields, calibration: ""}   # "" = nominal HDL-64E S2
/// ```
/// See config/demo_drive.yaml for the default drive with every field and its unit.
#pragma once

#include <string>

#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/scene_generator.h"

namespace urban_detection {
namespace core {

/// Everything needed to run a simulated drive.
struct SimulationConfig {
  SceneParams scene;
  DriveParams drive;
  SimSensorParams sensor;
  std::string calibration_file;  // "" = Calibration::nominalHdl64eS2()
};

/// Parses a YAML file (see above). Relative calibration paths are resolved against the YAML
/// file's directory. Throws std::invalid_argument naming the file and the offending key.
SimulationConfig loadSimulationConfig(const std::string& path);
/// Same, from YAML text (relative paths are left as they are).
SimulationConfig parseSimulationConfig(const std::string& yaml_text,
                                       const std::string& source_name = "<string>");

}  // namespace core
}  // namespace urban_detection
