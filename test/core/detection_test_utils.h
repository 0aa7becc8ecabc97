// Helpers shared by the detection tests: synthetic foreground clouds with known objects.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace test {

/// A point set as (sets of `index` values): one set per object, order-free.
using Partition = std::set<std::set<std::uint32_t>>;

inline Partition partitionOf(const std::vector<core::DetectedObject>& objects) {
  Partition p;
  for (const core::DetectedObject& o : objects) p.insert({o.indices.begin(), o.indices.end()});
  return p;
}

/// Appends a point; its `index` is its position and `label` is the ground-truth object (0 =
/// none), so tests can rebuild the expected partition independently of the detector.
inline void addPoint(LabeledCloud* cloud, float x, float y, float z, std::uint32_t truth) {
  cloud->push_back(makeLabeledPoint(x, y, z, truth, static_cast<std::uint32_t>(cloud->size())));
}

/// Expected partition from the ground-truth labels (label 0 excluded).
inline Partition truthPartition(const LabeledCloud& cloud) {
  std::map<std::uint32_t, std::set<std::uint32_t>> groups;
  for (const LabeledPoint& p : cloud.points) {
    if (p.label != 0) groups[p.label].insert(p.index);
  }
  Partition out;
  for (auto& g : groups) out.insert(g.second);
  return out;
}

/// Builds a cloud from ASCII art of 0.20 m sub-cells (3 x 3 per 0.60 m super-cell). Row r is
/// y = y0 + 0.2 r .. y0 + 0.2 (r + 1), column c likewise in x from x0. A capital letter is a
/// sub-cell with `dense_points` points of object (letter), a lower-case letter one with a
/// single point of that object, '.' an empty sub-cell. The points of object L reach the height
/// heights[L] [m] (Zmax of every super-cell it touches).
inline LabeledCloud fromAsciiArt(const std::vector<std::string>& rows,
                                 const std::map<char, float>& heights, float x0 = 3.0f,
                                 float y0 = 0.0f, int dense_points = 12) {
  LabeledCloud cloud;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < rows[r].size(); ++c) {
      const char ch = rows[r][c];
      if (ch == '.' || ch == ' ') continue;
      const char obj = static_cast<char>(std::toupper(ch));
      const int n = std::isupper(ch) ? dense_points : 1;
      const float h = heights.at(obj);
      for (int k = 0; k < n; ++k) {
        // Spread inside the sub-cell, 2 cm away from its borders; the first point of every
        // sub-cell is at the object's full height so each super-cell's Zmax is that height.
        const float fx = 0.02f + 0.16f * ((k * 7) % n) / std::max(1, n - 1);
        const float fy = 0.02f + 0.16f * ((k * 3) % n) / std::max(1, n - 1);
        const float z = h - 0.9f * h * static_cast<float>(k) / std::max(1, n);
        addPoint(&cloud, x0 + 0.2f * c + fx, y0 + 0.2f * r + fy, z,
                 static_cast<std::uint32_t>(obj));
      }
    }
  }
  return cloud;
}

/// Samples the sensor-facing surfaces of a box-shaped car (length x width x height [m], centre
/// (cx, cy) on the road at z = -1.73, yaw [rad]) like a spinning LiDAR at the origin: rays
/// every `dazim_rad` in azimuth and `delev_rad` in elevation, first hit of each ray on the box
/// (slab test). Every point is labelled `truth`.
inline void addLidarCar(LabeledCloud* cloud, float cx, float cy, float yaw, std::uint32_t truth,
                        float length = 4.5f, float width = 1.8f, float height = 1.5f,
                        float dazim_rad = 0.003f, float delev_rad = 0.007f) {
  const float ground = -1.73f;
  const float c = std::cos(yaw), s = std::sin(yaw);
  const float dist = std::hypot(cx, cy);
  const float az0 = std::atan2(cy, cx);
  const float span = std::atan2(std::hypot(length, width), dist);
  for (float az = az0 - span; az <= az0 + span; az += dazim_rad) {
    for (float el = -0.43f; el <= 0.035f; el += delev_rad) {
      const float dx = std::cos(el) * std::cos(az), dy = std::cos(el) * std::sin(az),
                  dz = std::sin(el);
      // Ray in the car frame.
      const float ox = -(c * cx + s * cy), oy = -(-s * cx + c * cy), oz = -ground;
      const float rx = c * dx + s * dy, ry = -s * dx + c * dy, rz = dz;
      float t0 = 0.0f, t1 = 1e9f;
      const float o[3] = {ox, oy, oz}, d[3] = {rx, ry, rz};
      const float lo[3] = {-length / 2, -width / 2, 0.15f}, hi[3] = {length / 2, width / 2, height};
      bool hit = true;
      for (int k = 0; k < 3 && hit; ++k) {
        if (std::fabs(d[k]) < 1e-9f) {
          hit = o[k] >= lo[k] && o[k] <= hi[k];
          continue;
        }
        float a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
        hit = t0 <= t1;
      }
      if (hit && t0 > 0.0f) addPoint(cloud, t0 * dx, t0 * dy, t0 * dz, truth);
    }
  }
}

}  // namespace test
}  // namespace urban_detection
