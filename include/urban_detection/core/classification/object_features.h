/// \file object_features.h
/// Per-object features for the object classifier (object_classifier.h), computed from the
/// detector's input (the foreground points) and a DetectedObject. ROS-free.
///
/// The detectors are class-agnostic: every connected group of short foreground points becomes
/// an object, so on a real street most of them are hedges, bushes, verges, terrain steps,
/// fences and facade pieces. The features describe what separates those from vehicles,
/// people and street furniture:
///  - size and shape: oriented box, height, bottom and top above the sensor's ground plane,
///    PCA eigenvalue ratios (linearity, planarity, scattering) and the verticality of the
///    surface normal, the vertical occupancy profile;
///  - sampling: point count, the count a target at 10 m would give (count x range^2 / 100),
///    rings (scan rows) hit, points per row, the azimuth spacing of neighbours on a row
///    against the sensor's angular resolution;
///  - porosity: along one scan row, consecutive returns on leaves lie at different depths,
///    while car bodies, people, poles and bins are smooth (the range profile is almost linear
///    in azimuth): the fraction of range "jumps" (second difference of range over three
///    azimuth-consecutive returns above `jump_m`) and the mean absolute second difference;
///  - intensity (switchable, sensor specific): mean, spread and quantiles. Vegetation,
///    walls and fences are one material; vehicles and people mix paint, glass, plates,
///    lamps, tyres, skin and cloth.
/// Scan rows are rebuilt from the points alone (runs of equal elevation, ordered by azimuth):
/// no ring field is needed, so KITTI files and decoded packets are treated alike.
#pragma once

#include <array>
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

/// Parameters of the feature extraction (fixed by the model they were trained with).
struct ObjectFeatureParams {
  double sensor_height_m = 1.73;         // [m] sensor above the road (heights refer to z = -this)
  double row_gap_deg = 0.12;             // [deg] elevation gap that starts a new scan row
  double max_azimuth_gap_deg = 0.6;      // [deg] returns farther apart in azimuth: not neighbours
  double jump_m = 0.25;                  // [m] |r_b - (r_a + r_c) / 2| above this is a range jump
  double azimuth_resolution_deg = 0.17;  // [deg] the sensor's horizontal step (HDL-64E at
                                         //       10 Hz: 0.17 deg)
};

/// ObjectFeatureParams' field table (core/common/param_fields.h). The values travel in the
/// model file (the features a model was trained on).
template <>
struct ParamFields<ObjectFeatureParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"sensor_height_m", "m", -10.0, 10.0, "sensor above the road (heights refer to z = -this)"},
      p.sensor_height_m);
    f({"row_gap_deg", "deg", 0.001, 5.0, "elevation gap that starts a new scan row"},
      p.row_gap_deg);
    f({"max_azimuth_gap_deg", "deg", 0.001, 10.0,
       "returns farther apart in azimuth are not neighbours"},
      p.max_azimuth_gap_deg);
    f({"jump_m", "m", 0.001, 10.0, "|r_b - (r_a + r_c) / 2| above this is a range jump"}, p.jump_m);
    f({"azimuth_resolution_deg", "deg", 0.001, 5.0, "the sensor's horizontal step"},
      p.azimuth_resolution_deg);
  }
};

/// Empty when valid, else a message naming the first out-of-range field and its range.
std::string validate(const ObjectFeatureParams& p);

/// out[r] = the value of rank ranks[r] (0-based, ranks ascending and < values.size()) of the
/// finite `values`, exactly the element a full sort puts there. Counts the values into 256
/// buckets spanning [min, max] first and selects only inside the buckets holding a rank, which
/// one pass gathers: near-linear for intensities, integer (HDL-64E packets) or in [0, 1]
/// (KITTI files). `scratch` is reused between calls.
void selectRanks(const std::vector<float>& values, const std::size_t* ranks, int count, float* out,
                 std::vector<float>* scratch);

