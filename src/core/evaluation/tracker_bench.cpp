#include "urban_detection/core/evaluation/tracker_bench.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {

void benchTracker(int objects, int revolutions,
                  const std::function<void(const char*, const std::function<void()>&)>& time) {
  std::mt19937 rng(28);
  std::normal_distribution<double> noise(0.0, 0.03);
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
  Tracker tracker;
  BoxFitter fitter;
  std::vector<DetectedObject> dets;
  LabeledCloud foreground;
  for (int r = 0; r < revolutions; ++r) {
    const double t_s = 0.1 * r;
    Eigen::Isometry3d odom_T_sensor = Eigen::Isometry3d::Identity();
    odom_T_sensor.translation() = Eigen::Vector3d(8.0 * t_s, 0.0, 1.73);
    const Eigen::Isometry3d sensor_T_odom = odom_T_sensor.inverse();
    dets.clear();
    foreground.clear();
    for (const Truth& t : truth) {
      if (u(rng) < 0.05) continue;
      const Eigen::Vector2d p = t.p0 + t.v * t_s;
      const Eigen::Vector3d c = sensor_T_odom * Eigen::Vector3d(p.x(), p.y(), 0.8);
      const Eigen::Vector2d ax(std::cos(t.yaw), std::sin(t.yaw)), ay(-ax.y(), ax.x());
      const Eigen::Vector2d centre = c.head<2>();
      const Eigen::Vector2d corner[4] = {centre + 0.5 * t.size.x() * ax + 0.5 * t.size.y() * ay,
                                         centre - 0.5 * t.size.x() * ax + 0.5 * t.size.y() * ay,
                                         centre - 0.5 * t.size.x() * ax - 0.5 * t.size.y() * ay,
                                         centre + 0.5 * t.size.x() * ax - 0.5 * t.size.y() * ay};
      DetectedObject o;
      for (int e = 0; e < 4; ++e) {
        const Eigen::Vector2d a = corner[e], b = corner[(e + 1) % 4];
        const Eigen::Vector2d mid = 0.5 * (a + b), normal = mid - centre;
        if (normal.dot(mid) >= 0.0) continue;  // faces away from the sensor
        const int steps = std::max(1, static_cast<int>((b - a).norm() / 0.1));
        for (int k = 0; k <= steps; ++k) {
          const Eigen::Vector2d q = a + (b - a) * (static_cast<double>(k) / steps);
          for (int row = 0; row < 3; ++row) {
            LabeledPoint pt;
            pt.x = static_cast<float>(q.x() + noise(rng));
            pt.y = static_cast<float>(q.y() + noise(rng));
            pt.z = static_cast<float>(0.3 + 0.4 * row);
            pt.data[3] = 1.0f;
            pt.intensity = 0.0f;
            pt.label = 0;
            pt.index = static_cast<std::uint32_t>(foreground.size());
            o.indices.push_back(pt.index);
            foreground.push_back(pt);
          }
        }
      }
      o.obb_center = c.cast<float>();
      o.centroid = o.obb_center;
      o.obb_size = t.size.cast<float>();
      o.obb_yaw_rad = static_cast<float>(t.yaw);
      o.category = t.size.x() > 1.0 ? ObjectCategory::kVehicle : ObjectCategory::kPedestrian;
      o.class_confidence = 0.8f;
      dets.push_back(o);
    }
    time("box_fitting_100_objects", [&] { fitter.fit(foreground, &dets); });
    time("tracker_100_objects", [&] { tracker.update(dets, odom_T_sensor, t_s); });
  }
}

}  // namespace core
}  // namespace urban_detection
