// urban_detection_train_classifier: trains the object classifier (object_classifier.h) on
// labelled real scans and reports it leave-one-sequence-out. No ROS master needed.
//
//   urban_detection_train_classifier --semantic-kitti DIR [--config FILE]... [--out MODEL]
//       [--csv FILE] [--json FILE] [--no-intensity] [--trees N] [--max-depth N]
//       [--min-samples N] [--fragments reject|skip] [--threshold auto|P] [--no-loso]
//       [--no-kdtree] [--min-points N] [--augment P,V] [--decision object|class]
//       [--class-balance B] [--uncertain-band W]
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
// 2b. Examples the sensor would have given (--augment, augmentation.h): each sequence's persons,
//    cyclists and vehicles re-sampled farther away and pasted on free ground into its own
//    scans; only the detections of pasted objects become training rows; never scored.
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
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/evaluation/augmentation.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/calibration.h"

#include "datasets.h"
#include "tool_common.h"
#include "tracking_eval.h"

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
  bool augmented = false;     // made by augmentSequence (or simulated): trained on, never scored
  bool always_train = false;  // simulated: in the training set of every fold
  core::EvalFrame gt;
  std::vector<float> gt_range;  // per GT object, its horizontal distance [m]
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
    if (!f.always_train && !groups.count(f.group)) continue;
    const DetectorFrame& d = f.detectors[0];
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (d.labels[i] == core::ObjectCategory::kUnknown) continue;
      x->push_back(d.features[i]);
      y->push_back(d.labels[i]);
    }
  }
}

// Score and breakdown of a set of frames.
struct Scored {
  core::DetectionScore score;       // under --min-points
  core::DetectionScore all;         // every object (N = 1)
  core::RecallBreakdown breakdown;  // per class, points, range
};

// Scores the frames of `groups` for detector k, classified by `decision` (null: the detector
// alone, every detection kept) with the probabilities `probs(frame, detection)`. Adds per
// group to `by_group` when not null.
// Per frame and detection, the class a later stage gave (kUnknown: the decision's own).
using ClassOverride = std::map<std::size_t, std::vector<core::ObjectCategory>>;

template <class ProbFn>
Scored score(const std::vector<FrameData>& frames, const std::set<std::string>& groups,
             std::size_t k, const core::ClassDecision* decision, ProbFn probs,
             const core::EvaluationParams& ep, std::map<std::string, Scored>* by_group,
             const ClassOverride* override_class = nullptr) {
  core::DetectionEvaluator eval(ep);
  core::EvaluationParams ep_all = ep;
  ep_all.min_points = 1;
  core::DetectionEvaluator eval_all(ep_all);
  Scored out;
  std::vector<core::DetectedObject> kept;
  core::FrameMatch m;
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    const FrameData& f = frames[fi];
    if (f.augmented || !groups.count(f.group)) continue;
    const DetectorFrame& d = f.detectors[k];
    kept.clear();
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (!decision) {
        kept.push_back(d.objects[i]);
        continue;
      }
      float confidence = 0.0f;
      core::ObjectCategory c = core::decideClass(probs(fi, i), *decision, true, &confidence);
      if (override_class) {
        const auto it = override_class->find(fi);
        if (it != override_class->end() && i < it->second.size() &&
            it->second[i] != core::ObjectCategory::kUnknown) {
          c = it->second[i];
        }
      }
      if (c == core::ObjectCategory::kNonObject) continue;
      kept.push_back(d.objects[i]);
      kept.back().category = c;
    }
    eval_all.evaluate(f.gt, kept, &m);
    const core::DetectionScore all = m.score;
    eval.evaluate(f.gt, kept, &m);
    core::RecallBreakdown b;
    b.addFrame(f.gt, m, kept, f.gt_range, ep.min_points);
    out.breakdown += b;
    if (by_group) {
      Scored& g = (*by_group)[f.group];
      g.score += m.score;
      g.all += all;
      g.breakdown += b;
    }
  }
  out.score = eval.total();
  out.all = eval_all.total();
  return out;
}

// What the decision is chosen for: the pooled F and, as much, the mean recall of the classes
// present (vehicle, pedestrian, cyclist): missing a person costs more than keeping a bush.
double objective(const Scored& s) {
  double sum = 0.0;
  int n = 0;
  for (int c = 0; c < 3; ++c) {
    if (s.breakdown.by_class[c].total == 0) continue;
    sum += s.breakdown.by_class[c].recall();
    ++n;
  }
  const double f = s.score.fRate();
  return n == 0 ? f : 0.5 * f + 0.5 * sum / n;
}

