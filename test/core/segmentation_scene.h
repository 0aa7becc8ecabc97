// Synthetic LiDAR scenes for the segmentation tests: a ray caster with a Velodyne-like beam
// pattern over a flat ground plane and axis-aligned boxes (walls, cars), plus direct surface
// sampling for terrain shapes (slopes, camber, curbs).
#pragma once

#include "urban_detection/core/common/point_types.h"

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

namespace urban_detection {
namespace test {

/// Axis-aligned box in world coordinates (z = 0 is the ground below the sensor). `tag`
/// identifies the object in the ray-cast ground truth.
struct Box {
  float x0, y0, z0, x1, y1, z1;
  int tag;
};

/// Ray-casts a scan: `beams` lasers evenly spread from bottom_deg to top_deg, `azimuths`
/// firings per revolution. Sensor at (0, 0, sensor_h) looking horizontally; points are returned
/// in the sensor frame. `tags` receives, per point, the hit box tag or 0 for the ground.
inline CloudXYZIRT rayCast(float sensor_h, const std::vector<Box>& boxes, std::vector<int>* tags,
                           int beams = 64, int azimuths = 1500, float top_deg = 2.0f,
                           float bottom_deg = -24.8f, float max_range = 60.0f) {
  CloudXYZIRT cloud;
  tags->clear();
  const float kDeg = static_cast<float>(M_PI / 180.0);
  for (int b = 0; b < beams; ++b) {
    const float el = (bottom_deg + (top_deg - bottom_deg) * b / (beams - 1)) * kDeg;
    for (int a = 0; a < azimuths; ++a) {
      const float az = 2.0f * static_cast<float>(M_PI) * a / azimuths;
      const float dx = std::cos(el) * std::cos(az), dy = std::cos(el) * std::sin(az),
                  dz = std::sin(el);
      float best = max_range;
      int tag = -1;
      if (dz < 0.0f) {  // ground plane z = 0
        const float t = -sensor_h / dz;
        if (t < best) best = t, tag = 0;
      }
      for (const Box& bx : boxes) {  // slab test
        float t0 = 0.0f, t1 = best;
        const float o[3] = {0.0f, 0.0f, sensor_h}, d[3] = {dx, dy, dz};
        const float lo[3] = {bx.x0, bx.y0, bx.z0}, hi[3] = {bx.x1, bx.y1, bx.z1};
        bool hit = true;
        for (int k = 0; k < 3 && hit; ++k) {
          if (std::fabs(d[k]) < 1e-9f) {
            hit = o[k] >= lo[k] && o[k] <= hi[k];
            continue;
          }
          float ta = (lo[k] - o[k]) / d[k], tb = (hi[k] - o[k]) / d[k];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
          hit = t0 <= t1;
        }
        if (hit && t0 > 0.0f && t0 < best) best = t0, tag = bx.tag;
      }
      if (tag < 0) continue;
      cloud.push_back(makePoint(dx * best, dy * best, dz * best, 10.0f,  // sensor frame
                                static_cast<std::uint16_t>(b)));
      tags->push_back(tag);
    }
  }
  return cloud;
}

/// Samples the surface z = height(x, y) (world, ground below the sensor = 0) on a regular
/// lattice over [x0, x1] x [y0, y1]; points are appended in the sensor frame.
inline void sampleSurface(CloudXYZIRT* cloud, float sensor_h, float x0, float x1, float y0,
                          float y1, float step, const std::function<float(float, float)>& height) {
  for (float x = x0; x <= x1; x += step) {
    for (float y = y0; y <= y1; y += step) {
      cloud->push_back(makePoint(x, y, height(x, y) - sensor_h));
    }
  }
}

}  // namespace test
}  // namespace urban_detection
