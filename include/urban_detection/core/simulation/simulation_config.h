/// \file simulation_config.h
/// The YAML description of a simulated drive (scene, drive, sensor), ROS-free.
///
/// Layout (every key optional; a missing key keeps the default of the params structs, an
/// unknown key, a value of the wrong type or out of its range is an error naming the key, so
/// that typos do not pass silently). The keys are those of the field tables of SceneParams,
/// DriveParams and SimSensorParams (docs/parameters.md), read by the one YAML reader of the
/// parameter structs (core/params/field_yaml.h):
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

/// The keys of a simulation config file: `seed`, `scene/...`, `drive/...`, `sensor/...`.
template <>
struct ParamFields<SimulationConfig> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("seed", "", 0, 1e15, "scene seed (the same seed gives the same scene)"),
      p.scene.seed);
    forEachField(p.scene, "scene", f);
    forEachField(p.drive, "drive", f);
    forEachField(p.sensor, "sensor", f);
    f(FieldInfo("sensor/calibration",
                "velodyne YAML or db.xml, relative to the config file (\"\" = nominal HDL-64E S2)"),
      p.calibration_file);
  }
};

/// "" or why `config` is invalid (table ranges, then the cross-field rules of the scene, drive
/// and sensor).
std::string validate(const SimulationConfig& config);

/// Parses a YAML file (see above). Relative calibration paths are resolved against the YAML
/// file's directory. Throws std::invalid_argument naming the file and the offending key.
SimulationConfig loadSimulationConfig(const std::string& path);
/// Same, from YAML text (relative paths are left as they are).
SimulationConfig parseSimulationConfig(const std::string& yaml_text,
                                       const std::string& source_name = "<string>");

}  // namespace core
}  // namespace urban_detection
