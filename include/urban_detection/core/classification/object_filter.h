/// \file object_filter.h
/// Object-level rejection of vegetation fragments (hedges, bushes, tree crowns that reach into
/// the short-object foreground), run after either ObjectDetector. ROS-free.
///
/// The detectors are class-agnostic: any connected group of short foreground points becomes an
/// object. Vegetation is porous: along one laser's scan line, consecutive returns inside a bush
/// hit leaves at different depths, so the range profile is rough, while car bodies, people,
/// poles and bins are smooth surfaces whose range varies almost linearly with azimuth (even at
/// grazing incidence). The filter rebuilds the scan lines of an object from its points alone
/// (rows of equal elevation angle, sorted by azimuth; no ring field needed, so it works on
/// KITTI files and on decoded packets alike) and measures the fraction of range "jumps": the
/// second difference of range over three azimuth-consecutive returns exceeds `jump_m`. An
/// object with enough measurable triplets whose jump fraction exceeds `max_jump_fraction` is
/// rejected as vegetation. Objects too small or too far to judge are kept.
///
/// Optional second rule (off by default): trimmed hedges are smooth, but bright at 905 nm
/// (leaves reflect strongly in the near infrared); an object whose mean intensity exceeds
/// `hedge_min_intensity` and whose box is at least `hedge_min_length_m` long (longer than a
/// person) is rejected. The threshold is in the sensor's intensity units (KITTI reflectance
/// x 255 in this package's readers), so it is set per sensor, never by default.
///
/// Optional third rule (off by default, also per sensor): vegetation, walls and fences are one
/// material, so the intensities of their returns spread little, while vehicles and people mix
/// paint, glass, tyres, lamps, plates, skin and cloth. An object with at least
/// `uniform_min_points` points whose intensity standard deviation is below
/// `uniform_max_intensity_std` is rejected, at any range and whatever the porosity gates above.
/// On KITTI's HDL-64E (reflectance x 255) cars spread 33-70 and SemanticKITTI's vegetation
/// 13-33 (docs/measurements.md); a simulator that gives each object one reflectivity cannot use it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/classification/foreground_index.h"
#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

struct ObjectFilterParams {
  bool enabled = false;       // [-] false: apply() keeps every object. Off by default: on the
                              //     shared data it removed ~1 false object per revolution for
                              //     ~1.3 ms (docs/measurements.md)
  int min_points = 30;        // [-] objects with fewer points are always kept
  double max_range_m = 30.0;  // [m] objects whose centroid is farther are always kept
  // Porosity rule (geometry, any sensor):
  double row_gap_deg = 0.12;         // [deg] elevation gap that starts a new scan row
  double max_azimuth_gap_deg = 0.6;  // [deg] returns farther apart in azimuth: not neighbours
  double jump_m = 0.25;              // [m] |r_b - (r_a + r_c) / 2| above this is a range jump
  int min_triplets = 20;             // [-] fewer measurable triplets: porosity not judged
  double max_jump_fraction = 0.3;    // [0..1] reject when the fraction of jumps exceeds this
  // Bright-hedge rule (intensity, depends on the sensor's intensity scale; 0 = off):
  double hedge_min_intensity = 0.0;  // [input intensity units] reject when the mean is above
  double hedge_min_length_m = 1.5;   // [m] ... and the longer box side is at least this
  // Uniform-material rule (intensity spread, per sensor; 0 = off):
  double uniform_max_intensity_std = 0.0;  // [input intensity units] reject below this spread
  int uniform_min_points = 10;             // [-] ... when the object has at least this many
};

/// ObjectFilterParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<ObjectFilterParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"enabled", "false: every object is kept"}, p.enabled);
    f({"min_points", "points", 3, 1000000, "objects with fewer points are always kept"},
      p.min_points);
    f({"max_range_m", "m", 0.001, 1000.0, "objects whose centroid is farther are always kept"},
      p.max_range_m);
    f({"row_gap_deg", "deg", 0.001, 5.0, "elevation gap that starts a new scan row"},
      p.row_gap_deg);
    f({"max_azimuth_gap_deg", "deg", 0.001, 10.0, "returns farther apart are not neighbours"},
      p.max_azimuth_gap_deg);
    f({"jump_m", "m", 0.001, 10.0, "a range jump within a row triplet is larger than this"},
      p.jump_m);
    f({"min_triplets", "", 1, 1000000, "fewer measurable triplets: porosity not judged"},
      p.min_triplets);
    f({"max_jump_fraction", "", 0.0, 1.0, "reject when the fraction of jumps exceeds this"},
      p.max_jump_fraction);
    f({"hedge_min_intensity", "", 0.0, 1e6,
       "reject when the mean intensity is above this (input units); 0 = off"},
      p.hedge_min_intensity);
    f({"hedge_min_length_m", "m", 0.0, 100.0, "... and the longer box side is at least this"},
      p.hedge_min_length_m);
    f({"uniform_max_intensity_std", "", 0.0, 1e6,
       "reject when the intensity spread is below this (input units); 0 = off"},
      p.uniform_max_intensity_std);
    f({"uniform_min_points", "points", 2, 1000000, "... when the object has this many points"},
      p.uniform_min_points);
  }
};

/// Empty when valid, else a message naming the first out-of-range field and its range.
std::string validate(const ObjectFilterParams& p);

/// Per-object features (also used by urban_detection_eval --features to measure separation).
struct ObjectFeatures {
  std::size_t points = 0;       // [-] object points found in the foreground
  std::size_t triplets = 0;     // [-] azimuth-consecutive return triplets on one row
  std::size_t jumps = 0;        // [-] triplets whose range second difference > jump_m
  double jump_fraction = 0.0;   // [0..1] jumps / triplets (0 when no triplet)
  double height_m = 0.0;        // [m] z extent
  double range_m = 0.0;         // [m] horizontal distance of the object's centroid
  double length_m = 0.0;        // [m] longer side of the object's box (oriented or not)
  double mean_intensity = 0.0;  // [0..255 or 0..1, as the input]
  double std_intensity = 0.0;   // [same]
};

/// Why an object was rejected.
enum class RejectReason : std::uint8_t { kNone = 0, kPorous = 1, kBrightHedge = 2, kUniform = 3 };

struct ObjectFilterStats {
  std::size_t input = 0;         // objects given to apply()
  std::size_t kept = 0;          // objects left in the output
  std::size_t vegetation = 0;    // rejected: porous + bright_hedge
  std::size_t porous = 0;        // rejected by the porosity rule
  std::size_t bright_hedge = 0;  // rejected by the bright-hedge rule
  std::size_t uniform = 0;       // rejected by the uniform-material rule
  std::size_t not_judged = 0;    // kept because too small or too far
};

class ObjectFilter {
 public:
  /// Throws std::invalid_argument when validate(params) is not empty (also setParams()).
  explicit ObjectFilter(const ObjectFilterParams& params = ObjectFilterParams());
  const ObjectFilterParams& params() const { return params_; }
  void setParams(const ObjectFilterParams& params);  // validates; throws std::invalid_argument

  /// Removes the rejected objects from `objects` (order kept, ids renumbered 1..N as the
  /// detectors number them). `foreground` is the detector's input (points carry `index`, the
  /// object indices refer to it). When `rejected` is not null it receives the removed objects
  /// (their original ids). Returns the counts of this call.
  ObjectFilterStats apply(const LabeledCloud& foreground, std::vector<DetectedObject>* objects,
                          std::vector<DetectedObject>* rejected = nullptr);

  /// Features of one object (its points are looked up in `foreground` by `index`). Call
  /// indexForeground() first for the same foreground.
  ObjectFeatures features(const LabeledCloud& foreground, const DetectedObject& object);
  void indexForeground(const LabeledCloud& foreground);

  /// The verdict for given features (kNone: kept).
  RejectReason classify(const ObjectFeatures& f) const;

 private:
  struct RowPoint {
    float elevation, azimuth, range;
  };
  ObjectFilterParams params_;
  ForegroundIndex index_;
  std::vector<RowPoint> row_points_;  // scratch
  std::vector<DetectedObject> kept_;  // scratch
};

}  // namespace core
}  // namespace urban_detection
