/// \file synthetic_scene.h
/// A small analytic scene for the decode benchmark and the demo: a closed street of 120 m x 24 m
/// (ground plane and four walls) with one car-sized box, scanned by the packet encoder at a
/// given spin rate. Every beam hits something within 70 m, so a revolution carries all
/// 384 returns per packet.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "urban_detection/core/calibration.h"
#include "urban_detection/core/hdl64e_packet.h"

namespace urban_detection {
namespace tools {

struct SceneParams {
  double sensor_height_m = 1.8;                                    // [m] above the ground
  double street_half_length_m = 60.0, street_half_width_m = 12.0;  // [m] walls
  double box_min[3] = {6.0, 2.0, -1.8};                            // [m] car-sized box
  double box_max[3] = {10.5, 3.8, -0.3};
  double rpm = 600.0;  // [1/min]
};

/// Distance along a ray to the first surface of the scene (infinity if none).
inline double castRay(const SceneParams& s, const float o[3], const float d[3]) {
  double best = std::numeric_limits<double>::infinity();
  auto plane = [&](int axis, double value) {
    if (std::fabs(d[axis]) < 1e-9) return;
    const double t = (value - o[axis]) / d[axis];
    if (t > 0 && t < best) best = t;
  };
  plane(2, -s.sensor_height_m);
  plane(0, s.street_half_length_m);
  plane(0, -s.street_half_length_m);
  plane(1, s.street_half_width_m);
  plane(1, -s.street_half_width_m);
  // Slab test for the box.
  double t0 = 0.0, t1 = best;
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(d[a]) < 1e-12) {
      if (o[a] < s.box_min[a] || o[a] > s.box_max[a]) return best;
      continue;
    }
    double ta = (s.box_min[a] - o[a]) / d[a], tb = (s.box_max[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return best;
  }
  return t0 > 0 ? t0 : best;
}

/// Encodes `packets` consecutive packets of the scene starting at azimuth `start_deg`.
inline std::vector<core::RawPacket> scanScene(const core::PacketEncoder& encoder,
                                              const SceneParams& s, int packets,
                                              double start_deg = 0.0) {
  std::vector<core::RawPacket> out;
  out.reserve(packets);
  const double deg_per_firing = s.rpm / 60.0 * 360.0 * core::kFiringPeriodS;
  std::array<core::Firing, 6> firings;
  long firing_index = 0;
  for (int p = 0; p < packets; ++p) {
    for (core::Firing& f : firings) {
      const double deg = std::fmod(start_deg + deg_per_firing * firing_index++, 360.0);
      f.azimuth = static_cast<std::uint16_t>(static_cast<int>(std::lround(deg * 100.0)) % 36000);
      for (int l = 0; l < core::kNumLasers; ++l) {
        float o[3], d[3];
        encoder.ray(l, f.azimuth, o, d);
        const double t = castRay(s, o, d);
        std::uint16_t raw = 0;
        if (std::isfinite(t) && !encoder.rawDistance(l, t, &raw)) raw = 0;
        f.distance[l] = raw;
        f.intensity[l] = static_cast<std::uint8_t>(40 + (l * 7) % 160);
      }
    }
    const std::uint32_t stamp_us =
        static_cast<std::uint32_t>(p * 6 * core::kFiringPeriodS * 1e6) % 3600000000u;
    out.push_back(encoder.encode(firings.data(), stamp_us));
  }
  return out;
}

/// The calibration named on the command line, else the SZTAKI one from $UD_SHARED_DATA or
/// ../shared/data, else the nominal geometry.
inline core::Calibration findCalibration(const std::string& path) {
  if (!path.empty()) return core::loadCalibration(path);
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("UD_SHARED_DATA")) {
    candidates.push_back(std::string(env) + "/calibration/64e_s2.1-sztaki.yaml");
  }
  candidates.push_back("../shared/data/calibration/64e_s2.1-sztaki.yaml");
  for (const std::string& c : candidates) {
    if (std::ifstream(c).good()) return core::loadCalibration(c);
  }
  return core::Calibration::nominalHdl64eS2();
}

}  // namespace tools
}  // namespace urban_detection
