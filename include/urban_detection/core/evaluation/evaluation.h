/// \file evaluation.h
/// Detection scoring of the paper (Sec. 5): a one-to-one assignment between detected objects
/// and ground-truth (GT) objects by the Hungarian algorithm, then the counts NO (number of GT
/// objects), MO (missed objects) and FO (falsely detected objects), precision, recall and
/// F-rate (their harmonic mean), per frame and accumulated over a sequence. ROS-free.
///
/// Objects are compared as point sets: a detection is the set of input-cloud indices of its
/// points, a GT object the set of indices of the points that belong to it, and their overlap
/// is the point-set intersection over union (IoU). The dataset-specific rules (what is a GT
/// object, which points are "don't care") are encoded by the dataset readers into a
/// EvalFrame; the scoring itself is dataset independent.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

/// Role of one input point in the scoring.
enum class PointRole : std::uint8_t {
  kScored = 0,    ///< counts in IoU; a detection made mostly of such non-object points is false
  kDontCare = 1,  ///< counts in IoU; a detection made mostly of such points is ignored
                  ///< (outside the labelled field of view, DontCare regions, unlabelled
                  ///< real objects such as poles)
  kExcluded = 2,  ///< removed from both point sets before IoU (e.g. ground under a GT box)
};

/// One ground-truth object of a frame.
struct EvalObject {
  std::string label;           ///< class name ("Car", "person", ...)
  std::uint32_t id = 0;        ///< dataset id (instance id, label line number, track id)
  bool ignored = false;        ///< not counted in NO (e.g. too few points); a detection
                               ///< matched to it, or made mostly of its points, is ignored
  std::size_t num_points = 0;  ///< scored (non-excluded) points; filled by finalize()
};

/// Ground truth of one frame, per point of the evaluated cloud.
struct EvalFrame {
  std::vector<EvalObject> objects;
  /// Per input point: index into `objects`, or -1 for none. Size = number of input points.
  std::vector<std::int32_t> object_of_point;
  /// Per input point role; empty means every point is kScored.
  std::vector<PointRole> role;

  /// Resizes both per-point arrays to `num_points` (no object, kScored).
  void reset(std::size_t num_points);
  /// Recomputes EvalObject::num_points and marks objects with fewer than
  /// `min_points` scored points as ignored. Call after filling the arrays.
  void finalize(std::size_t min_points);
};

/// Scoring parameters.
struct EvaluationParams {
  double min_iou = 0.5;          ///< [0..1] a detection/GT pair is a match when IoU >= this
  double ignore_majority = 0.5;  ///< [0..1] an unmatched detection is ignored when more than
                                 ///< this fraction of its scored points is don't-care or
                                 ///< belongs to ignored GT objects
  /// Small objects count only when they match (SemanticKITTI's panoptic convention): a GT
  /// object with fewer scored points is not counted as missed, and a detection with fewer
  /// scored points is not counted as false, unless the two match each other (then it is a
  /// true positive and the object counts in NO). 1: every object counts (the paper's rule).
  std::size_t min_points = 1;
};

/// Verdict on one detection.
enum class DetectionVerdict : std::uint8_t { kTrue = 0, kFalse = 1, kIgnored = 2 };

inline const char* toString(DetectionVerdict v) {
  switch (v) {
    case DetectionVerdict::kTrue:
      return "true";
    case DetectionVerdict::kFalse:
      return "false";
    default:
      return "ignored";
  }
}

/// Counts and rates. Rates are computed from the counts: precision = TP / (TP + FO) (1 when
/// nothing was detected), recall = TP / NO (1 when there is no GT object), F-rate =
/// 2 P R / (P + R) (0 when both are 0), with TP = NO - MO.
struct DetectionScore {
  std::size_t no = 0;          ///< number of (non-ignored) GT objects
  std::size_t mo = 0;          ///< missed GT objects
  std::size_t fo = 0;          ///< false detections
  std::size_t tp = 0;          ///< matched GT objects (= no - mo)
  std::size_t ignored = 0;     ///< detections neither true nor false
  std::size_t detections = 0;  ///< all detections (tp + fo + ignored)

  double precision() const;
  double recall() const;
  double fRate() const;
  /// Adds another score's counts (micro average over frames).
  DetectionScore& operator+=(const DetectionScore& other);
};