/// The feature vector's entries, in order. Names (featureName) go into the training CSV and
/// the model file, so a model refuses a feature list it was not trained with.
enum ObjectFeature : int {
  kFeatPoints = 0,       // [-] points of the object
  kFeatPointsAt10m,      // [-] points x (range / 10 m)^2: the count at 10 m
  kFeatRange,            // [m] horizontal distance of the centroid
  kFeatLength,           // [m] oriented box, longer side
  kFeatWidth,            // [m] oriented box, shorter side
  kFeatHeight,           // [m] z extent
  kFeatFootprint,        // [m^2] length x width
  kFeatBottom,           // [m] lowest point above the sensor's ground plane
  kFeatTop,              // [m] highest point above the sensor's ground plane
  kFeatMeanAboveBottom,  // [m] mean z - lowest z
  kFeatStdZ,             // [m] standard deviation of z
  kFeatLinearity,        // [0..1] (l1 - l2) / l1 of the 3-D covariance eigenvalues
  kFeatPlanarity,        // [0..1] (l2 - l3) / l1
  kFeatScattering,       // [0..1] l3 / l1
  kFeatNormalZ,          // [0..1] |z| of the smallest eigenvector (1: horizontal surface)
  kFeatPrincipalZ,       // [0..1] |z| of the largest eigenvector (1: vertical, pole-like)
  kFeatXyElongation,     // [0..1] 1 - l2 / l1 of the horizontal covariance
  kFeatProfile0,         // [0..1] share of points in the lowest quarter of the height
  kFeatProfile1,         // [0..1] second quarter
  kFeatProfile2,         // [0..1] third quarter
  kFeatProfile3,         // [0..1] top quarter
  kFeatBelow05,          // [0..1] share of points less than 0.5 m above the lowest point
  kFeatAbove15,          // [0..1] share of points more than 1.5 m above the lowest point
  kFeatRows,             // [-] scan rows hit
  kFeatPointsPerRow,     // [-] points / rows
  kFeatAzimuthFill,      // [-] mean azimuth step between row neighbours / sensor resolution
  kFeatRowNeighbours,    // [0..1] share of points with a row neighbour on both sides
  kFeatJumpFraction,     // [0..1] range jumps / triplets
  kFeatMeanSecondDiff,   // [m] mean |r_b - (r_a + r_c) / 2| over the triplets
  kFeatIntensityMean,    // [input units] mean intensity
  kFeatIntensityStd,     // [input units] standard deviation
  kFeatIntensityQ10,     // [input units] 10 % quantile
  kFeatIntensityQ50,     // [input units] median
  kFeatIntensityQ90,     // [input units] 90 % quantile
  kFeatIntensityMax,     // [input units] largest intensity
  kNumObjectFeatures
};

/// First intensity feature: features from here on are sensor specific (switchable).
constexpr int kFirstIntensityFeature = kFeatIntensityMean;

using ObjectFeatureVector = std::array<float, kNumObjectFeatures>;

/// Short snake_case name of a feature ("points", "intensity_q90", ...).
const char* featureName(int feature);

/// Computes the features of objects found in one foreground cloud. Holds its scratch buffers
/// between frames (no reallocation in steady state).
class ObjectFeatureExtractor {
 public:
  /// Throws std::invalid_argument when validate(params) is not empty.
  explicit ObjectFeatureExtractor(const ObjectFeatureParams& params = ObjectFeatureParams());
  const ObjectFeatureParams& params() const { return params_; }

  /// Indexes the foreground (points carry `index`, the position in the segmented cloud that
  /// the objects' indices refer to). Call once per frame before compute().
  void indexForeground(const LabeledCloud& foreground);

  /// Features of one object of the indexed foreground. Indices not found in the foreground and
  /// non-finite points are skipped; an object without any point gives all zeros but its box.
  /// Bit for bit the features of computeReference(), in fewer passes: the moments, z and
  /// elevation ranges in the gathering pass, each point's elevation bin computed once, and a
  /// row that is neither in azimuth order nor reversed ordered by merging its ascending runs
  /// (a row is a few interleaved runs: returns of neighbouring lasers, or both ends of the
  /// seam) instead of a comparison sort; a row holding equal azimuths, whose order a sort
  /// leaves open, is ordered by the reference's std::sort.
  ObjectFeatureVector compute(const LabeledCloud& foreground, const DetectedObject& object);
  /// The plain reference of compute() (tests): one pass per quantity, the row's points
  /// ordered by std::sort.
  ObjectFeatureVector computeReference(const LabeledCloud& foreground,
                                       const DetectedObject& object);

  /// Indexes the foreground and computes the features of every object of one frame.
  /// `features` is cleared and filled, one row per object.
  void computeAll(const LabeledCloud& foreground, const std::vector<DetectedObject>& objects,
                  std::vector<ObjectFeatureVector>* features);

 private:
  struct RowPoint {
    float elevation;  // [-] tan(elevation)
    float azimuth;    // [-] tan(azimuth relative to the centroid's direction): no wrap
    float range;      // [m]
    float z;          // [m]
  };
  ObjectFeatureParams params_;
  ForegroundIndex index_;
  std::vector<RowPoint> rows_, sorted_;          // scratch: points, ordered by elevation bin
  std::vector<std::uint32_t> bin_start_, fill_;  // scratch of the counting sort
  std::vector<std::uint32_t> bin_of_;            // scratch: each point's elevation bin
  std::vector<RowPoint> row_copy_, merge_;       // scratch of the run merging
  std::vector<std::size_t> runs_, next_runs_;    // scratch: run boundaries
  std::vector<float> intensities_;               // scratch
  std::vector<float> bucket_values_;             // scratch of the quantile selection
};

}  // namespace core
}  // namespace urban_detection
