// urban_detection_train_classifier: trains the object classifier (object_classifier.h) on
// labelled real scans and reports it leave-one-sequence-out. No ROS master needed.
//
//   urban_detection_train_classifier --semantic-kitti DIR [--config FILE]... [--out MODEL]
//       [--csv FILE] [--json FILE] [--no-intensity] [--trees N] [--max-depth N]
//       [--min-samples N] [--fragments reject|skip] [--threshold auto|P] [--no-loso]
//       [--no-kdtree]
//
// 1. Runs the pipeline (segmentation, hierarchical grid and kd-tree detectors, shipped
//    configs) over every scan and computes the features of every detection.
// 2. Labels each detection by the evaluation's rules (eval_datasets.h): a detection matched
//    to a ground-truth object takes its class (vehicle, pedestrian, cyclist); one made mostly of
//    SemanticKITTI's other-object points is an other street object; one made mostly of
//    background (vegetation, terrain, building, fence, structure) is a non-object; a false
//    detection made mostly of a real object's points (a fragment or a merge) is left out
//    (`--fragments skip`, the default: it looks like the object it is part of) or a
//    non-object (`reject`: it costs a false object); detections of don't-care points (poles,
//    trunks, signs) are left out.
// 3. Leave-one-sequence-out: for each sequence, a forest trained on the other sequences (the
//    threshold on P(object) chosen on those sequences by an inner 3-fold cross-validation over
//    sequences) classifies the held-out sequence's detections of both detectors; the kept ones
//    are scored with the paper's protocol. Printed per sequence and pooled, with the classifier
//    off and on, and the pooled confusion matrix of the held-out predictions.
// 4. The shipped model: trained on all sequences, its threshold the one that maximises the
//    pooled leave-one-sequence-out F of step 3 (chosen on held-out predictions only).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

#include "datasets.h"
#include "tool_common.h"

namespace core = urban_detection::core;
using urban_detection::tools::jsonEscape;
using urban_detection::tools::jsonNumber;

namespace {

using Probabilities = std::array<float, core::kNumObjectCategories>;

// One detector's output on one frame, with the features and labels of its detections.
struct DetectorFrame {
  std::vector<core::DetectedObject> objects;
  std::vector<core::ObjectFeatureVector> features;
  std::vector<core::ObjectCategory> labels;  // training label (kUnknown: not trained on)
  std::vector<Probabilities> held_out;       // leave-one-sequence-out probabilities
};

struct FrameData {
  std::string id, group;
  core::EvalFrame gt;
  std::vector<DetectorFrame> detectors;
};

enum class FragmentRule { kReject, kSkip };

core::ObjectCategory trainingLabel(const core::FrameMatch& m, std::size_t d,
                                   const core::EvalFrame& gt, const std::string& content,
                                   FragmentRule fragments) {
  switch (m.verdict[d]) {
    case core::DetectionVerdict::kTrue:
      return core::categoryOfClassName(gt.objects[m.matched_gt[d]].label);
    case core::DetectionVerdict::kIgnored:
      return content == "other-object" ? core::ObjectCategory::kOtherObject
                                       : core::ObjectCategory::kUnknown;
    case core::DetectionVerdict::kFalse:
    default:
      if (content.compare(0, 8, "part_of_") == 0 && fragments == FragmentRule::kSkip) {
        return core::ObjectCategory::kUnknown;
      }
      return core::ObjectCategory::kNonObject;
  }
}

// The rows and labels of detector 0 over the frames whose group is in `groups`.
void trainingSet(const std::vector<FrameData>& frames, const std::set<std::string>& groups,
                 std::vector<core::ObjectFeatureVector>* x, std::vector<core::ObjectCategory>* y) {
  x->clear();
  y->clear();
  for (const FrameData& f : frames) {
    if (!groups.count(f.group)) continue;
    const DetectorFrame& d = f.detectors[0];
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (d.labels[i] == core::ObjectCategory::kUnknown) continue;
      x->push_back(d.features[i]);
      y->push_back(d.labels[i]);
    }
  }
}