/// Result of scoring one frame.
struct FrameMatch {
  DetectionScore score;
  /// Per detection: the verdict and the matched GT object index (-1 if none) with its IoU.
  std::vector<DetectionVerdict> verdict;
  std::vector<std::int32_t> matched_gt;
  std::vector<double> iou;
  /// Per GT object: the matched detection index or -1.
  std::vector<std::int32_t> matched_detection;
};

/// Optimal one-to-one assignment on an IoU matrix (rows: detections, cols: GT objects) by the
/// Hungarian algorithm (tracking/hungarian.h). It maximises first the number of pairs with
/// IoU >= min_iou and then the total IoU of those pairs; pairs below min_iou count for nothing
/// (maximising the total of all IoUs could trade one valid match for two sub-threshold
/// overlaps). Returns, per row, the assigned column or -1.
std::vector<std::int32_t> assignMaxIou(const std::vector<std::vector<double>>& iou, double min_iou);

/// Scores the detections of one frame against its ground truth. Detection indices outside the
/// GT arrays are ignored (counted as non-existent points).
class DetectionEvaluator {
 public:
  explicit DetectionEvaluator(const EvaluationParams& params = EvaluationParams());

  /// Scores one frame and adds its score to the running total.
  void evaluate(const EvalFrame& gt, const std::vector<DetectedObject>& detections,
                FrameMatch* match);
  const DetectionScore& total() const { return total_; }
  void resetTotal() { total_ = DetectionScore(); }
  const EvaluationParams& params() const { return params_; }

 private:
  EvaluationParams params_;
  DetectionScore total_;
  // Scratch, reused between frames.
  std::vector<std::uint32_t> gt_hits_;  // per GT: intersection with the current detection
  std::vector<std::int32_t> touched_;   // GT objects touched by the current detection
};

/// Where recall goes: per class, by size and by range, of one detector's matched GT objects,
/// and whether the kept objects carry the right class. Filled frame by frame with
/// addFrame(); the class of a GT object is categoryOfClassName() of its label.
struct RecallBreakdown {
  /// found / total of one group of GT objects.
  struct Count {
    std::size_t found = 0;
    std::size_t total = 0;
    double recall() const { return total == 0 ? 1.0 : static_cast<double>(found) / total; }
    Count& operator+=(const Count& o) {
      found += o.found;
      total += o.total;
      return *this;
    }
  };
  static constexpr int kClasses = 4;  ///< vehicle, pedestrian, cyclist, other_object
  static const char* className(int c);
  static constexpr int kPointBins = 4;  ///< < 30, 30-100, 100-300, >= 300 points
  static const char* pointBinName(int b);
  static constexpr int kRangeBins = 3;  ///< < 20, 20-40, >= 40 m
  static const char* rangeBinName(int b);

  /// Per class, the objects counted under the min_points convention (as the score's NO).
  std::array<Count, kClasses> by_class{};
  /// Every non-ignored GT object (whatever its size), by points and by range, all classes and
  /// per class.
  std::array<Count, kPointBins> by_points{};
  std::array<Count, kRangeBins> by_range{};
  std::array<std::array<Count, kPointBins>, kClasses> class_by_points{};
  std::array<std::array<Count, kRangeBins>, kClasses> class_by_range{};
  /// Matched detections by true class: how many carry that class (class_correct) of all
  /// matched (class_kept).
  std::array<std::size_t, kClasses> class_kept{};
  std::array<std::size_t, kClasses> class_correct{};

  /// Adds one scored frame. `gt_range_m[g]` is GT object g's horizontal distance from the
  /// sensor; `min_points` the convention the score used.
  void addFrame(const EvalFrame& gt, const FrameMatch& match,
                const std::vector<DetectedObject>& detections, const std::vector<float>& gt_range_m,
                std::size_t min_points);
  RecallBreakdown& operator+=(const RecallBreakdown& o);
  /// Share of the matched objects of class c given class c (1 when none).
  double classAccuracy(int c) const;
  /// Index of a GT label's class in by_class, or -1 (not one of the four).
  static int classIndex(const std::string& gt_label);
  /// Multi-line text table and a JSON object (no trailing newline).
  std::string table(const std::string& indent = "") const;
  std::string json() const;
};

/// Horizontal distance of each GT object's centroid (scored points) from the sensor origin.
std::vector<float> gtObjectRanges(const EvalFrame& gt, const CloudXYZIRT& cloud);

}  // namespace core
}  // namespace urban_detection
