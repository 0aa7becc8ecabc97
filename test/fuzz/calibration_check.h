/// \file calibration_check.h
/// Shared body of the calibration fuzz targets: parse a file, and when the parser accepts it,
/// check the promises of Calibration::finalize() and decode a fixed packet with it.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_common.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace fuzz {

/// A packet with returns on every laser at 8 azimuths (2..100 m), from the core encoder.
inline const core::RawPacket& probePacket() {
  static const core::RawPacket packet = [] {
    core::PacketEncoder enc(core::Calibration::nominalHdl64eS2());
    core::Firing firings[6];
    for (int f = 0; f < 6; ++f) {
      firings[f].azimuth = static_cast<std::uint16_t>(4500 * f + 17);
      for (int l = 0; l < core::kNumLasers; ++l) {
        firings[f].distance[l] = static_cast<std::uint16_t>(1000 + 800 * l + 37 * f);
        firings[f].intensity[l] = static_cast<std::uint8_t>(4 * l + f);
      }
    }
    return enc.encode(firings, 123456);
  }();
  return packet;
}

/// Parses with `load` (a core reader taking a path). Only CalibrationError may escape a reader;
/// anything else (another exception type, a crash, UB) is a finding.
template <typename Loader>
void checkCalibration(Loader load, const std::string& path) {
  core::Calibration cal;
  try {
    cal = load(path);
  } catch (const core::CalibrationError& e) {
    // The message must name the file.
    UD_FUZZ_CHECK(std::string(e.what()).find(path) != std::string::npos);
    return;
  }
  UD_FUZZ_CHECK(cal.lasers.size() == static_cast<std::size_t>(core::kNumLasers));
  UD_FUZZ_CHECK(cal.ring_of_laser.size() == static_cast<std::size_t>(core::kNumLasers));
  UD_FUZZ_CHECK(std::isfinite(cal.distance_resolution_m) && cal.distance_resolution_m > 0.0);
  std::vector<int> ring_used(core::kNumLasers, 0);
  for (int l = 0; l < core::kNumLasers; ++l) {
    const core::LaserCorrection& c = cal.lasers[l];
    UD_FUZZ_CHECK(c.laser_id == l);
    UD_FUZZ_CHECK(std::isfinite(c.rot_correction_rad) && std::isfinite(c.vert_correction_rad));
    UD_FUZZ_CHECK(c.min_intensity >= 0 && c.min_intensity <= c.max_intensity &&
                  c.max_intensity <= 255);
    const int r = cal.ring_of_laser[l];
    UD_FUZZ_CHECK(r >= 0 && r < core::kNumLasers);
    ++ring_used[r];
  }
  for (int r = 0; r < core::kNumLasers; ++r) UD_FUZZ_CHECK(ring_used[r] == 1);
  // Rings ordered by elevation.
  for (int a = 0; a < core::kNumLasers; ++a) {
    for (int b = 0; b < core::kNumLasers; ++b) {
      if (cal.ring_of_laser[a] < cal.ring_of_laser[b]) {
        UD_FUZZ_CHECK(cal.lasers[a].vert_correction_rad <= cal.lasers[b].vert_correction_rad);
      }
    }
  }

  // An accepted calibration must decode into finite points with valid rings and intensities.
  const core::PacketDecoder decoder(cal, core::DecoderParams());
  CloudXYZIRT cloud;
  const core::RawPacket& packet = probePacket();
  UD_FUZZ_CHECK(decoder.decode(packet.data(), packet.size(), 0.0, &cloud, nullptr) ==
                core::PacketStatus::kOk);
  for (const PointXYZIRT& p : cloud.points) {
    UD_FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    UD_FUZZ_CHECK(p.ring < core::kNumLasers);
    UD_FUZZ_CHECK(p.intensity >= 0.0f && p.intensity <= 255.0f);
  }
}

}  // namespace fuzz
}  // namespace urban_detection