// Scores the frames of `groups` for detector k, keeping the detections whose P(object) >= t
// (t < 0: all). `probs(frame, detection)` gives the probabilities. Adds per group to `by_group`.
template <class ProbFn>
core::DetectionScore score(const std::vector<FrameData>& frames,
                           const std::set<std::string>& groups, std::size_t k, double t,
                           ProbFn probs, std::map<std::string, core::DetectionScore>* by_group) {
  core::DetectionEvaluator eval;
  std::vector<core::DetectedObject> kept;
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    const FrameData& f = frames[fi];
    if (!groups.count(f.group)) continue;
    const DetectorFrame& d = f.detectors[k];
    kept.clear();
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (t < 0.0 || 1.0 - probs(fi, i)[0] >= t) kept.push_back(d.objects[i]);
    }
    core::FrameMatch m;
    eval.evaluate(f.gt, kept, &m);
    if (by_group) (*by_group)[f.group] += m.score;
  }
  return eval.total();
}

// Thresholds tried when choosing P(object).
std::vector<double> thresholdGrid() {
  std::vector<double> t;
  for (int k = 5; k <= 95; k += 5) t.push_back(k / 100.0);
  return t;
}

// A forest trained on the hierarchical-grid detections of the frames of `groups`.
core::ObjectClassifierModel trainOn(const std::vector<FrameData>& frames,
                                    const std::set<std::string>& groups,
                                    const core::ClassifierTrainingParams& params,
                                    const core::ObjectFeatureParams& fp) {
  std::vector<core::ObjectFeatureVector> x;
  std::vector<core::ObjectCategory> y;
  trainingSet(frames, groups, &x, &y);
  return core::ObjectClassifierModel::train(x, y, params, fp);
}

// The threshold maximising the pooled F of `groups` (detector 0) under `probs`.
template <class ProbFn>
double bestThreshold(const std::vector<FrameData>& frames, const std::set<std::string>& groups,
                     ProbFn probs) {
  double best_t = 0.5, best_f = -1.0;
  for (const double t : thresholdGrid()) {
    const double f = score(frames, groups, 0, t, probs, nullptr).fRate();
    if (f > best_f + 1e-12) {
      best_f = f;
      best_t = t;
    }
  }
  return best_t;
}

// Threshold for a model trained on `groups`: inner 3-fold cross-validation over the groups.
double innerThreshold(std::vector<FrameData>* frames, const std::vector<std::string>& groups,
                      const core::ClassifierTrainingParams& params,
                      const core::ObjectFeatureParams& fp) {
  const int folds = std::min<int>(3, static_cast<int>(groups.size()));
  if (folds < 2) return params.object_threshold;
  std::map<std::pair<std::size_t, std::size_t>, Probabilities> oof;
  for (int k = 0; k < folds; ++k) {
    std::set<std::string> train, test;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      (static_cast<int>(g) % folds == k ? test : train).insert(groups[g]);
    }
    const core::ObjectClassifierModel m = trainOn(*frames, train, params, fp);
    for (std::size_t fi = 0; fi < frames->size(); ++fi) {
      const FrameData& f = (*frames)[fi];
      if (!test.count(f.group)) continue;
      std::vector<Probabilities> p;
      m.predict(f.detectors[0].features, &p);
      for (std::size_t i = 0; i < p.size(); ++i) oof[{fi, i}] = p[i];
    }
  }
  const std::set<std::string> all(groups.begin(), groups.end());
  return bestThreshold(*frames, all, [&](std::size_t fi, std::size_t i) { return oof[{fi, i}]; });
}

std::string scoreRow(const core::DetectionScore& s) {
  char b[160];
  std::snprintf(b, sizeof b, "%5zu %5zu %5zu %9.3f %7.3f %7.3f", s.no, s.mo, s.fo, s.precision(),
                s.recall(), s.fRate());
  return b;
}

