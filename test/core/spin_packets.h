/// \file spin_packets.h
/// HDL-64E packets of a sensor spinning inside a uniform cylinder: every laser of every firing
/// returns the same range, the azimuth advances by a fixed step per firing. The packet tests
/// of every layer (assembler, nodelets, pcap replay, load) cut revolutions from these.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace test {

/// `count` packets of 6 firings, nominal HDL-64E S2 calibration. Firing k of packet i points at
/// (first_az_deg + (6 i + k) deg_per_firing) mod 360, returns `distance_raw` (2 mm units;
/// 5000 = 10 m) with intensity `intensity + k * intensity_step`; packet i is stamped
/// i * stamp_step_us.
inline std::vector<core::RawPacket> spinPackets(int count, double first_az_deg,
                                                double deg_per_firing, std::uint32_t stamp_step_us,
                                                std::uint8_t intensity = 50,
                                                std::uint8_t intensity_step = 0,
                                                std::uint16_t distance_raw = 5000) {
  const core::PacketEncoder encoder(core::Calibration::nominalHdl64eS2());
  std::vector<core::RawPacket> packets;
  packets.reserve(count > 0 ? static_cast<std::size_t>(count) : 0u);
  for (int i = 0; i < count; ++i) {
    core::Firing firings[6];
    for (int k = 0; k < 6; ++k) {
      const double az = std::fmod(first_az_deg + deg_per_firing * (6 * i + k), 360.0);
      firings[k].azimuth = static_cast<std::uint16_t>(std::lround(az * 100.0) % 36000);
      firings[k].distance.fill(distance_raw);
      firings[k].intensity.fill(static_cast<std::uint8_t>(intensity + k * intensity_step));
    }
    packets.push_back(encoder.encode(firings, static_cast<std::uint32_t>(i) * stamp_step_us));
  }
  return packets;
}

}  // namespace test
}  // namespace urban_detection
