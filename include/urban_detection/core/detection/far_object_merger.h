/// \file far_object_merger.h
/// Joins far objects that are pieces of one vehicle (ours, step 6 of the hierarchical grid, after
/// its size filters). ROS-free.
///
/// Far away a vehicle seen end-on falls apart along the line of sight: the sensor sees the rear
/// (or front) face of its lower body and, ~1.1 m behind it, the face of its cabin, but the
/// horizontal surface between them (boot lid, bonnet) lies about r^2 * dtheta / h from the ring
/// below it (dtheta the ring step, h the surface's depth below the sensor): ~7 m at 30 m and
/// ~12 m at 45 m, so it gets no return at all. The sub-cell bridges of step 3 cannot span 1.1 m
/// without joining neighbours elsewhere (5 far bridge sub-cells merged parked cars in a row on
/// SemanticKITTI), so the pieces are joined as objects, where their boxes are known.
///
/// Rule: two objects are joined when
///   - both centroids are at least `min_range_m` from the sensor (horizontally);
///   - the gap between their yaw-oriented boxes is at most `max_gap_m` along the line of sight
///     (from the sensor to the midpoint of their centroids) and at most `max_across_gap_m`
///     across it (0: the boxes overlap across it; there the azimuth step, ~0.07 m at 45 m,
///     leaves no holes that the gap bridge of step 3 does not already span);
///   - when they overlap across the line of sight, the overlap is at least
///     `min_across_overlap` of the narrower box: one piece lies behind the other (a cabin
///     behind its body), not beside it (a neighbour);
///   - the gap between their z ranges is at most `max_z_gap_m` (a car's lower body and its
///     cabin need not overlap in height);
///   - and the joined object still fits a vehicle: its yaw-oriented box is at most
///     `max_length_m` x `max_width_m`.
/// Pairs are tried smallest gap first and joins are transitive (a third piece joins when the
/// group still fits). Objects nearer than `min_range_m` are never touched.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/detection/object_geometry.h"

namespace urban_detection {
namespace core {

/// Parameters of FarObjectMerger, mirrored in config/hierarchical_grid.yaml
/// (`hierarchical_grid: far_merge:`).
struct FarObjectMergerParams {
  double max_gap_m = 1.2;           // [m] 0 = off; largest gap between the boxes of two pieces
                                    //     along the line of sight
  double max_across_gap_m = 0.0;    // [m] ... and across it
  double min_across_overlap = 0.5;  // [0..1] boxes overlapping across it: by at least this
                                    //     fraction of the narrower one (a piece behind another)
  double max_z_gap_m = 0.5;         // [m] largest gap between the pieces' z ranges
  double min_range_m = 30.0;        // [m] only objects whose centroid is at least this far
  double max_length_m = 5.0;        // [m] the joined object's oriented box at most this long ...
  double max_width_m = 2.2;         // [m] ... and this wide
};

/// FarObjectMergerParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<FarObjectMergerParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"max_gap_m", "m", 0.0, 10.0,
       "largest gap between two pieces' boxes along the line of sight; 0 = off"},
      p.max_gap_m);
    f({"max_across_gap_m", "m", 0.0, 10.0, "... and across it"}, p.max_across_gap_m);
    f({"min_across_overlap", "", 0.0, 1.0,
       "boxes overlapping across it by at least this fraction of the narrower one"},
      p.min_across_overlap);
    f({"max_z_gap_m", "m", 0.0, 10.0, "largest gap between the pieces' z ranges"}, p.max_z_gap_m);
    f({"min_range_m", "m", 0.0, 1000.0, "only objects whose centroid is at least this far"},
      p.min_range_m);
    f({"max_length_m", "m", 0.01, 100.0, "the joined object's box at most this long"},
      p.max_length_m);
    f({"max_width_m", "m", 0.01, 100.0, "... and this wide (at most max_length_m)"}, p.max_width_m);
  }
};

/// Returns "" when `p` is usable, else a message naming the first bad field and
/// its range.
std::string validate(const FarObjectMergerParams& p);

/// Joins far pieces of one vehicle (see the file comment).
class FarObjectMerger {
 public:
  /// Throws std::invalid_argument when validate(params) is not empty.
  explicit FarObjectMerger(const FarObjectMergerParams& params = FarObjectMergerParams());
  const FarObjectMergerParams& params() const { return params_; }

  /// `foreground` is the detector's input (points carry `index`; the objects'
  /// indices refer to it), `objects` its output with their geometry. Joined
  /// objects keep the place of their first member, their points in the members'
  /// order, and get their geometry recomputed; ids are renumbered 1..N. Returns
  /// the number of joins made.
  std::size_t apply(const LabeledCloud& foreground, std::vector<DetectedObject>* objects);

 private:
  struct Pair {
    float gap;
    std::uint32_t a, b;
  };
  // Per far object (far_[k]): box axis, half diagonal, and its points' positions in the
  // foreground (far_positions_[begin, end)), looked up on first use.
  struct FarObject {
    enum State : std::uint8_t { kUnknown, kFound, kMissing };
    Eigen::Vector2f axis;  // (cos, sin) of obb_yaw_rad
    std::uint32_t begin, end;
    State state;
  };
  // Per far object, the fields the first pair tests read (see apply()).
  struct FarArrays {
    std::vector<float> min_z, max_z;            // [m] min_pt.z(), max_pt.z()
    std::vector<float> centroid_x, centroid_y;  // [m]
    std::vector<double> center_x, center_y;     // [m] obb_center
    std::vector<double> radius;                 // [m] half the diagonal of the oriented box
    std::vector<std::uint8_t> near;             // scratch: pair (i, j) passed them
  };
  bool fits(const LabeledCloud& foreground, const std::vector<DetectedObject>& objects,
            std::uint32_t ra, std::uint32_t rb);
  bool positionsOf(const LabeledCloud& foreground, const std::vector<DetectedObject>& objects,
                   std::size_t slot);
  std::int32_t positionOf(const LabeledCloud& foreground, std::uint32_t index,
                          std::size_t hint) const;
  std::uint32_t find(std::uint32_t a);

  FarObjectMergerParams params_;
  ObjectGeometry geometry_;
  std::vector<std::uint32_t> far_;            // objects far enough to be joined
  std::vector<FarObject> far_info_;           // per far object, see FarObject
  FarArrays far_arrays_;                      // per far object, see FarArrays
  std::vector<std::uint32_t> far_positions_;  // their points' positions
  std::vector<Pair> pairs_;                   // candidate pairs, nearest first
  std::vector<std::uint32_t> parent_;         // union-find over objects
  std::vector<std::uint8_t> grouped_;         // per object: a root with other members
  std::vector<std::uint32_t> members_;        // scratch: objects of a group
  std::vector<std::uint32_t> positions_;
  std::vector<std::uint32_t> indices_;
  std::vector<DetectedObject> out_;
  DetectedObject trial_;
};

}  // namespace core
}  // namespace urban_detection
