/// \file box_fitting.h
/// Whole-object boxes: the box of the object, not of its visible points. ROS-free.
///
/// A LiDAR sees one or two faces of a car (an "L" or an "I" in the bird's-eye view); the
/// points' own box (ObjectGeometry) then covers only that part and its centre lies on the seen
/// faces. After classification, BoxFitter replaces each object's yaw-oriented box by:
///   1. heading: the rectangle orientation that maximises the closeness criterion of Zhang et
///      al. 2017, "Efficient L-shape fitting for vehicle detection using laser scanners"
///      (Sec. III-B, Algorithm 4): for each candidate heading theta the points are projected
///      on the rectangle's two axes, each point's distance to the nearer rectangle edge is
///      d = max(min(d_axis1, d_axis2), d0), and the score is sum(1 / d); points on two
///      perpendicular edges score highest. Search: a coarse sweep of [0, 90) deg, then a fine
///      one around the best coarse heading, on at most `max_fit_points` points (a stride
///      sample); the plain reference (every point, a fine sweep of the whole quarter turn) is
///      in the tests;
///   2. extent: the points' extent along both axes of that heading; for a class with a size
///      prior (vehicle, pedestrian, cyclist) each side shorter than the prior is lengthened to
///      the prior. Which axis is the length: the longer seen side when it is longer than the
///      prior width + `side_margin_m` (it must be a side); otherwise (only a front, a back or a
///      short piece is seen) the axis nearer the line of sight from the sensor;
///   3. centre: a lengthened side grows away from the sensor, so the faces that were seen stay
///      where they are: when the sensor lies beyond one end of that axis, that end stays; when
///      it lies between both ends (the object is beside the sensor), the side grows equally at
///      both ends.
/// Objects of other classes (other_object, unknown) get steps 1 and 2 without priors. The
/// height (z) of the box is kept.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "urban_detection/core/classification/foreground_index.h"
#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

/// Parameters of the BoxFitter. The size priors default to the mean KITTI object sizes used
/// as anchors by PointPillars / SECOND (car 3.9 x 1.6 m, pedestrian 0.8 x 0.6 m, cyclist
/// 1.76 x 0.6 m).
struct BoxFittingParams {
  bool enabled = true;                     // [-] false: objects keep the box of their points
  double coarse_step_deg = 6.0;            // [deg] step of the coarse heading sweep over [0, 90)
  double fine_step_deg = 1.0;              // [deg] step of the fine sweep (+- one coarse step)
  double closeness_min_distance_m = 0.01;  // [m] d0 of the closeness criterion
  int max_fit_points = 48;                 // [-] points scored per heading (a stride sample)
  double side_margin_m = 0.4;              // [m] a seen side longer than the prior width + this is
                                           //     the length
  double vehicle_length_m = 3.9;           // [m] size prior of vehicles
  double vehicle_width_m = 1.6;            // [m]
  double pedestrian_length_m = 0.8;        // [m] size prior of pedestrians
  double pedestrian_width_m = 0.6;         // [m]
  double cyclist_length_m = 1.76;          // [m] size prior of cyclists
  double cyclist_width_m = 0.6;            // [m]
};

/// "" when every value is in its table range and no prior width exceeds its length, else a
/// message naming the first offending field.
std::string validate(const BoxFittingParams& params);