std::string scoreJson(const core::DetectionScore& s) {
  std::ostringstream o;
  o << "{\"no\": " << s.no << ", \"mo\": " << s.mo << ", \"fo\": " << s.fo
    << ", \"precision\": " << jsonNumber(s.precision())
    << ", \"recall\": " << jsonNumber(s.recall()) << ", \"f_rate\": " << jsonNumber(s.fRate())
    << "}";
  return o.str();
}

void usage() {
  std::fprintf(
      stderr,
      "usage: urban_detection_train_classifier --semantic-kitti DIR [--config FILE]...\n"
      "         [--out MODEL] [--csv FILE] [--json FILE] [--no-intensity] [--trees N]\n"
      "         [--max-depth N] [--min-samples N] [--fragments reject|skip]\n"
      "         [--threshold auto|P] [--no-loso] [--no-kdtree] [--max-frames N]\n"
      "  --semantic-kitti DIR  dataset root (sequences/NN/{velodyne,labels}) or one sequence\n"
      "  --out MODEL     model file to write (.yml or .yml.gz), trained on every sequence\n"
      "  --csv FILE      feature table: one row per detection with its label and content\n"
      "  --no-intensity  train and score without the intensity features\n"
      "  --fragments     false detections made of a real object's points: not trained on\n"
      "                  (skip, default) or non-object (reject)\n"
      "  --threshold     P(object) to keep an object: chosen by cross-validation (auto,\n"
      "                  default) or fixed\n"
      "  --no-loso       skip the leave-one-sequence-out report (threshold: --threshold P or\n"
      "                  0.5)\n"
      "  --no-kdtree     do not score the kd-tree baseline with the same classifier\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string skitti_dir, out_path, csv_path, json_path, fragments_arg = "skip",
                                                         threshold_arg = "auto";
  std::vector<std::string> configs;
  core::ClassifierTrainingParams tp;
  bool loso = true, kdtree = true;
  long max_frames = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const urban_detection::tools::OptionArgs arg{argc, argv, &i};
    if (a == "--semantic-kitti")
      skitti_dir = arg.value("--semantic-kitti");
    else if (a == "--config")
      configs.push_back(arg.value("--config"));
    else if (a == "--out")
      out_path = arg.value("--out");
    else if (a == "--csv")
      csv_path = arg.value("--csv");
    else if (a == "--json")
      json_path = arg.value("--json");
    else if (a == "--no-intensity")
      tp.use_intensity = false;
    else if (a == "--trees")
      tp.trees = static_cast<int>(arg.count("--trees"));
    else if (a == "--max-depth")
      tp.max_depth = static_cast<int>(arg.count("--max-depth"));
    else if (a == "--min-samples")
      tp.min_sample_count = static_cast<int>(arg.count("--min-samples"));
    else if (a == "--fragments")
      fragments_arg = arg.value("--fragments");
    else if (a == "--threshold")
      threshold_arg = arg.value("--threshold");
    else if (a == "--no-loso")
      loso = false;
    else if (a == "--no-kdtree")
      kdtree = false;
    else if (a == "--max-frames")
      max_frames = arg.count("--max-frames");
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "error: unknown argument '%s'\n", a.c_str());
      usage();
      return 2;
    }
  }
  if (skitti_dir.empty()) {
    std::fprintf(stderr, "error: --semantic-kitti DIR is required\n");
    usage();
    return 2;
  }
  if (fragments_arg != "reject" && fragments_arg != "skip") {
    std::fprintf(stderr, "error: --fragments must be reject or skip\n");
    return 2;
  }
  const FragmentRule fragments =
      fragments_arg == "skip" ? FragmentRule::kSkip : FragmentRule::kReject;
  bool auto_threshold = threshold_arg == "auto";
  if (!auto_threshold) {
    char* end = nullptr;
    tp.object_threshold = std::strtod(threshold_arg.c_str(), &end);
    if (end == threshold_arg.c_str() || *end != '\0') {
      std::fprintf(stderr, "error: --threshold must be auto or a probability\n");
      return 2;
    }
  }
  const std::string tp_error = core::validate(tp);
  if (!tp_error.empty()) {
    std::fprintf(stderr, "error: %s\n", tp_error.c_str());
    return 2;
  }

  urban_detection::tools::PipelineParams params;
  if (!urban_detection::tools::loadConfigs(configs, &params)) return 2;
  core::ObjectFeatureParams fp;
  fp.sensor_height_m = params.segmentation.sensor_height_m;
  core::GridSegmenter segmenter(params.segmentation);
  std::vector<std::unique_ptr<core::ObjectDetector>> detectors;
  detectors.emplace_back(new core::HierarchicalGridDetector(params.hierarchical));
  if (kdtree) detectors.emplace_back(new core::KdTreeDetector(params.kdtree));
  core::ObjectFeatureExtractor extractor(fp);

  core::SemanticKittiGroundTruthParams gtp;
  urban_detection::tools::SemanticKittiDataset dataset(skitti_dir, gtp);
  if (dataset.size() == 0) {
    std::fprintf(stderr, "error: no labelled scans in %s\n", skitti_dir.c_str());
    return 1;
  }

  // 1-2. Pipeline, features, labels.
  std::vector<FrameData> frames;
  std::FILE* csv = nullptr;
  if (!csv_path.empty()) {
    csv = std::fopen(csv_path.c_str(), "w");
    if (!csv) {
      std::fprintf(stderr, "error: cannot write %s\n", csv_path.c_str());
      return 1;
    }
    std::fprintf(csv, "sequence,frame,detector,label,verdict,content");
    for (int k = 0; k < core::kNumObjectFeatures; ++k)
      std::fprintf(csv, ",%s", core::featureName(k));
    std::fprintf(csv, "\n");
  }
  urban_detection::tools::Frame f;
  std::vector<core::SegmentClass> seg;
  urban_detection::LabeledCloud foreground;
  core::DetectionEvaluator evaluator;
  std::size_t read = 0;
  for (;;) {
    if (max_frames >= 0 && read >= static_cast<std::size_t>(max_frames)) break;
    std::string err;
    const auto status = dataset.next(&f, &err);
    if (status == urban_detection::tools::Dataset::Status::kEnd) break;
    ++read;
    if (status == urban_detection::tools::Dataset::Status::kSkipped) {
      std::fprintf(stderr, "warning: skipping a scan: %s\n", err.c_str());
      continue;
    }
    segmenter.segment(f.cloud, &seg);
    core::extractForeground(f.cloud, seg, &foreground);
    FrameData fd;
    fd.id = f.id;
    fd.group = urban_detection::tools::frameGroup(f.id, dataset.name());
    fd.detectors.resize(detectors.size());
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      DetectorFrame& d = fd.detectors[k];
      detectors[k]->detect(foreground, &d.objects);
      core::FrameMatch m;
      evaluator.evaluate(f.gt, d.objects, &m);
      extractor.computeAll(foreground, d.objects, &d.features);
      for (std::size_t i = 0; i < d.objects.size(); ++i) {
        const std::string content =
            urban_detection::tools::detectionContent(f, dataset, d.objects[i]);
        d.labels.push_back(trainingLabel(m, i, f.gt, content, fragments));
        if (csv) {
          std::fprintf(csv, "%s,%s,%s,%s,%s,%s", fd.group.c_str(), f.id.c_str(),
                       detectors[k]->name().c_str(), core::toString(d.labels.back()),
                       core::toString(m.verdict[i]), content.c_str());
          for (const float v : d.features[i]) std::fprintf(csv, ",%.6g", v);
          std::fprintf(csv, "\n");
        }
      }
    }
    fd.gt = std::move(f.gt);
    frames.push_back(std::move(fd));
  }
  if (csv) std::fclose(csv);
  std::vector<std::string> groups;
  for (const FrameData& fd : frames) {
    if (groups.empty() || groups.back() != fd.group) groups.push_back(fd.group);
  }
  std::array<std::size_t, core::kNumObjectCategories> label_count{};
  std::size_t unlabelled = 0;
  for (const FrameData& fd : frames) {
    for (const auto l : fd.detectors[0].labels) {
      if (l == core::ObjectCategory::kUnknown)
        ++unlabelled;
      else
        ++label_count[static_cast<int>(l)];
    }
  }
  std::printf("%zu scans, %zu sequences; training rows (hierarchical grid):", frames.size(),
              groups.size());
  for (int c = 0; c < core::kNumObjectCategories; ++c) {
    std::printf(" %s %zu", core::toString(static_cast<core::ObjectCategory>(c)), label_count[c]);
  }
  std::printf(", not trained on %zu\n", unlabelled);

  const std::set<std::string> all_groups(groups.begin(), groups.end());
  std::ostringstream json;
  double shipped_threshold = tp.object_threshold;
  if (loso && groups.size() >= 2) {
    // 3. Leave one sequence out.
    std::map<std::string, double> fold_threshold;
    for (const std::string& held : groups) {
      std::vector<std::string> train_groups;
      for (const std::string& g : groups) {
        if (g != held) train_groups.push_back(g);
      }
      core::ClassifierTrainingParams fold_tp = tp;
      if (auto_threshold) fold_tp.object_threshold = innerThreshold(&frames, train_groups, tp, fp);
      fold_threshold[held] = fold_tp.object_threshold;
      const core::ObjectClassifierModel m = trainOn(
          frames, std::set<std::string>(train_groups.begin(), train_groups.end()), fold_tp, fp);
      for (FrameData& fd : frames) {
        if (fd.group != held) continue;
        for (DetectorFrame& d : fd.detectors) m.predict(d.features, &d.held_out);
      }
    }
    auto held_out = [&](std::size_t k) {
      return [&frames, k](std::size_t fi, std::size_t i) {
        return frames[fi].detectors[k].held_out[i];
      };
    };
    // Each sequence scored with its own fold's threshold.
    std::vector<std::map<std::string, core::DetectionScore>> off(detectors.size()),
        on(detectors.size());
    std::vector<core::DetectionScore> off_total(detectors.size()), on_total(detectors.size());
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      off_total[k] = score(frames, all_groups, k, -1.0, held_out(k), &off[k]);
      for (const std::string& g : groups) {
        on_total[k] += score(frames, {g}, k, fold_threshold[g], held_out(k), &on[k]);
      }
    }
    std::printf("\nleave-one-sequence-out, intensity features %s, fragments %s\n",
                tp.use_intensity ? "on" : "off", fragments_arg.c_str());
    std::printf("%-8s %-18s %9s | %-43s | %-43s\n", "seq", "detector", "threshold",
                "classifier off: NO MO FO P R F", "classifier on: NO MO FO P R F");
    json << "{\n  \"dataset\": \"semantic_kitti\",\n  \"path\": \"" << jsonEscape(skitti_dir)
         << "\",\n  \"scans\": " << frames.size()
         << ",\n  \"intensity_features\": " << (tp.use_intensity ? "true" : "false")
         << ",\n  \"fragments\": \"" << fragments_arg << "\",\n  \"trees\": " << tp.trees
         << ",\n  \"loso\": {";
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      json << (k ? ",\n" : "\n") << "    \"" << detectors[k]->name() << "\": {\"sequences\": {";
      bool first = true;
      for (const std::string& g : groups) {
        std::printf("%-8s %-18s %9.2f | %s | %s\n", g.c_str(), detectors[k]->name().c_str(),
                    fold_threshold[g], scoreRow(off[k][g]).c_str(), scoreRow(on[k][g]).c_str());
        json << (first ? "" : ", ") << "\"" << g
             << "\": {\"threshold\": " << jsonNumber(fold_threshold[g])
             << ", \"off\": " << scoreJson(off[k][g]) << ", \"on\": " << scoreJson(on[k][g]) << "}";
        first = false;
      }
      std::printf("%-8s %-18s %9s | %s | %s\n", "pooled", detectors[k]->name().c_str(), "",
                  scoreRow(off_total[k]).c_str(), scoreRow(on_total[k]).c_str());
      double min_f = 1.0;
      for (const std::string& g : groups) min_f = std::min(min_f, on[k][g].fRate());
      json << "}, \"pooled_off\": " << scoreJson(off_total[k])
           << ", \"pooled_on\": " << scoreJson(on_total[k])
           << ", \"min_sequence_f_on\": " << jsonNumber(min_f) << "}";
    }
    json << "\n  },\n";
    // Pooled confusion matrix of the held-out predictions (hierarchical grid, argmax rule of
    // the classification stage with each fold's threshold).
    std::array<std::array<std::size_t, core::kNumObjectCategories>, core::kNumObjectCategories>
        confusion{};
    for (const FrameData& fd : frames) {
      const DetectorFrame& d = fd.detectors[0];
      for (std::size_t i = 0; i < d.objects.size(); ++i) {
        if (d.labels[i] == core::ObjectCategory::kUnknown) continue;
        const Probabilities& p = d.held_out[i];
        int pred = 0;
        if (1.0 - p[0] >= fold_threshold[fd.group]) {
          pred = 1;
          for (int c = 2; c < core::kNumObjectCategories; ++c) {
            if (p[c] > p[pred]) pred = c;
          }
        }
        ++confusion[static_cast<int>(d.labels[i])][pred];
      }
    }
    std::printf("\nheld-out confusion (rows: label, columns: prediction), hierarchical grid\n%14s",
                "");
    for (int c = 0; c < core::kNumObjectCategories; ++c) {
      std::printf(" %12s", core::toString(static_cast<core::ObjectCategory>(c)));
    }
    std::printf("\n");
    json << "  \"confusion\": [";
    for (int r = 0; r < core::kNumObjectCategories; ++r) {
      std::printf("%14s", core::toString(static_cast<core::ObjectCategory>(r)));
      json << (r ? ", " : "") << "[";
      for (int c = 0; c < core::kNumObjectCategories; ++c) {
        std::printf(" %12zu", confusion[r][c]);
        json << (c ? ", " : "") << confusion[r][c];
      }
      json << "]";
      std::printf("\n");
    }
    json << "],\n";
    // 4. The shipped threshold: best pooled F of the held-out predictions.
    if (auto_threshold) shipped_threshold = bestThreshold(frames, all_groups, held_out(0));
  } else if (auto_threshold) {
    std::printf("no leave-one-sequence-out run: threshold 0.5\n");
    shipped_threshold = 0.5;
  }

  if (!out_path.empty()) {
    core::ClassifierTrainingParams final_tp = tp;
    final_tp.object_threshold = shipped_threshold;
    std::ostringstream desc;
    desc << "random forest, " << tp.trees << " trees, max depth " << tp.max_depth
         << ", min samples " << tp.min_sample_count << ", intensity features "
         << (tp.use_intensity ? "on" : "off") << ", fragments " << fragments_arg << "; trained on "
         << frames.size() << " SemanticKITTI scans of sequences";
    for (const std::string& g : groups) desc << " " << g;
    desc << " (hierarchical grid detections, shipped configs); threshold "
         << (auto_threshold ? "from the pooled leave-one-sequence-out F" : "given");
    final_tp.description = desc.str();
    try {
      const core::ObjectClassifierModel m = trainOn(frames, all_groups, final_tp, fp);
      m.save(out_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
    std::printf("\nmodel: %s (threshold %.2f)\n", out_path.c_str(), shipped_threshold);
  }
  if (!json_path.empty()) {
    if (json.tellp() == 0) {
      json << "{\n  \"dataset\": \"semantic_kitti\",\n  \"scans\": " << frames.size() << ",\n";
    }
    json << "  \"threshold\": " << jsonNumber(shipped_threshold) << "\n}\n";
    std::ofstream out(json_path);
    out << json.str();
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}