// Thresholds tried when choosing a decision.
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

// Time as evidence: a sequence's scans in order through the tracker in the world frame of
// poses.txt, every detection with its class (non-objects included, with P(non_object)). A
// confirmed track whose accumulated class (class_evidence.h) is an object class makes its
// detection an object of that class. Returns the classes per frame (kUnknown: the scan's own
// decision stands). Keeping small tracks that move and dropping detections of tracks whose
// evidence says non-object were measured and are not used (docs/classification.md).
struct TemporalStats {
  std::size_t kept = 0;       // rejected by their scan, kept by their track's class
  std::size_t reclassed = 0;  // kept by their scan, class taken from their track
};

template <class ProbFn>
void temporalClasses(const std::vector<FrameData>& frames, const std::string& group, std::size_t k,
                     const core::ClassDecision& decision, ProbFn probs,
                     const std::vector<Eigen::Isometry3d>& poses,
                     const core::TrackerParams& tracker_params, ClassOverride* out,
                     TemporalStats* stats) {
  core::Tracker tracker(tracker_params);
  std::vector<core::DetectedObject> objects;
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    const FrameData& f = frames[fi];
    if (f.augmented || f.group != group) continue;
    const std::size_t slash = f.id.find('/');
    const std::size_t scan = std::strtoul(f.id.c_str() + (slash + 1), nullptr, 10);
    if (scan >= poses.size()) continue;
    objects = f.detectors[k].objects;
    std::vector<core::ObjectCategory> own(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
      float confidence = 0.0f;
      own[i] = core::decideClass(probs(fi, i), decision, true, &confidence);
      objects[i].category = own[i];
      objects[i].class_confidence = confidence;
    }
    tracker.update(objects, poses[scan], 0.1 * static_cast<double>(scan));
    std::vector<core::ObjectCategory>& cls = (*out)[fi];
    cls.assign(objects.size(), core::ObjectCategory::kUnknown);
    for (const core::Track& t : tracker.tracks()) {
      if (t.detection < 0 || static_cast<std::size_t>(t.detection) >= objects.size() ||
          t.state == core::TrackState::kTentative ||
          t.category == core::ObjectCategory::kNonObject ||
          t.category == core::ObjectCategory::kUnknown) {
        continue;
      }
      const std::size_t i = static_cast<std::size_t>(t.detection);
      cls[i] = t.category;
      ++(own[i] == core::ObjectCategory::kNonObject ? stats->kept : stats->reclassed);
    }
  }
}

enum class DecisionRule { kObject, kClass };

// The decision maximising objective() on `groups` (detector 0) under `probs`: the object
// threshold alone (kObject) or, after it, each class threshold and the uncertain band in turn
// (coordinate ascent, kClass).
template <class ProbFn>
core::ClassDecision bestDecision(const std::vector<FrameData>& frames,
                                 const std::set<std::string>& groups, ProbFn probs,
                                 const core::EvaluationParams& ep, DecisionRule rule,
                                 double uncertain_band) {
  core::ClassDecision best;
  double best_j = -1.0;
  auto consider = [&](const core::ClassDecision& d) {
    const double j = objective(score(frames, groups, 0, &d, probs, ep, nullptr));
    if (j > best_j + 1e-12) {
      best_j = j;
      best = d;
    }
  };
  for (const double t : thresholdGrid()) {
    core::ClassDecision d;
    d.object_threshold = t;
    consider(d);
  }
  if (rule == DecisionRule::kObject) {
    best.uncertain_threshold = std::max(0.0, best.object_threshold - uncertain_band);
    return best;
  }
  for (int round = 0; round < 2; ++round) {
    for (std::size_t c = 0; c < 3; ++c) {
      const core::ClassDecision base = best;
      for (const double t : thresholdGrid()) {
        if (t >= base.object_threshold) break;
        core::ClassDecision d = base;
        d.class_thresholds[c] = t;
        consider(d);
      }
    }
    const core::ClassDecision base = best;
    for (const double t : thresholdGrid()) {
      if (t >= base.object_threshold) break;
      core::ClassDecision d = base;
      d.uncertain_threshold = t;
      consider(d);
    }
  }
  return best;
}

