#include "urban_detection/core/evaluation/detection_scoring.h"

#include <sstream>

#include "urban_detection/core/evaluation/report.h"

namespace urban_detection {
namespace core {

namespace {

EvaluationParams everyObject(EvaluationParams p) {
  p.min_points = 1;
  return p;
}

}  // namespace

DetectorScoring::DetectorScoring(const EvaluationParams& params)
    : params_(params),
      scored_(params),
      all_(everyObject(params)),
      alone_(params),
      alone_all_(everyObject(params)) {}

void DetectorScoring::addDetectorAlone(const EvalFrame& gt,
                                       const std::vector<DetectedObject>& objects,
                                       const std::vector<float>& gt_range, FrameMatch* match) {
  alone_.evaluate(gt, objects, match);
  breakdown_alone_.addFrame(gt, *match, objects, gt_range, params_.min_points);
  alone_all_.evaluate(gt, objects, nullptr);
}

void DetectorScoring::add(const Frame& f, const Dataset& ds, const std::vector<SegmentClass>& seg,
                          const std::vector<DetectedObject>& objects,
                          const std::vector<DetectedObject>& rejected,
                          const std::vector<float>& gt_range, bool classified,
                          const std::string& detector, std::FILE* details, FrameMatch* match) {
  for (const auto& o : rejected) ++rejected_[detectionContent(f, ds, o)];
  all_.evaluate(f.gt, objects, nullptr);
  scored_.evaluate(f.gt, objects, match);
  breakdown_.addFrame(f.gt, *match, objects, gt_range, params_.min_points);
  by_group_[frameGroup(f.id, ds.name())] += match->score;
  for (std::size_t d = 0; d < objects.size() && classified; ++d) {
    if (match->verdict[d] != DetectionVerdict::kTrue) continue;
    const ObjectCategory truth = categoryOfClassName(f.gt.objects[match->matched_gt[d]].label);
    ++class_pairs_[std::string(toString(truth)) + "->" + toString(objects[d].category)];
  }
  diagnose(f, ds, seg, objects, *match, rejected, detector, &diagnostics_, details);
}

std::string DetectorScoring::jsonMembers() const {
  std::ostringstream out;
  out << scoreJsonMembers(scored_.total()) << ", \"all_objects\": {"
      << scoreJsonMembers(all_.total()) << "}"
      << ", \"classifier_off\": {" << scoreJsonMembers(alone_.total()) << "}"
      << ", \"classifier_off_all_objects\": {" << scoreJsonMembers(alone_all_.total())
      << "}, \"breakdown\": " << breakdown_.json()
      << ", \"breakdown_classifier_off\": " << breakdown_alone_.json()
      << ", \"missed_by_cause\": " << countsJson(diagnostics_.missed_by_cause)
      << ", \"false_by_content\": " << countsJson(diagnostics_.false_by_class)
      << ", \"classifier_rejected_by_content\": " << countsJson(rejected_)
      << ", \"class_truth_to_given\": " << countsJson(class_pairs_) << ", \"by_sequence\": {";
  bool first_group = true;
  for (const auto& g : by_group_) {
    out << (first_group ? "" : ", ") << "\"" << jsonStringContent(g.first) << "\": {"
        << scoreJsonMembers(g.second) << "}";
    first_group = false;
  }
  out << "}";
  return out.str();
}

std::string scoreJsonMembers(const DetectionScore& s) {
  std::ostringstream o;
  o << "\"no\": " << s.no << ", \"mo\": " << s.mo << ", \"fo\": " << s.fo << ", \"tp\": " << s.tp
    << ", \"ignored\": " << s.ignored << ", \"detections\": " << s.detections
    << ", \"precision\": " << jsonNumber(s.precision())
    << ", \"recall\": " << jsonNumber(s.recall()) << ", \"f_rate\": " << jsonNumber(s.fRate());
  return o.str();
}

std::string countsJson(const std::map<std::string, std::size_t>& m) {
  std::ostringstream o;
  o << "{";
  bool first = true;
  for (const auto& kv : m) {
    o << (first ? "" : ", ") << "\"" << jsonStringContent(kv.first) << "\": " << kv.second;
    first = false;
  }
  o << "}";
  return o.str();
}

}  // namespace core
}  // namespace urban_detection
