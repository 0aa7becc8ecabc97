// The tracker's timing case of urban_detection_bench (issue 28): a synthetic street of
// `objects` objects (parked cars on both sides, cars driving both ways, pedestrians), seen
// from a sensor driving at 8 m/s with 0.1 m of noise on every box centre and 5 % of the
// detections missed, for `revolutions` revolutions at 10 Hz. Every update is timed through
// `time(update)`. Not a tool itself (only src/tools/*.cpp are executables).
#pragma once

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace tools {

inline void benchTracker(int objects, int revolutions,
                         const std::function<void(const std::function<void()>&)>& time) {
  namespace core = urban_detection::core;
  std::mt19937 rng(28);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Truth {
    Eigen::Vector2d p0, v;
    double yaw;
    Eigen::Vector3d size;
  };
  std::vector<Truth> truth;
  for (int k = 0; k < objects; ++k) {
    Truth t;
    const int kind = k % 4;
    const double along = 5.0 * (k / 4) - 60.0;
    if (kind == 0 || kind == 1) {  // parked cars, both sides
      t.p0 = Eigen::Vector2d(along, kind == 0 ? 5.0 : -5.0);
      t.v = Eigen::Vector2d::Zero();
      t.size = Eigen::Vector3d(4.3, 1.8, 1.5);
    } else if (kind == 2) {  // traffic, both ways
      t.p0 = Eigen::Vector2d(along, (k / 4) % 2 ? 1.7 : -1.7);
      t.v = Eigen::Vector2d((k / 4) % 2 ? -10.0 : 10.0, 0.0);
      t.size = Eigen::Vector3d(4.3, 1.8, 1.5);
    } else {  // pedestrians on the sidewalks
      t.p0 = Eigen::Vector2d(along + 2.5, (k / 4) % 2 ? 8.0 : -8.0);
      t.v = Eigen::Vector2d((k / 4) % 2 ? 1.3 : -1.3, 0.0);
      t.size = Eigen::Vector3d(0.6, 0.6, 1.75);
    }
    t.yaw = t.v.squaredNorm() > 0 ? std::atan2(t.v.y(), t.v.x()) : 0.0;
    truth.push_back(t);
  }
  core::Tracker tracker;
  std::vector<core::DetectedObject> dets;
  for (int r = 0; r < revolutions; ++r) {
    const double t_s = 0.1 * r;
    Eigen::Isometry3d odom_T_sensor = Eigen::Isometry3d::Identity();
    odom_T_sensor.translation() = Eigen::Vector3d(8.0 * t_s, 0.0, 1.73);
    const Eigen::Isometry3d sensor_T_odom = odom_T_sensor.inverse();
    dets.clear();
    for (const Truth& t : truth) {
      if (u(rng) < 0.05) continue;
      const Eigen::Vector2d p = t.p0 + t.v * t_s;
      core::DetectedObject o;
      const Eigen::Vector3d in_sensor =
          sensor_T_odom * Eigen::Vector3d(p.x() + noise(rng), p.y() + noise(rng), 0.8);
      o.obb_center = in_sensor.cast<float>();
      o.centroid = o.obb_center;
      o.obb_size = t.size.cast<float>();
      o.obb_yaw_rad = static_cast<float>(t.yaw);
      o.category =
          t.size.x() > 1.0 ? core::ObjectCategory::kVehicle : core::ObjectCategory::kPedestrian;
      o.class_confidence = 0.8f;
      dets.push_back(o);
    }
    time([&] { tracker.update(dets, odom_T_sensor, t_s); });
  }
}

}  // namespace tools
}  // namespace urban_detection
