// Synthetic LiDAR scans of simple shapes for the classifier tests: rays of a 64-beam-like sensor
// (rows of constant elevation, fixed azimuth step) from the
// origin cast against a box (car), a vertical cylinder (pedestrian, pole) and a porous sphere
// (bush: returns at random depths along the chord).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include <Eigen/Core>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace test {

constexpr double kDeg = M_PI / 180.0;

// A ray from the sensor origin; returns the range of its return or a negative value.
using Shape = std::function<double(const Eigen::Vector3d& dir)>;

// Ray / axis-aligned box (slab method): the entry distance.
inline Shape box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return [lo, hi](const Eigen::Vector3d& d) {
    double t0 = 0.0, t1 = 1e9;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-12) {
        if (0.0 < lo[a] || 0.0 > hi[a]) return -1.0;
        continue;
      }
      double ta = lo[a] / d[a], tb = hi[a] / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return t0 <= t1 && t0 > 0.0 ? t0 : -1.0;
  };
}

// Vertical cylinder (centre cx, cy, radius r, z in [z0, z1]): the entry distance.
inline Shape cylinder(double cx, double cy, double r, double z0, double z1) {
  return [=](const Eigen::Vector3d& d) {
    const double a = d.x() * d.x() + d.y() * d.y();
    const double b = -2.0 * (d.x() * cx + d.y() * cy);
    const double c = cx * cx + cy * cy - r * r;
    const double disc = b * b - 4 * a * c;
    if (a < 1e-12 || disc < 0) return -1.0;
    const double t = (-b - std::sqrt(disc)) / (2 * a);
    const double z = t * d.z();
    return t > 0 && z >= z0 && z <= z1 ? t : -1.0;
  };
}

// A porous sphere: the return comes from a random depth along the chord (leaves at all
// depths), or from the entry point with probability `solid`.
inline Shape bush(const Eigen::Vector3d& c, double r, std::mt19937* rng, double solid = 0.2) {
  return [=](const Eigen::Vector3d& d) {
    const double b = d.dot(c);
    const double disc = b * b - (c.squaredNorm() - r * r);
    if (disc < 0) return -1.0;
    const double t0 = b - std::sqrt(disc), chord = 2.0 * std::sqrt(disc);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    if (u(*rng) < solid) return t0;
    return t0 + u(*rng) * chord;
  };
}

// Scans `shape` with rows every `row_deg` between the elevations and azimuths given (sensor
// at the origin) and appends the returns to `fg` as one object. `index` values are spread
// (3 k + 7) so the filter must look them up, not assume positions.
inline core::DetectedObject scan(const Shape& shape, double az0_deg, double az1_deg, double el0_deg,
                                 double el1_deg, LabeledCloud* fg, double az_step_deg = 0.09,
                                 double row_deg = 0.4, float intensity = 20.0f) {
  core::DetectedObject o;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (double el = el0_deg; el <= el1_deg; el += row_deg) {
    for (double az = az0_deg; az <= az1_deg; az += az_step_deg) {
      const Eigen::Vector3d d(std::cos(el * kDeg) * std::cos(az * kDeg),
                              std::cos(el * kDeg) * std::sin(az * kDeg), std::sin(el * kDeg));
      const double t = shape(d);
      if (t <= 0) continue;
      const Eigen::Vector3d p = t * d;
      o.indices.push_back(static_cast<std::uint32_t>(3 * fg->size() + 7));
      fg->push_back(makeLabeledPoint(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                     static_cast<float>(p.z()), 4, o.indices.back(), intensity));
      sum += p;
      if (o.indices.size() == 1) o.min_pt = o.max_pt = p.cast<float>();
      o.min_pt = o.min_pt.cwiseMin(p.cast<float>());
      o.max_pt = o.max_pt.cwiseMax(p.cast<float>());
    }
  }
  if (!o.indices.empty()) o.centroid = (sum / o.indices.size()).cast<float>();
  return o;
}

}  // namespace test
}  // namespace urban_detection