template <>
struct ParamFields<BoxFittingParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("enabled", "false: objects keep the box of their points"), p.enabled);
    f(FieldInfo("coarse_step_deg", "deg", 0.5, 45, "step of the coarse heading sweep"),
      p.coarse_step_deg);
    f(FieldInfo("fine_step_deg", "deg", 0.05, 10, "step of the fine sweep around the best"),
      p.fine_step_deg);
    f(FieldInfo("closeness_min_distance_m", "m", 0.001, 1,
                "d0 of the closeness criterion (distances below count as this)"),
      p.closeness_min_distance_m);
    f(FieldInfo("max_fit_points", "", 4, 100000, "points scored per heading (a stride sample)"),
      p.max_fit_points);
    f(FieldInfo("side_margin_m", "m", 0, 10,
                "a seen side longer than the prior width + this is the length"),
      p.side_margin_m);
    f(FieldInfo("vehicle_length_m", "m", 0.1, 30, "size prior of vehicles: length"),
      p.vehicle_length_m);
    f(FieldInfo("vehicle_width_m", "m", 0.1, 10, "size prior of vehicles: width"),
      p.vehicle_width_m);
    f(FieldInfo("pedestrian_length_m", "m", 0.1, 5, "size prior of pedestrians: length"),
      p.pedestrian_length_m);
    f(FieldInfo("pedestrian_width_m", "m", 0.1, 5, "size prior of pedestrians: width"),
      p.pedestrian_width_m);
    f(FieldInfo("cyclist_length_m", "m", 0.1, 10, "size prior of cyclists: length"),
      p.cyclist_length_m);
    f(FieldInfo("cyclist_width_m", "m", 0.1, 5, "size prior of cyclists: width"),
      p.cyclist_width_m);
  }
};

/// A bird's-eye box: centre [m], length >= width [m] (sides), yaw of the length [rad].
struct BevBox {
  Eigen::Vector2f center = Eigen::Vector2f::Zero();
  Eigen::Vector2f size = Eigen::Vector2f::Zero();  // x = length, y = width
  float yaw_rad = 0.0f;                            // in (-pi/2, pi/2]
};

/// Closeness score of Zhang et al. 2017 of the points `xy` (n of them) for a rectangle at
/// heading `theta_rad` (see the file comment); larger is better. Exposed for the reference.
double closenessScore(const Eigen::Vector2f* xy, std::size_t n, double theta_rad, double d0_m);

class BoxFitter {
 public:
  /// Throws std::invalid_argument with validate()'s message.
  explicit BoxFitter(const BoxFittingParams& params = BoxFittingParams());

  /// Replaces obb_center (x, y), obb_size (x, y) and obb_yaw_rad of every object in `objects`
  /// by its whole-object box, from its points in `foreground` (found by their `index`; objects
  /// whose points are not there keep their box). The sensor is at the origin of the cloud's
  /// frame. Does nothing when params().enabled is false.
  void fit(const LabeledCloud& foreground, std::vector<DetectedObject>* objects);

  /// The whole-object box of one object's points `xy` (n >= 1) of class `category` seen from
  /// `sensor_xy`. `fallback_yaw_rad` is used when fewer than 3 points give no heading.
  BevBox fitPoints(const Eigen::Vector2f* xy, std::size_t n, ObjectCategory category,
                   const Eigen::Vector2f& sensor_xy = Eigen::Vector2f::Zero(),
                   float fallback_yaw_rad = 0.0f);

  /// The heading in [0, pi/2) found by the coarse-to-fine search on `xy` (stride-sampled).
  double searchHeading(const Eigen::Vector2f* xy, std::size_t n);

  const BoxFittingParams& params() const { return params_; }
  void setParams(const BoxFittingParams& params);

 private:
  BoxFittingParams params_;
  ForegroundIndex index_;
  std::vector<Eigen::Vector2f> pts_;
  std::vector<float> sx_, sy_;  // the stride sample, x and y apart
};

/// The box of points `xy` at a given heading (their extent along its two axes), completed with
/// the size prior of `category` as the file comment says. Exposed for tests.
BevBox completeBox(const Eigen::Vector2f* xy, std::size_t n, double theta_rad,
                   ObjectCategory category, const Eigen::Vector2f& sensor_xy,
                   const BoxFittingParams& params);

/// Bird's-eye intersection over union of two yaw-oriented rectangles (centre [m], length and
/// width [m], yaw [rad]); 0 when either has no area.
double bevIoU(const Eigen::Vector2d& c1, double l1, double w1, double yaw1,
              const Eigen::Vector2d& c2, double l2, double w2, double yaw2);

}  // namespace core
}  // namespace urban_detection
