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
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/evaluation/feature_table.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/evaluation/training.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/calibration.h"

#include "tool_common.h"

namespace core = urban_detection::core;
using core::DecisionRule;
using core::FragmentRule;
using core::jsonNumber;
using core::TrainingDetections;
using core::TrainingFrame;
using core::TrainingScore;
using urban_detection::tools::jsonEscape;

namespace {

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
  core::ObjectFeatureExtractor extractor(fp);

  core::SemanticKittiGroundTruthParams gtp;
  gtp.min_points = 1;  // small objects are trained on; the scoring applies --min-points
  core::SemanticKittiDataset dataset(skitti_dir, gtp);
  if (dataset.size() == 0) {
    std::fprintf(stderr, "error: no labelled scans in %s\n", skitti_dir.c_str());
    return 1;
  }

  // 1-2. Pipeline, features, labels.
  std::vector<TrainingFrame> frames;
  const bool augmenting = augment.person_copies > 0 || augment.vehicle_copies > 0;
  std::map<std::string, std::vector<core::LabelledScan>> scans_of_group;  // for augmentation
  core::FeatureCsvWriter csv(csv_path, "sequence,frame,detector,label,verdict,content");
  if (!csv.ok()) {
    std::fprintf(stderr, "error: cannot write %s\n", csv_path.c_str());
    return 1;
  }
  core::Frame f;
  std::size_t read = 0;
  for (;;) {
    if (max_frames >= 0 && read >= static_cast<std::size_t>(max_frames)) break;
    std::string err;
    const auto status = dataset.next(&f, &err);
    if (status == core::Dataset::Status::kEnd) break;
    ++read;
    if (status == core::Dataset::Status::kSkipped) {
      std::fprintf(stderr, "warning: skipping a scan: %s\n", err.c_str());
      continue;
    }
    TrainingFrame fd =
        core::labelledTrainingFrame(f, dataset, core::frameGroup(f.id, dataset.name()), pipelines,
                                    pipelines.size(), &extractor, fragments);
    for (std::size_t k = 0; k < fd.detectors.size() && csv.enabled(); ++k) {
      const TrainingDetections& d = fd.detectors[k];
      for (std::size_t i = 0; i < d.objects.size(); ++i) {
        csv.row(fd.group + "," + f.id + "," + pipelines[k]->detector().name() + "," +
                    core::toString(d.labels[i]) + "," + core::toString(d.verdicts[i]) + "," +
                    d.contents[i],
                d.features[i]);
      }
    }
    fd.gt_range = core::gtObjectRanges(f.gt, f.cloud);
    if (augmenting) scans_of_group[fd.group].push_back(core::labelledScanOf(f));
    fd.gt = std::move(f.gt);
    frames.push_back(std::move(fd));
  }
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
      core::Frame af;
      af.id = kv.first + "/augmented_" + std::to_string(a);
      af.cloud = made[a].cloud;
      core::buildSemanticKittiGroundTruth(made[a].labels, gtp, &af.gt);
      frames.push_back(core::augmentedTrainingFrame(af.id, kv.first, af.cloud, af.gt, pipelines,
                                                    &extractor, &augmented_rows));
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
      sim_rows = core::addSimTrainingFrames(sim_gt, sim_pcap, static_cast<std::size_t>(sim_frames),
                                            pipelines, &extractor, fragments, &frames);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
    std::printf("simulated drive: %zu training rows\n", sim_rows);
  }
  const std::vector<std::string> groups = core::scoredGroups(frames);
  std::size_t unlabelled = 0;
  const core::LabelCounts label_count = core::trainingLabelCounts(frames, &unlabelled);
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
    std::map<std::string, core::ClassDecision> fold_decision = core::leaveOneSequenceOut(
        &frames, groups, tp, fp, ep, auto_threshold, rule, uncertain_band);
    auto held_out = [&](std::size_t k) { return core::heldOutProbabilities(frames, k); };
    // Each sequence scored with its own fold's decision.
    std::vector<std::map<std::string, TrainingScore>> off(pipelines.size()), on(pipelines.size());
    std::vector<TrainingScore> off_total(pipelines.size()), on_total(pipelines.size());
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      off_total[k] = core::scoreFrames(frames, all_groups, k, nullptr, held_out(k), ep, &off[k]);
      for (const std::string& g : groups) {
        on_total[k].add(
            core::scoreFrames(frames, {g}, k, &fold_decision[g], held_out(k), ep, &on[k]));
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
                    pipelines[k]->detector().name().c_str(),
                    core::decisionText(fold_decision[g]).c_str(),
                    core::trainingScoreRow(off[k][g].score).c_str(),
                    core::trainingScoreRow(on[k][g].score).c_str());
        json << (first ? "" : ", ") << "\"" << g
             << "\": {\"decision\": " << core::decisionJson(fold_decision[g])
             << ", \"off\": " << core::trainingScoreJson(off[k][g].score)
             << ", \"on\": " << core::trainingScoreJson(on[k][g].score) << "}";
        first = false;
      }
      std::printf("%-8s %-18s %-22s | %s | %s\n", "pooled", pipelines[k]->detector().name().c_str(),
                  "", core::trainingScoreRow(off_total[k].score).c_str(),
                  core::trainingScoreRow(on_total[k].score).c_str());
      std::printf("%-8s %-18s %-22s | %s | %s\n", "N = 1", pipelines[k]->detector().name().c_str(),
                  "", core::trainingScoreRow(off_total[k].all).c_str(),
                  core::trainingScoreRow(on_total[k].all).c_str());
      double min_f = 1.0;
      for (const std::string& g : groups) min_f = std::min(min_f, on[k][g].score.fRate());
      json << "}, \"pooled_off\": " << core::trainingScoreJson(off_total[k].score)
           << ", \"pooled_on\": " << core::trainingScoreJson(on_total[k].score)
           << ", \"pooled_off_all_objects\": " << core::trainingScoreJson(off_total[k].all)
           << ", \"pooled_on_all_objects\": " << core::trainingScoreJson(on_total[k].all)
           << ", \"breakdown_off\": " << off_total[k].breakdown.json()
           << ", \"breakdown_on\": " << on_total[k].breakdown.json()
           << ", \"min_sequence_f_on\": " << jsonNumber(min_f) << "}";
    }
    json << "\n  },\n";
    // Time as evidence (hierarchical grid): each held-out sequence in scan order with its poses.
    core::ClassOverride over_time;
    core::TemporalStats temporal_stats;
    const bool temporal_ok = core::temporalEvidence(frames, groups, skitti_dir, fold_decision,
                                                    &over_time, &temporal_stats);
    TrainingScore on_time;
    std::map<std::string, TrainingScore> on_time_by_group;
    for (const std::string& g : groups) {
      on_time.add(core::scoreFrames(frames, {g}, 0, &fold_decision[g], held_out(0), ep,
                                    &on_time_by_group, &over_time));
    }
    std::printf("%-8s %-18s %-22s | %-43s | %s\n", "+ time",
                pipelines[0]->detector().name().c_str(),
                temporal_ok ? "tracker, poses" : "(some poses missing)", "",
                core::trainingScoreRow(on_time.score).c_str());
    std::printf("%-8s %-18s %-22s | %-43s | %s\n", "N = 1", pipelines[0]->detector().name().c_str(),
                "", "", core::trainingScoreRow(on_time.all).c_str());
    std::printf(
        "time as evidence: %zu detections rejected by their scan kept by their track's "
        "class, %zu kept ones given their track's class\n",
        temporal_stats.kept, temporal_stats.reclassed);
    double min_f_time = 1.0;
    for (const std::string& g : groups) {
      min_f_time = std::min(min_f_time, on_time_by_group[g].score.fRate());
    }
    json << "  \"time_as_evidence\": {\"pooled\": " << core::trainingScoreJson(on_time.score)
         << ", \"pooled_all_objects\": " << core::trainingScoreJson(on_time.all)
         << ", \"breakdown\": " << on_time.breakdown.json()
         << ", \"min_sequence_f\": " << jsonNumber(min_f_time)
         << ", \"kept_by_track_class\": " << temporal_stats.kept
         << ", \"class_from_track\": " << temporal_stats.reclassed << ", \"sequences\": {";
    for (std::size_t gi = 0; gi < groups.size(); ++gi) {
      json << (gi ? ", " : "") << "\"" << groups[gi]
           << "\": " << core::trainingScoreJson(on_time_by_group[groups[gi]].score);
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
    const core::CategoryConfusion confusion = core::heldOutConfusion(frames, fold_decision);
    std::printf("\nheld-out confusion (rows: label, columns: prediction), hierarchical grid\n%s",
                core::confusionTable(confusion).c_str());
    json << "  \"confusion\": " << core::confusionJson(confusion) << ",\n";
    // 4. The shipped decision: chosen on the pooled held-out predictions.
    if (auto_threshold) {
      shipped_decision =
          core::bestDecision(frames, all_groups, held_out(0), ep, rule, uncertain_band);
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
      const core::ObjectClassifierModel m = core::trainOn(frames, all_groups, final_tp, fp);
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
