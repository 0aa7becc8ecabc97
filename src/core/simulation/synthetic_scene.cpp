#include "urban_detection/core/simulation/synthetic_scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>

namespace urban_detection {
namespace core {

double castRay(const SyntheticSceneParams& s, const float o[3], const float d[3]) {
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

std::vector<RawPacket> scanScene(const PacketEncoder& encoder, const SyntheticSceneParams& s,
                                 int packets, double start_deg) {
  std::vector<RawPacket> out;
  out.reserve(packets);
  const double deg_per_firing = s.rpm / 60.0 * 360.0 * kFiringPeriodS;
  std::array<Firing, 6> firings;
  long firing_index = 0;
  for (int p = 0; p < packets; ++p) {
    for (Firing& f : firings) {
      const double deg = std::fmod(start_deg + deg_per_firing * firing_index++, 360.0);
      f.azimuth = static_cast<std::uint16_t>(static_cast<int>(std::lround(deg * 100.0)) % 36000);
      for (int l = 0; l < kNumLasers; ++l) {
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
        static_cast<std::uint32_t>(p * 6 * kFiringPeriodS * 1e6) % 3600000000u;
    out.push_back(encoder.encode(firings.data(), stamp_us));
  }
  return out;
}

std::vector<float> readKittiBinXyz(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<float> xyzr;
  if (!in) return {};
  in.seekg(0, std::ios::end);
  const std::streamoff bytes = in.tellg();
  in.seekg(0);
  xyzr.resize(static_cast<std::size_t>(bytes) / sizeof(float) / 4 * 4);
  in.read(reinterpret_cast<char*>(xyzr.data()),
          static_cast<std::streamsize>(xyzr.size() * sizeof(float)));
  if (!in) return {};
  std::vector<float> xyz;
  xyz.reserve(xyzr.size() / 4 * 3);
  for (std::size_t i = 0; i + 3 < xyzr.size(); i += 4) {
    xyz.insert(xyz.end(), {xyzr[i], xyzr[i + 1], xyzr[i + 2]});
  }
  return xyz;
}

std::vector<RawPacket> packetsFromScan(const PacketEncoder& encoder, const std::vector<float>& xyz,
                                       double rpm, int packets) {
  const Calibration& cal = encoder.calibration();
  const int firings_per_rev = packets * 6;
  const double deg_per_firing = rpm / 60.0 * 360.0 * kFiringPeriodS;
  std::vector<Firing> firings(firings_per_rev);
  for (int f = 0; f < firings_per_rev; ++f) {
    const double deg = std::fmod(deg_per_firing * f, 360.0);
    firings[f].azimuth =
        static_cast<std::uint16_t>(static_cast<int>(std::lround(deg * 100.0)) % 36000);
  }
  const double max_gap_rad = 0.3 * 3.14159265358979323846 / 180.0;
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) {
    const double x = xyz[i], y = xyz[i + 1], z = xyz[i + 2];
    const double elevation = std::atan2(z, std::hypot(x, y));
    int laser = -1;
    double best = max_gap_rad;
    for (int l = 0; l < kNumLasers; ++l) {
      const double gap = std::fabs(cal.lasers[l].vert_correction_rad - elevation);
      if (gap < best) best = gap, laser = l;
    }
    std::uint16_t raw_az = 0, raw_d = 0;
    if (laser < 0 || !encoder.invert(laser, x, y, z, &raw_az, &raw_d)) continue;
    const int f = static_cast<int>(std::lround(raw_az / 100.0 / deg_per_firing)) % firings_per_rev;
    std::uint16_t& slot = firings[f].distance[laser];
    if (slot == 0 || raw_d < slot) slot = raw_d;  // keep the nearest echo
    firings[f].intensity[laser] = 100;
  }
  std::vector<RawPacket> out;
  out.reserve(packets);
  for (int p = 0; p < packets; ++p) {
    out.push_back(encoder.encode(&firings[6 * p], static_cast<std::uint32_t>(p * 288)));
  }
  return out;
}

Calibration findCalibration(const std::string& path) {
  if (!path.empty()) return loadCalibration(path);
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("UD_SHARED_DATA")) {
    candidates.push_back(std::string(env) + "/calibration/64e_s2.1-sztaki.yaml");
  }
  candidates.push_back("../shared/data/calibration/64e_s2.1-sztaki.yaml");
  for (const std::string& c : candidates) {
    if (std::ifstream(c).good()) return loadCalibration(c);
  }
  return Calibration::nominalHdl64eS2();
}

}  // namespace core
}  // namespace urban_detection
