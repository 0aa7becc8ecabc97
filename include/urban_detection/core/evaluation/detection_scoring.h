/// \file detection_scoring.h
/// The scores of one detector over the frames of an evaluation (urban_detection_eval): the
/// paper's counts (evaluation.h) under EvaluationParams::min_points and with every object
/// (N = 1), of the pipeline's output and of the detector alone (before the classifier); the
/// recall breakdowns of both; the score per group (SemanticKITTI sequence); of the matched
/// detections, the class given against the ground truth's; what the classifier rejected; and
/// the diagnostics of misses and false detections (detection_diagnostics.h). ROS-free.
#pragma once

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/detection_diagnostics.h"
#include "urban_detection/core/evaluation/evaluation.h"

namespace urban_detection {
namespace core {

class DetectorScoring {
 public:
  explicit DetectorScoring(const EvaluationParams& params);

  /// The detector's own objects of a frame (before the classifier); `match` receives the match.
  void addDetectorAlone(const EvalFrame& gt, const std::vector<DetectedObject>& objects,
                        const std::vector<float>& gt_range, FrameMatch* match);
  /// The pipeline's objects of frame `f` (`seg`: its segment class per point; `rejected`: what
  /// the classifier dropped; class pairs counted when `classified`); `match` receives the
  /// match. With `details`, one line per missed or false object is printed there.
  void add(const Frame& f, const Dataset& ds, const std::vector<SegmentClass>& seg,
           const std::vector<DetectedObject>& objects, const std::vector<DetectedObject>& rejected,
           const std::vector<float>& gt_range, bool classified, const std::string& detector,
           std::FILE* details, FrameMatch* match);

  const DetectionEvaluator& scored() const { return scored_; }
  const DetectionEvaluator& allObjects() const { return all_; }
  const DetectionEvaluator& detectorAlone() const { return alone_; }
  const DetectionEvaluator& detectorAloneAllObjects() const { return alone_all_; }
  const RecallBreakdown& breakdown() const { return breakdown_; }
  const RecallBreakdown& breakdownDetectorAlone() const { return breakdown_alone_; }
  const DetectionDiagnostics& diagnostics() const { return diagnostics_; }
  /// Rejected detections by content (detectionContent()).
  const std::map<std::string, std::size_t>& classifierRejected() const { return rejected_; }
  /// Matched detections by "truth->given" category.
  const std::map<std::string, std::size_t>& classPairs() const { return class_pairs_; }
  const std::map<std::string, DetectionScore>& byGroup() const { return by_group_; }

  /// The figures as the members of a JSON object (scores, all_objects, classifier_off,
  /// classifier_off_all_objects, breakdowns, diagnostics, by_sequence), without the braces.
  std::string jsonMembers() const;

 private:
  EvaluationParams params_;
  DetectionEvaluator scored_, all_, alone_, alone_all_;
  RecallBreakdown breakdown_, breakdown_alone_;
  DetectionDiagnostics diagnostics_;
  std::map<std::string, std::size_t> rejected_, class_pairs_;
  std::map<std::string, DetectionScore> by_group_;
};

/// The members of a detection score's JSON object (no, mo, fo, tp, ignored, detections,
/// precision, recall, f_rate), without the braces.
std::string scoreJsonMembers(const DetectionScore& s);

/// Counts by name as a JSON object.
std::string countsJson(const std::map<std::string, std::size_t>& m);

/// One evaluation run (urban_detection_eval) after its frames: what its reports are made of.
struct EvalRunSummary {
  std::string dataset;  // Dataset::name()
  std::string path;     // the dataset's folder or file
  std::size_t frames_evaluated = 0, frames_failed = 0;
  EvaluationParams params;
  bool classifier = false;       // the object classifier ran
  std::string classifier_model;  // its model file
  std::vector<std::string> configs;
  std::vector<std::string> detectors;             // names, in the order of `scoring`
  std::vector<const DetectorScoring*> scoring;    // one per detector
  std::map<std::string, std::size_t> foreground;  // foreground points by dataset class
};

/// The F-rate table (classifier on and off, under min_points and N = 1), the recall breakdowns
/// and the per-group lines, as urban_detection_eval prints them.
std::string scoreTables(const EvalRunSummary& s);

/// Per detector: what the classifier rejected and the class pairs (classifier on), the misses
/// by cause and false detections by content, with `details` the false parts of objects.
std::string diagnosticsLines(const EvalRunSummary& s, bool details);

/// The JSON report: dataset, path, frame counts, min_iou, min_points, classifier, configs,
/// detectors, `frame_rows` (the "frames" array's rows), overall, by_detector,
/// foreground_points_by_class and, when not empty, `box_quality_json`.
std::string evalReportJson(const EvalRunSummary& s, const std::string& frame_rows,
                           const std::string& box_quality_json);

}  // namespace core
}  // namespace urban_detection
