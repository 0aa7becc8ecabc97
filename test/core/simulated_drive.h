// The shipped simulated drive (config/demo_drive.yaml) for the core tests: its first
// revolutions, decoded from their packets as PacketSource decodes them.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace ud_test {

inline std::vector<urban_detection::CloudXYZIRT> simulatedRevolutions(int count) {
  namespace core = urban_detection::core;
  const core::SimulationConfig c =
      core::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  core::LidarSimulator sim(core::generateScene(c.scene, c.drive), c.scene, c.drive,
                           core::Calibration::nominalHdl64eS2(), c.sensor);
  core::PacketDecoder decoder(sim.calibration(), core::DecoderParams());
  std::vector<urban_detection::CloudXYZIRT> out;
  core::SimRevolution rev;
  for (int r = 0; r < count; ++r) {
    sim.simulateNext(&rev);
    urban_detection::CloudXYZIRT cloud;
    for (std::size_t i = 0; i < rev.packets.size(); ++i) {
      core::DecodeStats stats;
      decoder.decode(rev.packets[i].data(), rev.packets[i].size(),
                     rev.packet_stamps_s[i] - rev.stamp_s, &cloud, &stats);
    }
    out.push_back(std::move(cloud));
  }
  return out;
}

}  // namespace ud_test