// Decision for a model trained on `groups`: inner 3-fold cross-validation over the groups.
core::ClassDecision innerDecision(std::vector<FrameData>* frames,
                                  const std::vector<std::string>& groups,
                                  const core::ClassifierTrainingParams& params,
                                  const core::ObjectFeatureParams& fp,
                                  const core::EvaluationParams& ep, DecisionRule rule,
                                  double uncertain_band) {
  const int folds = std::min<int>(3, static_cast<int>(groups.size()));
  if (folds < 2) {
    core::ClassDecision d;
    d.object_threshold = params.object_threshold;
    return d;
  }
  std::map<std::pair<std::size_t, std::size_t>, Probabilities> oof;
  for (int k = 0; k < folds; ++k) {
    std::set<std::string> train, test;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      (static_cast<int>(g) % folds == k ? test : train).insert(groups[g]);
    }
    const core::ObjectClassifierModel m = trainOn(*frames, train, params, fp);
    for (std::size_t fi = 0; fi < frames->size(); ++fi) {
      const FrameData& f = (*frames)[fi];
      if (f.augmented || !test.count(f.group)) continue;
      std::vector<Probabilities> p;
      m.predict(f.detectors[0].features, &p);
      for (std::size_t i = 0; i < p.size(); ++i) oof[{fi, i}] = p[i];
    }
  }
  const std::set<std::string> all(groups.begin(), groups.end());
  return bestDecision(
      *frames, all,
      [&](std::size_t fi, std::size_t i) {
        return oof[{fi, i}];
      },
      ep, rule, uncertain_band);
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
      "         [--min-points N] [--decision object|class] [--class-balance B]\n"
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
      "  --no-kdtree     do not score the kd-tree baseline with the same classifier\n"
      "  --min-points N  objects and detections under N points count only when matched\n"
      "                  (default 30; the N = 1 figure is printed beside it)\n"
      "  --decision      object (default): one P(object) threshold; class: also a threshold\n"
      "                  per class and an uncertain band kept as other_object, all chosen on\n"
      "                  the training sequences\n"
      "  --uncertain-band W  with --decision object: objects with P(object) within W below\n"
      "                  the threshold stay as uncertain other_object (default 0: none)\n"
      "  --class-balance B  row weights (rows / (classes x class rows))^B (default 0)\n"
      "  --sim GT --pcap PCAP  also train on the first --sim-frames N (default 60) revolutions\n"
      "                  of a simulated drive (urban_detection_simulate), in every fold's\n"
      "                  training set, never scored\n"
      "  --augment P[,V]  training examples made from the training sequences' objects: P\n"
      "                  copies of each person and cyclist, V of each vehicle (default 16,2;\n"
      "                  0,0: off), re-sampled farther away and pasted on free ground into the\n"
      "                  sequence's scans (augmentation.h); trained on, never scored\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string skitti_dir, out_path, csv_path, json_path, fragments_arg = "skip",
                                                         threshold_arg = "auto";
  std::vector<std::string> configs;
  core::ClassifierTrainingParams tp;
  bool loso = true, kdtree = true;
  long max_frames = -1, min_points = 30;
  std::string decision_arg = "object";
  double uncertain_band = 0.0;
  std::string sim_gt, sim_pcap;
  long sim_frames = 60;
  core::AugmentParams augment;
  augment.person_copies = 16;
  augment.vehicle_copies = 2;
  tp.class_balance = 0.0;
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
    else if (a == "--min-points")
      min_points = arg.count("--min-points");
    else if (a == "--augment") {
      const std::string v = arg.value("--augment");
      int pc = 0, vc = 0;
      const int n = std::sscanf(v.c_str(), "%d,%d", &pc, &vc);
      if (n < 1 || pc < 0 || pc > 100 || vc < 0 || vc > 100) {
        std::fprintf(stderr, "error: --augment needs P[,V] copies in [0, 100]\n");
        return 2;
      }
      augment.person_copies = pc;
      augment.vehicle_copies = n == 2 ? vc : 0;
    } else if (a == "--sim") {
      sim_gt = arg.value("--sim");
    } else if (a == "--pcap") {
      sim_pcap = arg.value("--pcap");
    } else if (a == "--sim-frames") {
      sim_frames = arg.count("--sim-frames");
    } else if (a == "--uncertain-band") {
      const std::string v = arg.value("--uncertain-band");
      char* end = nullptr;
      uncertain_band = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(uncertain_band >= 0.0 && uncertain_band <= 1.0)) {
        std::fprintf(stderr, "error: --uncertain-band needs a probability in [0, 1]\n");
        return 2;
      }
    } else if (a == "--decision")
      decision_arg = arg.value("--decision");
    else if (a == "--class-balance") {
      const std::string v = arg.value("--class-balance");
      char* end = nullptr;
      tp.class_balance = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0') {
        std::fprintf(stderr, "error: --class-balance needs a number in [0, 1]\n");
        return 2;
      }
    } else if (a == "-h" || a == "--help") {
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
  if (decision_arg != "object" && decision_arg != "class") {
    std::fprintf(stderr, "error: --decision must be object or class\n");
    return 2;
  }
  if (min_points < 1) {
    std::fprintf(stderr, "error: --min-points must be at least 1\n");
    return 2;
  }
  const DecisionRule rule = decision_arg == "class" ? DecisionRule::kClass : DecisionRule::kObject;
  core::EvaluationParams ep;
  ep.min_points = static_cast<std::size_t>(min_points);
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

  core::PipelineParams params;
  if (!urban_detection::tools::loadConfigs(configs, &params)) return 2;
  core::ObjectFeatureParams fp;
  fp.sensor_height_m = params.segmentation.sensor_height_m;
  // The detectors' own objects: the pipeline without the classifier (it is what is trained
  // here) and without box fitting. The first pipeline's foreground serves the second.
  params.classifier.enabled = false;
  params.box_fitting.enabled = false;
  std::vector<std::unique_ptr<core::Pipeline>> pipelines;
  for (const char* detector : {"hierarchical_grid", "kdtree"}) {
    if (!kdtree && pipelines.size() == 1) break;
    params.detector = detector;
    pipelines.emplace_back(new core::Pipeline(params));
  }
  // Segmentation, foreground and the hierarchical grid's objects of `cloud`.
  auto detectScan = [&](const urban_detection::CloudXYZIRT& cloud) -> const core::PipelineResult& {
    return pipelines[0]->process(cloud);
  };
  core::ObjectFeatureExtractor extractor(fp);

  core::SemanticKittiGroundTruthParams gtp;
  gtp.min_points = 1;  // small objects are trained on; the scoring applies --min-points
  urban_detection::tools::SemanticKittiDataset dataset(skitti_dir, gtp);
  if (dataset.size() == 0) {
    std::fprintf(stderr, "error: no labelled scans in %s\n", skitti_dir.c_str());
    return 1;
  }

  // 1-2. Pipeline, features, labels.
  std::vector<FrameData> frames;
  const bool augmenting = augment.person_copies > 0 || augment.vehicle_copies > 0;
  std::map<std::string, std::vector<core::LabelledScan>> scans_of_group;  // for augmentation
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
    const urban_detection::LabeledCloud& foreground = detectScan(f.cloud).foreground;
    FrameData fd;
    fd.id = f.id;
    fd.group = urban_detection::tools::frameGroup(f.id, dataset.name());
    fd.detectors.resize(pipelines.size());
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      DetectorFrame& d = fd.detectors[k];
      d.objects = (k == 0 ? pipelines[0]->result() : pipelines[k]->detect(foreground)).objects;
      core::FrameMatch m;
      evaluator.evaluate(f.gt, d.objects, &m);
      extractor.computeAll(foreground, d.objects, &d.features);
      for (std::size_t i = 0; i < d.objects.size(); ++i) {
        const std::string content =
            urban_detection::tools::detectionContent(f, dataset, d.objects[i]);
        d.labels.push_back(trainingLabel(m, i, f.gt, content, fragments));
        if (csv) {
          std::fprintf(csv, "%s,%s,%s,%s,%s,%s", fd.group.c_str(), f.id.c_str(),
                       pipelines[k]->detector().name().c_str(), core::toString(d.labels.back()),
                       core::toString(m.verdict[i]), content.c_str());
          for (const float v : d.features[i]) std::fprintf(csv, ",%.6g", v);
          std::fprintf(csv, "\n");
        }
      }
    }
    fd.gt_range = core::gtObjectRanges(f.gt, f.cloud);
    if (augmenting) {
      core::LabelledScan scan;
      scan.cloud = f.cloud;
      scan.labels.resize(f.cloud.size());
      for (std::size_t i = 0; i < scan.labels.size(); ++i) {
        const std::int32_t g = f.gt.object_of_point[i];
        scan.labels[i] = f.point_class[i] | (g >= 0 ? f.gt.objects[g].id << 16 : 0u);
      }
      scans_of_group[fd.group].push_back(std::move(scan));
    }
    fd.gt = std::move(f.gt);
    frames.push_back(std::move(fd));
  }
  if (csv) std::fclose(csv);
  // Augmented examples: each sequence's objects copied into its own scans, so that they stay on
  // the training side of every leave-one-sequence-out split.
  std::size_t augmented_rows = 0;
  for (const auto& kv : scans_of_group) {
    std::vector<const core::LabelledScan*> scans;
    for (const auto& sc : kv.second) scans.push_back(&sc);
    core::AugmentParams ap = augment;
    ap.seed =
        augment.seed + static_cast<std::uint32_t>(std::hash<std::string>{}(kv.first) & 0xFFFF);
    const std::vector<core::LabelledScan> made = core::augmentSequence(scans, ap);
    for (std::size_t a = 0; a < made.size(); ++a) {
      urban_detection::tools::Frame af;
      af.id = kv.first + "/augmented_" + std::to_string(a);
      af.cloud = made[a].cloud;
      core::buildSemanticKittiGroundTruth(made[a].labels, gtp, &af.gt);
      const core::PipelineResult& scan = detectScan(af.cloud);
      const urban_detection::LabeledCloud& foreground = scan.foreground;
      FrameData fd;
      fd.id = af.id;
      fd.group = kv.first;
      fd.augmented = true;
      fd.detectors.resize(pipelines.size());
      DetectorFrame& d = fd.detectors[0];  // the forest learns from the hierarchical grid
      d.objects = scan.objects;
      core::FrameMatch m;
      evaluator.evaluate(af.gt, d.objects, &m);
      extractor.computeAll(foreground, d.objects, &d.features);
      for (std::size_t i = 0; i < d.objects.size(); ++i) {
        // Only the pasted objects are new; the rest of the scan is already in the table.
        const bool pasted = m.verdict[i] == core::DetectionVerdict::kTrue &&
                            af.gt.objects[m.matched_gt[i]].id >= core::kPastedInstanceBase;
        d.labels.push_back(pasted ? core::categoryOfClassName(af.gt.objects[m.matched_gt[i]].label)
                                  : core::ObjectCategory::kUnknown);
        augmented_rows += pasted;
      }
      frames.push_back(std::move(fd));
    }
  }
  // Simulated revolutions: trained on in every fold, never scored.
  if (sim_gt.empty() != sim_pcap.empty()) {
    std::fprintf(stderr, "error: --sim GT and --pcap PCAP go together\n");
    return 2;
  }
  std::size_t sim_rows = 0;
  if (!sim_gt.empty()) {
    try {
      core::SimulatedGroundTruthParams sgp;
      sgp.min_points = 1;
      urban_detection::tools::SimulatedDriveDataset sim(sim_gt, sim_pcap, core::loadCalibration(""),
                                                        0.0, sgp);
      urban_detection::tools::Frame sf;
      for (long n = 0; n < sim_frames; ++n) {
        std::string err;
        const auto status = sim.next(&sf, &err);
        if (status == urban_detection::tools::Dataset::Status::kEnd) break;
        if (status == urban_detection::tools::Dataset::Status::kSkipped) continue;
        const core::PipelineResult& scan = detectScan(sf.cloud);
        const urban_detection::LabeledCloud& foreground = scan.foreground;
        FrameData fd;
        fd.id = "sim/" + sf.id;
        fd.group = "sim";
        fd.augmented = true;
        fd.always_train = true;
        fd.detectors.resize(pipelines.size());
        DetectorFrame& d = fd.detectors[0];
        d.objects = scan.objects;
        core::FrameMatch m;
        evaluator.evaluate(sf.gt, d.objects, &m);
        extractor.computeAll(foreground, d.objects, &d.features);
        for (std::size_t i = 0; i < d.objects.size(); ++i) {
          const std::string content =
              urban_detection::tools::detectionContent(sf, sim, d.objects[i]);
          d.labels.push_back(trainingLabel(m, i, sf.gt, content, fragments));
          sim_rows += d.labels.back() != core::ObjectCategory::kUnknown;
        }
        frames.push_back(std::move(fd));
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
    std::printf("simulated drive: %zu training rows\n", sim_rows);
  }
  std::vector<std::string> groups;
  for (const FrameData& fd : frames) {
    if (!fd.augmented && (groups.empty() || groups.back() != fd.group)) groups.push_back(fd.group);
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
  std::printf(", not trained on %zu (augmented rows among them: %zu)\n", unlabelled,
              augmented_rows);

  const std::set<std::string> all_groups(groups.begin(), groups.end());
  std::ostringstream json;
  core::ClassDecision shipped_decision;
  shipped_decision.object_threshold = tp.object_threshold;
  if (loso && groups.size() >= 2) {
    // 3. Leave one sequence out.
    std::map<std::string, core::ClassDecision> fold_decision;
    for (const std::string& held : groups) {
      std::vector<std::string> train_groups;
      for (const std::string& g : groups) {
        if (g != held) train_groups.push_back(g);
      }
      core::ClassifierTrainingParams fold_tp = tp;
      core::ClassDecision d;
      d.object_threshold = tp.object_threshold;
      if (auto_threshold)
        d = innerDecision(&frames, train_groups, tp, fp, ep, rule, uncertain_band);
      fold_decision[held] = d;
      const core::ObjectClassifierModel m = trainOn(
          frames, std::set<std::string>(train_groups.begin(), train_groups.end()), fold_tp, fp);
      for (FrameData& fd : frames) {
        if (fd.augmented || fd.group != held) continue;
        for (DetectorFrame& dk : fd.detectors) m.predict(dk.features, &dk.held_out);
      }
    }
    auto held_out = [&](std::size_t k) {
      return [&frames, k](std::size_t fi, std::size_t i) {
        return frames[fi].detectors[k].held_out[i];
      };
    };
    // Each sequence scored with its own fold's decision.
    std::vector<std::map<std::string, Scored>> off(pipelines.size()), on(pipelines.size());
    std::vector<Scored> off_total(pipelines.size()), on_total(pipelines.size());
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      off_total[k] = score(frames, all_groups, k, nullptr, held_out(k), ep, &off[k]);
      for (const std::string& g : groups) {
        const Scored sg = score(frames, {g}, k, &fold_decision[g], held_out(k), ep, &on[k]);
        on_total[k].score += sg.score;
        on_total[k].all += sg.all;
        on_total[k].breakdown += sg.breakdown;
      }
    }
    std::printf(
        "\nleave-one-sequence-out, intensity features %s, fragments %s, decision %s, class "
        "balance %.2f; objects and detections under %ld points count only when matched (N = 1: "
        "every object)\n",
        tp.use_intensity ? "on" : "off", fragments_arg.c_str(), decision_arg.c_str(),
        tp.class_balance, min_points);
    std::printf("%-8s %-18s %-22s | %-43s | %-43s\n", "seq", "detector", "object/veh/ped/cyc/unc",
                "classifier off: NO MO FO P R F", "classifier on: NO MO FO P R F");
    auto decisionText = [](const core::ClassDecision& d) {
      char b[64];
      std::snprintf(b, sizeof b, "%.2f/%.2f/%.2f/%.2f/%.2f", d.object_threshold,
                    d.class_thresholds[0], d.class_thresholds[1], d.class_thresholds[2],
                    d.uncertain_threshold);
      return std::string(b);
    };
    auto decisionJson = [](const core::ClassDecision& d) {
      std::ostringstream o;
      o << "{\"object\": " << jsonNumber(d.object_threshold)
        << ", \"vehicle\": " << jsonNumber(d.class_thresholds[0])
        << ", \"pedestrian\": " << jsonNumber(d.class_thresholds[1])
        << ", \"cyclist\": " << jsonNumber(d.class_thresholds[2])
        << ", \"uncertain\": " << jsonNumber(d.uncertain_threshold) << "}";
      return o.str();
    };
    json << "{\n  \"dataset\": \"semantic_kitti\",\n  \"path\": \"" << jsonEscape(skitti_dir)
         << "\",\n  \"scans\": " << frames.size()
         << ",\n  \"intensity_features\": " << (tp.use_intensity ? "true" : "false")
         << ",\n  \"fragments\": \"" << fragments_arg << "\",\n  \"trees\": " << tp.trees
         << ",\n  \"min_points\": " << min_points << ",\n  \"decision\": \"" << decision_arg
         << "\",\n  \"class_balance\": " << jsonNumber(tp.class_balance) << ",\n  \"loso\": {";
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      json << (k ? ",\n" : "\n") << "    \"" << pipelines[k]->detector().name()
           << "\": {\"sequences\": {";
      bool first = true;
      for (const std::string& g : groups) {
        std::printf("%-8s %-18s %-22s | %s | %s\n", g.c_str(),
                    pipelines[k]->detector().name().c_str(), decisionText(fold_decision[g]).c_str(),
                    scoreRow(off[k][g].score).c_str(), scoreRow(on[k][g].score).c_str());
        json << (first ? "" : ", ") << "\"" << g
             << "\": {\"decision\": " << decisionJson(fold_decision[g])
             << ", \"off\": " << scoreJson(off[k][g].score)
             << ", \"on\": " << scoreJson(on[k][g].score) << "}";
        first = false;
      }
      std::printf("%-8s %-18s %-22s | %s | %s\n", "pooled", pipelines[k]->detector().name().c_str(),
                  "", scoreRow(off_total[k].score).c_str(), scoreRow(on_total[k].score).c_str());
      std::printf("%-8s %-18s %-22s | %s | %s\n", "N = 1", pipelines[k]->detector().name().c_str(),
                  "", scoreRow(off_total[k].all).c_str(), scoreRow(on_total[k].all).c_str());
      double min_f = 1.0;
      for (const std::string& g : groups) min_f = std::min(min_f, on[k][g].score.fRate());
      json << "}, \"pooled_off\": " << scoreJson(off_total[k].score)
           << ", \"pooled_on\": " << scoreJson(on_total[k].score)
           << ", \"pooled_off_all_objects\": " << scoreJson(off_total[k].all)
           << ", \"pooled_on_all_objects\": " << scoreJson(on_total[k].all)
           << ", \"breakdown_off\": " << off_total[k].breakdown.json()
           << ", \"breakdown_on\": " << on_total[k].breakdown.json()
           << ", \"min_sequence_f_on\": " << jsonNumber(min_f) << "}";
    }
    json << "\n  },\n";
    // Time as evidence (hierarchical grid): each held-out sequence in scan order with its poses.
    ClassOverride over_time;
    TemporalStats temporal_stats;
    bool temporal_ok = true;
    for (const std::string& g : groups) {
      const std::string seq_dir = std::filesystem::is_directory(skitti_dir + "/velodyne")
                                      ? skitti_dir
                                      : skitti_dir + "/sequences/" + g;
      std::vector<Eigen::Isometry3d> poses;
      bool nominal = false;
      std::string error;
      if (!urban_detection::tools::readSemanticKittiPoses(seq_dir, &poses, &nominal, &error)) {
        std::fprintf(stderr, "warning: no time evidence for %s: %s\n", g.c_str(), error.c_str());
        temporal_ok = false;
        continue;
      }
      temporalClasses(frames, g, 0, fold_decision[g], held_out(0), poses, core::TrackerParams(),
                      &over_time, &temporal_stats);
    }
    Scored on_time;
    std::map<std::string, Scored> on_time_by_group;
    for (const std::string& g : groups) {
      const Scored sg =
          score(frames, {g}, 0, &fold_decision[g], held_out(0), ep, &on_time_by_group, &over_time);
      on_time.score += sg.score;
      on_time.all += sg.all;
      on_time.breakdown += sg.breakdown;
    }
    std::printf("%-8s %-18s %-22s | %-43s | %s\n", "+ time",
                pipelines[0]->detector().name().c_str(),
                temporal_ok ? "tracker, poses" : "(some poses missing)", "",
                scoreRow(on_time.score).c_str());
    std::printf("%-8s %-18s %-22s | %-43s | %s\n", "N = 1", pipelines[0]->detector().name().c_str(),
                "", "", scoreRow(on_time.all).c_str());
    std::printf(
        "time as evidence: %zu detections rejected by their scan kept by their track's "
        "class, %zu kept ones given their track's class\n",
        temporal_stats.kept, temporal_stats.reclassed);
    double min_f_time = 1.0;
    for (const std::string& g : groups) {
      min_f_time = std::min(min_f_time, on_time_by_group[g].score.fRate());
    }
    json << "  \"time_as_evidence\": {\"pooled\": " << scoreJson(on_time.score)
         << ", \"pooled_all_objects\": " << scoreJson(on_time.all)
         << ", \"breakdown\": " << on_time.breakdown.json()
         << ", \"min_sequence_f\": " << jsonNumber(min_f_time)
         << ", \"kept_by_track_class\": " << temporal_stats.kept
         << ", \"class_from_track\": " << temporal_stats.reclassed << ", \"sequences\": {";
    for (std::size_t gi = 0; gi < groups.size(); ++gi) {
      json << (gi ? ", " : "") << "\"" << groups[gi]
           << "\": " << scoreJson(on_time_by_group[groups[gi]].score);
    }
    json << "}},\n";
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      std::printf("\n%s, held out, classifier off:\n%s", pipelines[k]->detector().name().c_str(),
                  off_total[k].breakdown.table("  ").c_str());
      std::printf("%s, held out, classifier on:\n%s", pipelines[k]->detector().name().c_str(),
                  on_total[k].breakdown.table("  ").c_str());
    }
    std::printf("%s, held out, classifier on + time:\n%s", pipelines[0]->detector().name().c_str(),
                on_time.breakdown.table("  ").c_str());
    // Pooled confusion matrix of the held-out predictions (hierarchical grid, each fold's
    // decision).
    std::array<std::array<std::size_t, core::kNumObjectCategories>, core::kNumObjectCategories>
        confusion{};
    for (const FrameData& fd : frames) {
      if (fd.augmented) continue;
      const DetectorFrame& d = fd.detectors[0];
      for (std::size_t i = 0; i < d.objects.size(); ++i) {
        if (d.labels[i] == core::ObjectCategory::kUnknown) continue;
        float confidence = 0.0f;
        const int pred = static_cast<int>(
            core::decideClass(d.held_out[i], fold_decision[fd.group], true, &confidence));
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
    // 4. The shipped decision: chosen on the pooled held-out predictions.
    if (auto_threshold) {
      shipped_decision = bestDecision(frames, all_groups, held_out(0), ep, rule, uncertain_band);
    }
  } else if (auto_threshold) {
    std::printf("no leave-one-sequence-out run: threshold 0.5\n");
    shipped_decision.object_threshold = 0.5;
  }

  if (!out_path.empty()) {
    core::ClassifierTrainingParams final_tp = tp;
    final_tp.object_threshold = shipped_decision.object_threshold;
    final_tp.class_thresholds = shipped_decision.class_thresholds;
    final_tp.uncertain_threshold = shipped_decision.uncertain_threshold;
    std::ostringstream desc;
    desc << "random forest, " << tp.trees << " trees, max depth " << tp.max_depth
         << ", min samples " << tp.min_sample_count << ", class balance " << tp.class_balance
         << ", decision " << decision_arg << ", intensity features "
         << (tp.use_intensity ? "on" : "off") << ", fragments " << fragments_arg << "; trained on "
         << frames.size() << " SemanticKITTI scans of sequences";
    for (const std::string& g : groups) desc << " " << g;
    desc << " (hierarchical grid detections, shipped configs); threshold "
         << (auto_threshold ? "from the pooled leave-one-sequence-out F" : "given");
    final_tp.description = desc.str();
    final_tp.training_groups = groups;
    try {
      const core::ObjectClassifierModel m = trainOn(frames, all_groups, final_tp, fp);
      m.save(out_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
    std::printf(
        "\nmodel: %s (thresholds object %.2f, vehicle %.2f, pedestrian %.2f, cyclist %.2f, "
        "uncertain %.2f)\n",
        out_path.c_str(), shipped_decision.object_threshold, shipped_decision.class_thresholds[0],
        shipped_decision.class_thresholds[1], shipped_decision.class_thresholds[2],
        shipped_decision.uncertain_threshold);
  }
  if (!json_path.empty()) {
    if (json.tellp() == 0) {
      json << "{\n  \"dataset\": \"semantic_kitti\",\n  \"scans\": " << frames.size() << ",\n";
    }
    json << "  \"threshold\": " << jsonNumber(shipped_decision.object_threshold)
         << ",\n  \"class_thresholds\": [" << jsonNumber(shipped_decision.class_thresholds[0])
         << ", " << jsonNumber(shipped_decision.class_thresholds[1]) << ", "
         << jsonNumber(shipped_decision.class_thresholds[2])
         << "],\n  \"uncertain_threshold\": " << jsonNumber(shipped_decision.uncertain_threshold)
         << "\n}\n";
    std::ofstream out(json_path);
    out << json.str();
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}
