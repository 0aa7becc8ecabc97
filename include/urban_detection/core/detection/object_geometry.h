/// \file object_geometry.h
/// Geometry of a detected object (centroid, axis-aligned box, yaw-oriented box), computed by one
/// piece of code for every detector so the hierarchical grid and the kd-tree baseline report
/// boxes that differ only because their point groups differ. ROS-free.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

/// Pass 1 of the object geometry: sums and axis-aligned extremes of an object's points, in the
/// order they are added (the sums are in double; the order fixes their last bits). A detector
/// that visits each point anyway (the hierarchical grid's output scatter) accumulates them
/// there and hands them to ObjectGeometry::finish(), so the points are read once.
struct ObjectMoments {
  double sx = 0.0, sy = 0.0, sz = 0.0;  // [m] sums of x, y, z
  float min_x = std::numeric_limits<float>::max(), min_y = min_x, min_z = min_x;  // [m]
  float max_x = -min_x, max_y = -min_x, max_z = -min_x;                           // [m]
  std::size_t n = 0;

  void add(float x, float y, float z) {
    sx += x;
    sy += y;
    sz += z;
    min_x = std::min(min_x, x);
    min_y = std::min(min_y, y);
    min_z = std::min(min_z, z);
    max_x = std::max(max_x, x);
    max_y = std::max(max_y, y);
    max_z = std::max(max_z, z);
    ++n;
  }
};

/// Computes the box fields of DetectedObjects. Holds scratch buffers so that, in steady state,
/// computing the geometry of a frame's objects allocates nothing.
///
/// Yaw-oriented box: the minimum-area rectangle enclosing the 2-D convex hull of the object's
/// points projected on the xy plane (hull computed to within kHullTolerance = 5 cm, from the
/// extreme points of narrow columns, in linear time; a column count cap of 512 loosens this
/// only for objects longer than 25 m) (a minimum-area enclosing rectangle has one side collinear
/// with a hull edge, so every hull edge direction is tried). Its z range is the points' z range.
/// The length (obb_size.x) is the longer side and obb_yaw_rad in (-pi/2, pi/2] is its direction;
/// a single point or collinear points give a degenerate box of zero width.
class ObjectGeometry {
 public:
  /// Fills centroid, min_pt, max_pt, obb_center, obb_size and obb_yaw_rad of `object` from the
  /// points `cloud_positions` of `cloud` (positions into `cloud`, not the `index` field). The
  /// caller guarantees the positions are valid and the points finite. An empty position list
  /// sets every field to zero.
  void compute(const LabeledCloud& cloud, const std::vector<std::uint32_t>& cloud_positions,
               DetectedObject* object);
  /// Same, positions given as an array of `n`; when `indices_out` is not null it receives the
  /// `index` field of each point (n entries), read in the same pass.
  void compute(const LabeledCloud& cloud, const std::uint32_t* cloud_positions, std::size_t n,
               DetectedObject* object, std::uint32_t* indices_out = nullptr);
  /// The part of compute() after pass 1, for a caller that accumulated `moments` and gathered
  /// the xy of the object's points itself (`xy`, moments.n entries, in the order they were
  /// added). compute() is this after its own pass 1, so both give identical fields.
  void finish(const ObjectMoments& moments, const Eigen::Vector2f* xy, DetectedObject* object);

  /// [m] the hull (and so the oriented box) is exact to within this distance, see compute().
  static constexpr float kHullTolerance = 0.05f;

 private:
  static constexpr int kMaxColumns = 512;
  std::vector<Eigen::Vector2f> pts_;   // xy of the object's points
  std::vector<std::uint64_t> keys_;    // per column: keys of its lowest and highest point
  std::vector<Eigen::Vector2f> cand_;  // hull candidates: lower chain, then upper chain
  std::vector<Eigen::Vector2f> hull_;  // convex hull, counter-clockwise
  std::vector<float> axes_;            // its edges' directions and lengths, see calipers()
};

/// Convex hull of 2-D points (Andrew's monotone chain), counter-clockwise, no collinear points;
/// `points` is reordered. Exposed for tests.
void convexHull2d(std::vector<Eigen::Vector2f>* points, std::vector<Eigen::Vector2f>* hull);

/// Minimum-area enclosing rectangle of a convex polygon given counter-clockwise. Returns centre
/// [m], size (x = longer side, y = shorter side) [m] and yaw of the longer side in (-pi/2, pi/2]
/// [rad]. Exposed for tests.
void minAreaRectangle(const std::vector<Eigen::Vector2f>& hull, Eigen::Vector2f* center,
                      Eigen::Vector2f* size, float* yaw_rad);

}  // namespace core
}  // namespace urban_detection
