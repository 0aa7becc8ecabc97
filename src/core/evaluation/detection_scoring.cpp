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
    out << (first_group ? "" : ", ") << "\"" << jsonEscape(g.first) << "\": {"
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
    o << (first ? "" : ", ") << "\"" << jsonEscape(kv.first) << "\": " << kv.second;
    first = false;
  }
  o << "}";
  return o.str();
}

std::string scoreTables(const EvalRunSummary& s) {
  std::string out;
  const bool classifier = s.classifier;
  const std::size_t n = s.params.min_points;
  appendf(&out,
          "\nsmall objects (< %zu points) count only when matched (--min-points %zu); N = 1: "
          "every object counts\n",
          n, n);
  appendf(&out, "%-15s %-18s %-11s %6s %5s %5s %5s %5s %9s %7s %7s\n", "dataset", "detector",
          "classifier", "frames", "NO", "MO", "FO", "ign", "precision", "recall", "F-rate");
  for (std::size_t k = 0; k < s.scoring.size(); ++k) {
    const std::pair<const char*, const DetectionEvaluator*> rows[] = {
        {classifier ? "on" : "off", &s.scoring[k]->scored()},
        {classifier ? "on, N=1" : "off, N=1", &s.scoring[k]->allObjects()},
        {"off", &s.scoring[k]->detectorAlone()},
        {"off, N=1", &s.scoring[k]->detectorAloneAllObjects()}};
    for (int r = 0; r < (classifier ? 4 : 2); ++r) {
      const DetectionScore& t = rows[r].second->total();
      appendf(&out, "%-15s %-18s %-11s %6zu %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
              s.dataset.c_str(), s.detectors[k].c_str(), rows[r].first, s.frames_evaluated, t.no,
              t.mo, t.fo, t.ignored, t.precision(), t.recall(), t.fRate());
    }
  }
  for (std::size_t k = 0; k < s.scoring.size(); ++k) {
    appendf(&out, "\n%s, classifier %s:\n%s", s.detectors[k].c_str(), classifier ? "on" : "off",
            s.scoring[k]->breakdown().table("  ").c_str());
    if (classifier) {
      appendf(&out, "%s, classifier off (the detector alone):\n%s", s.detectors[k].c_str(),
              s.scoring[k]->breakdownDetectorAlone().table("  ").c_str());
    }
  }
  out += "\n";
  for (std::size_t k = 0; k < s.scoring.size() && s.scoring[k]->byGroup().size() > 1; ++k) {
    for (const auto& g : s.scoring[k]->byGroup()) {
      const DetectionScore& t = g.second;
      appendf(&out, "%-15s %-18s %6s %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
              (s.dataset + ":" + g.first).c_str(), s.detectors[k].c_str(), "", t.no, t.mo, t.fo,
              t.ignored, t.precision(), t.recall(), t.fRate());
    }
  }
  return out;
}

std::string diagnosticsLines(const EvalRunSummary& s, bool details) {
  std::string out;
  for (std::size_t k = 0; k < s.scoring.size(); ++k) {
    const DetectorScoring& d = *s.scoring[k];
    const char* name = s.detectors[k].c_str();
    if (s.classifier) {
      appendf(&out,
              "%s: classifier rejected by content %s; matched objects' class "
              "(truth->given) %s\n",
              name, countsJson(d.classifierRejected()).c_str(), countsJson(d.classPairs()).c_str());
    }
    appendf(&out, "%s: missed by cause %s; false by content %s\n", name,
            countsJson(d.diagnostics().missed_by_cause).c_str(),
            countsJson(d.diagnostics().false_by_class).c_str());
    if (details) {
      appendf(&out, "%s: false parts of GT objects by kind %s\n", name,
              countsJson(d.diagnostics().false_fragments).c_str());
    }
  }
  return out;
}

std::string evalReportJson(const EvalRunSummary& s, const std::string& frame_rows,
                           const std::string& box_quality_json) {
  std::ostringstream out;
  out << "{\n  \"dataset\": \"" << s.dataset << "\",\n  \"path\": \"" << jsonEscape(s.path)
      << "\",\n  \"frames_evaluated\": " << s.frames_evaluated
      << ",\n  \"frames_failed\": " << s.frames_failed
      << ",\n  \"min_iou\": " << jsonNumber(s.params.min_iou)
      << ",\n  \"min_points\": " << s.params.min_points << ",\n  \"classifier\": "
      << (s.classifier ? "\"" + jsonEscape(s.classifier_model) + "\"" : "null")
      << ",\n  \"configs\": [";
  for (std::size_t c = 0; c < s.configs.size(); ++c) {
    out << (c ? ", " : "") << "\"" << jsonEscape(s.configs[c]) << "\"";
  }
  out << "],\n  \"detectors\": [";
  for (std::size_t k = 0; k < s.detectors.size(); ++k) {
    out << (k ? ", " : "") << "\"" << s.detectors[k] << "\"";
  }
  out << "],\n  \"frames\": [\n" << frame_rows << "\n  ],\n";
  out << "  \"overall\": {" << scoreJsonMembers(s.scoring[0]->scored().total()) << "},\n";
  out << "  \"by_detector\": {";
  for (std::size_t k = 0; k < s.scoring.size(); ++k) {
    out << (k ? ",\n" : "\n") << "    \"" << s.detectors[k] << "\": {"
        << s.scoring[k]->jsonMembers() << "}";
  }
  out << "\n  },\n  \"foreground_points_by_class\": " << countsJson(s.foreground);
  if (!box_quality_json.empty()) out << ",\n  \"box_quality\": " << box_quality_json;
  out << "\n}\n";
  return out.str();
}

}  // namespace core
}  // namespace urban_detection
