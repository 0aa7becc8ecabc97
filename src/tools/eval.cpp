// urban_detection_eval: offline F-rate evaluation of the core pipeline (segmentation + object
// detector) on a labelled dataset, scored as in the paper (Sec. 5). No ROS master needed.
//
//   urban_detection_eval (--kitti-object DIR | --semantic-kitti DIR | --sim GTFILE --pcap PCAP)
//                        [--detector hierarchical|kdtree|both] [--config FILE]...
//                        [--json FILE] [--max-frames N] [--min-points N] [--details]
//   urban_detection_eval --tracking (--sim GTFILE --pcap PCAP | --semantic-kitti DIR |
//                        --kitti-tracking DIR)  (CLEAR-MOT
//                        of the tracker after the pipeline; rules in tracking_eval.h)
//
// The ground-truth rules of each dataset (KITTI object, SemanticKITTI, simulated drive) are
// documented in eval_datasets.h.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/detection_scoring.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/evaluation/external_detections.h"
#include "urban_detection/core/evaluation/frame_picture.h"
#include "urban_detection/core/evaluation/kitti_box_quality.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/evaluation/tracking_eval.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/kitti_io.h"

#include "tool_common.h"

namespace core = urban_detection::core;
namespace fs = std::filesystem;

using core::Dataset;
using core::detectionContent;
using core::Frame;
using core::jsonNumber;
using core::KittiObjectDataset;
using core::SemanticKittiDataset;
using core::SimulatedDriveDataset;
using urban_detection::tools::jsonEscape;

namespace {

// Writes `text` to `path` (nothing when `path` is empty). Returns the process exit code.
int writeJsonFile(const std::string& path, const std::string& text) {
  if (path.empty()) return 0;
  std::ofstream out(path);
  out << text;
  if (!out) {
    std::fprintf(stderr, "error: cannot write %s\n", path.c_str());
    return 1;
  }
  return 0;
}

void printMot(const char* what, const core::ClearMotResult& r) {
  std::printf(
      "%-28s frames %4zu  GT %6zu  GT tracks %4zu  MOTA %.3f  MOTP %.3f m  recall %.3f  "
      "precision %.3f  FN %zu  FP %zu  IDSW %zu (%.2f per 100 GT tracks)  frag %zu  "
      "MT %zu  PT %zu  ML %zu\n",
      what, r.frames, r.gt, r.gt_tracks, r.mota(), r.motp_m(), r.recall(), r.precision(), r.misses,
      r.false_positives, r.id_switches, r.idSwitchesPer100GtTracks(), r.fragmentations,
      r.mostly_tracked, r.partially_tracked, r.mostly_lost);
}

// --tracking on a simulated drive. Returns the process exit code.
int runSimTracking(const core::TrackingEvalParams& p, const std::string& gt_path,
                   const std::string& pcap_path, const core::Calibration& calibration,
                   double cut_angle_deg, const std::string& json_path) {
  core::SimTrackingResult res;
  std::string error;
  if (!core::evaluateSimTracking(p, gt_path, pcap_path, calibration, cut_angle_deg, &res, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  const std::size_t frames = res.frames, skipped = res.skipped;
  const core::ClearMotResult &r = res.tracker, &d = res.detector, &o = res.oracle;
  const std::vector<double>&speed_error = res.speed_error, &static_speed = res.static_speed,
        &update_ms = res.update_ms;
  std::printf(
      "tracking on the simulated drive (%zu revolutions, %zu skipped), detector %s, "
      "classifier %s\n",
      frames, skipped, p.params.detector.c_str(), p.params.classifier.enabled ? "on" : "off");
  printMot("tracker (confirmed tracks)", r);
  std::printf(
      "%-28s recall %.3f  precision %.3f  (MOTA <= recall of the tracks; the detector "
      "bounds it unless coasting fills its gaps)\n",
      "detector alone", d.recall(), d.precision());
  printMot("tracker on GT boxes", o);
  std::printf(
      "speed error of matched moving cars/vans: median %.3f m/s, p90 %.3f m/s "
      "(%zu matches); speed of matched parked cars/vans: median %.3f m/s, p90 %.3f m/s "
      "(%zu)\n",
      core::median(speed_error), core::percentile(speed_error, 0.9), speed_error.size(),
      core::median(static_speed), core::percentile(static_speed, 0.9), static_speed.size());
  std::printf(
      "tracker update: median %.4f ms, max %.4f ms per revolution (wall clock, with "
      "the pipeline around it)\n",
      core::median(update_ms),
      update_ms.empty() ? 0.0 : *std::max_element(update_ms.begin(), update_ms.end()));
  return writeJsonFile(json_path, core::simTrackingJson(res, pcap_path));
}

// --kitti-tracking DIR. Returns the process exit code.
int runKittiTracking(const core::TrackingEvalParams& p, const std::string& dir,
                     const std::string& json_path) {
  core::KittiTrackingEvalResult res;
  std::string error;
  if (!core::evaluateKittiTracking(p, dir, &res, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  const std::size_t sequences = res.sequences, frames = res.frames;
  const core::ClearMotResult& r = res.tracker;
  std::printf("tracking on KITTI tracking (%zu sequences, %zu frames), sensor frame (no poses)\n",
              sequences, frames);
  printMot("tracker (confirmed tracks)", r);
  return writeJsonFile(json_path, core::kittiTrackingJson(res, dir));
}

// --tracking --semantic-kitti DIR. Returns the process exit code.
int runSemanticKittiTracking(const core::TrackingEvalParams& p, const std::string& dir,
                             const std::string& json_path) {
  core::SemanticKittiTrackingEvalResult res;
  std::string error;
  if (!core::evaluateSemanticKittiTracking(p, dir, &res, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  const std::size_t frames = res.frames;
  const bool any_nominal = res.nominal_tr;
  const core::ClearMotResult &r = res.tracker, &d = res.detector;
  const auto& per_sequence = res.per_sequence;
  const std::vector<double>& update_ms = res.update_ms;
  std::printf(
      "tracking on SemanticKITTI (%zu sequences, %zu scans), world frame (poses.txt%s), "
      "detector %s, classifier %s, min GT points %zu\n",
      per_sequence.size(), frames, any_nominal ? ", nominal Tr" : ", calib Tr",
      p.params.detector.c_str(), p.params.classifier.enabled ? "on" : "off", p.min_gt_points);
  for (const auto& s : per_sequence) printMot(("  sequence " + s.first).c_str(), s.second);
  printMot("tracker, pooled", r);
  std::printf("%-28s recall %.3f  precision %.3f\n", "detector alone", d.recall(), d.precision());
  std::printf("tracker update: median %.4f ms per scan\n", core::median(update_ms));
  return writeJsonFile(json_path, core::semanticKittiTrackingJson(res, dir, p.min_gt_points));
}

// The box-quality tables on stdout.
void printBoxQuality(const core::KittiBoxQuality& q) {
  const std::pair<const char*, const std::vector<core::BoxQualitySample>*> tables[] = {
      {"matched detections (the pipeline)", &q.detections()},
      {"box fitting alone, on each labelled object's own points", &q.labelledPoints()}};
  for (const auto& t : tables) {
    std::printf(
        "\nbox quality (bird's-eye view) vs KITTI 3-D boxes, %s:\n"
        "%-11s %-9s %8s %8s %10s %12s %9s %10s\n",
        t.first, "class", "range", "labelled", "matched", "centre_m", "heading_deg", "IoU_med",
        "IoU>=0.5");
    for (const core::KittiBoxQuality::Row& r : core::KittiBoxQuality::rows()) {
      const core::BoxQualitySummary s =
          core::summarize(*t.second, r.category, r.min_m, r.max_m, 0.5);
      if (s.labelled == 0) continue;
      std::printf("%-11s %-9s %8zu %8zu %10.3f %12.2f %9.3f %10.3f\n", core::toString(r.category),
                  r.name.c_str(), s.labelled, s.matched, s.median_center_error_m,
                  s.median_heading_error_deg, s.median_iou, s.share_iou_at_least);
    }
  }
}

void usage() {
  std::fprintf(
      stderr,
      "usage: urban_detection_eval (--kitti-object DIR | --semantic-kitti DIR |\n"
      "                             --sim GTFILE --pcap PCAP [--calibration FILE]\n"
      "                             [--cut-angle DEG])\n"
      "         [--detector hierarchical|kdtree|both] [--config FILE]... [--json FILE]\n"
      "         [--max-frames N] [--min-points N] [--details]\n"
      "         [--features CSV] [--classifier MODEL|off]\n"
      "         [--detections DIR]\n"
      "  --sim GTFILE    ground-truth file of urban_detection_simulate (--gt), with the pcap it\n"
      "                  wrote (--pcap); --calibration is the one the drive was simulated with\n"
      "                  (default: nominal HDL-64E S2), --cut-angle the revolution cut [deg]\n"
      "  --config FILE   a stage's YAML file (config/*.yaml; repeatable) (auto-detected by its\n"
      "                  keys), or a combined file with `segmentation:` / `detection:` maps;\n"
      "                  later files override earlier ones. Without it the in-class defaults\n"
      "                  (mirrored by config/*.yaml) are used.\n"
      "  --features CSV  write the object classifier's features of every detection (before the\n"
      "                  classifier) with its verdict and content\n"
      "  --classifier MODEL|off  the object classifier after the detector (default: classifier/\n"
      "                  of the config, e.g. config/classification.yaml's shipped model; else "
      "off)\n"
      "  --detections DIR  score another system's output instead of this package's detectors:\n"
      "                  per frame a file of one uint32 per input point, the point's instance\n"
      "                  (0 = none), at DIR/<frame>.label (SemanticKITTI: DIR/SEQ/NNNNNN.label\n"
      "                  or DIR/sequences/SEQ/predictions/NNNNNN.label; KITTI object:\n"
      "                  DIR/NNNNNN.label; simulated drive: DIR/revN.label)\n"
      "  --min-points N  objects and detections with fewer than N points count only when\n"
      "                  they match each other (SemanticKITTI's panoptic rule; default 30);\n"
      "                  the all-objects figure (N = 1) is printed beside it\n"
      "  --details       print every missed object and false detection with its cause\n"
      "  --png DIR       write a top view per frame (first detector): ground truth left,\n"
      "                  detections right; yellow boxes missed objects, red false detections\n"
      "  --png-view CX,CY,HALF_M   the square shown [m] (default 0,0,30)\n"
      "  --tracking      with --sim, --semantic-kitti or --kitti-tracking: the tracker after\n"
      "                  the pipeline, scored with CLEAR-MOT\n"
      "  --tracker-config FILE  the tracker's parameters (config/object_tracker.yaml's\n"
      "                  tracker: map; default: the in-class defaults it mirrors)\n"
      "  --kitti-tracking DIR  the same on the KITTI tracking layout (velodyne/<seq>/, label_02/,\n"
      "                  calib/); rules in core/evaluation/tracking_eval.h, docs/tracking.md\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string kitti_dir, skitti_dir, sim_gt, sim_pcap, calibration_path, json_path,
      detector_arg = "hierarchical";
  double cut_angle_deg = 0.0;
  std::vector<std::string> configs;
  long max_frames = -1;
  long min_points = 30;
  bool details = false;
  std::string png_dir, features_path, classifier_arg, detections_dir;
  core::PngView png_view;
  bool tracking = false;
  std::string kitti_tracking_dir, tracker_config;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const urban_detection::tools::OptionArgs arg{argc, argv, &i};
    if (a == "--kitti-object")
      kitti_dir = arg.value("--kitti-object");
    else if (a == "--semantic-kitti")
      skitti_dir = arg.value("--semantic-kitti");
    else if (a == "--sim")
      sim_gt = arg.value("--sim");
    else if (a == "--pcap")
      sim_pcap = arg.value("--pcap");
    else if (a == "--calibration")
      calibration_path = arg.value("--calibration");
    else if (a == "--cut-angle") {
      const std::string v = arg.value("--cut-angle");
      char* end = nullptr;
      cut_angle_deg = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(cut_angle_deg)) {
        std::fprintf(stderr, "error: --cut-angle needs a number of degrees, got '%s'\n", v.c_str());
        return 2;
      }
    } else if (a == "--detector")
      detector_arg = arg.value("--detector");
    else if (a == "--config")
      configs.push_back(arg.value("--config"));
    else if (a == "--json")
      json_path = arg.value("--json");
    else if (a == "--max-frames")
      max_frames = arg.count("--max-frames");
    else if (a == "--min-points")
      min_points = arg.count("--min-points");
    else if (a == "--details")
      details = true;
    else if (a == "--features")
      features_path = arg.value("--features");
    else if (a == "--classifier")
      classifier_arg = arg.value("--classifier");
    else if (a == "--detections")
      detections_dir = arg.value("--detections");
    else if (a == "--png")
      png_dir = arg.value("--png");
    else if (a == "--tracking")
      tracking = true;
    else if (a == "--kitti-tracking")
      kitti_tracking_dir = arg.value("--kitti-tracking");
    else if (a == "--tracker-config")
      tracker_config = arg.value("--tracker-config");
    else if (a == "--png-view") {
      const std::string v = arg.value("--png-view");
      if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &png_view.cx, &png_view.cy, &png_view.half_m) !=
              3 ||
          !(png_view.half_m > 0.0 && png_view.half_m <= 100.0)) {
        std::fprintf(stderr, "error: --png-view needs CX,CY,HALF_M (metres), got '%s'\n",
                     v.c_str());
        return 2;
      }
      png_view.px_per_m = std::min(40.0, 600.0 / png_view.half_m);
    } else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "error: unknown argument '%s'\n", a.c_str());
      usage();
      return 2;
    }
  }
  if ((!kitti_dir.empty() + !skitti_dir.empty() + !sim_gt.empty() + !kitti_tracking_dir.empty()) !=
          1 ||
      (tracking && !kitti_dir.empty())) {
    std::fprintf(stderr, "error: give exactly one dataset\n");
    usage();
    return 2;
  }
  if (sim_gt.empty() != sim_pcap.empty()) {
    std::fprintf(stderr, "error: --sim GTFILE and --pcap PCAP go together\n");
    usage();
    return 2;
  }
  if (sim_gt.empty() && (!calibration_path.empty() || cut_angle_deg != 0.0)) {
    std::fprintf(stderr, "error: --calibration and --cut-angle apply to --sim only\n");
    return 2;
  }

  // Parameters: in-class defaults, then each --config file in order.
  core::PipelineParams params;
  if (!urban_detection::tools::loadConfigs(configs, &params)) return 2;
  std::FILE* features_out = nullptr;
  core::ObjectFeatureParams feature_params;
  feature_params.sensor_height_m = params.segmentation.sensor_height_m;
  core::ObjectFeatureExtractor feature_extractor(feature_params);
  std::vector<core::ObjectFeatureVector> feature_rows;
  if (!features_path.empty()) {
    features_out = std::fopen(features_path.c_str(), "w");
    if (!features_out) {
      std::fprintf(stderr, "error: cannot write %s\n", features_path.c_str());
      return 1;
    }
    std::fprintf(features_out, "dataset,frame,detector,verdict,content");
    for (int k = 0; k < core::kNumObjectFeatures; ++k) {
      std::fprintf(features_out, ",%s", core::featureName(k));
    }
    std::fprintf(features_out, "\n");
  }

  // The classifier: the config's, replaced or switched off by --classifier.
  if (classifier_arg == "off") {
    params.classifier.enabled = false;
  } else if (!classifier_arg.empty()) {
    params.classifier.enabled = true;
    params.classifier.model_path = classifier_arg;
  }
  if (!detections_dir.empty() && params.classifier.enabled) {
    if (!classifier_arg.empty()) {
      std::fprintf(stderr, "error: --classifier does not apply to --detections\n");
      return 2;
    }
    params.classifier.enabled = false;
  }
  const bool classifier = params.classifier.enabled;

  // One pipeline per detector (the first one's segmentation serves all).
  std::vector<std::unique_ptr<core::Pipeline>> pipelines;
  core::ExternalDetections* external = nullptr;
  try {
    auto add = [&](std::unique_ptr<core::ObjectDetector> detector) {
      params.detector = detector->name();
      pipelines.emplace_back(new core::Pipeline(params, std::move(detector)));
    };
    if (!detections_dir.empty()) {
      if (!fs::is_directory(detections_dir)) {
        std::fprintf(stderr, "error: --detections %s is not a directory\n", detections_dir.c_str());
        return 1;
      }
      external = new core::ExternalDetections(detections_dir);
      add(std::unique_ptr<core::ObjectDetector>(external));
    } else if (detector_arg == "hierarchical" || detector_arg == "both") {
      add(std::make_unique<core::HierarchicalGridDetector>(params.hierarchical_grid));
    }
    if (detector_arg == "kdtree" || detector_arg == "both") {
      add(std::make_unique<core::KdTreeDetector>(params.kdtree));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (pipelines.empty()) {
    std::fprintf(stderr, "error: --detector must be hierarchical, kdtree or both\n");
    return 2;
  }
  if (tracking || !kitti_tracking_dir.empty()) {
    core::TrackingEvalParams tp;
    tp.params = pipelines[0]->params();
    tp.min_gt_points = static_cast<std::size_t>(min_points);
    if (max_frames >= 0) tp.max_frames = static_cast<std::size_t>(max_frames);
    std::string tracker_error;
    if (!tracker_config.empty() &&
        !core::loadTrackerParamsYaml(tracker_config, &tp.params.tracker, &tracker_error)) {
      std::fprintf(stderr, "error: %s\n", tracker_error.c_str());
      return 2;
    }
    if (!kitti_tracking_dir.empty()) {
      return runKittiTracking(tp, kitti_tracking_dir, json_path);
    }
    if (!skitti_dir.empty()) {
      return runSemanticKittiTracking(tp, skitti_dir, json_path);
    }
    try {
      return runSimTracking(tp, sim_gt, sim_pcap, core::loadCalibration(calibration_path),
                            cut_angle_deg, json_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
  }

  std::unique_ptr<Dataset> dataset;
  std::string dataset_path;
  if (!kitti_dir.empty()) {
    core::KittiGroundTruthParams p;
    p.min_points = 1;  // the evaluator applies --min-points (small objects count when matched)
    dataset.reset(new KittiObjectDataset(kitti_dir, p));
    dataset_path = kitti_dir;
  } else if (!skitti_dir.empty()) {
    core::SemanticKittiGroundTruthParams p;
    p.min_points = 1;  // the evaluator applies --min-points (small objects count when matched)
    dataset.reset(new SemanticKittiDataset(skitti_dir, p));
    dataset_path = skitti_dir;
  } else {
    core::SimulatedGroundTruthParams p;
    p.min_points = 1;  // the evaluator applies --min-points (small objects count when matched)
    try {
      const core::Calibration cal = core::loadCalibration(calibration_path);
      dataset.reset(new SimulatedDriveDataset(sim_gt, sim_pcap, cal, cut_angle_deg, p));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
    dataset_path = sim_pcap;
  }
  const std::size_t max_frames_n =
      max_frames >= 0 ? static_cast<std::size_t>(max_frames) : static_cast<std::size_t>(-1);

  if (min_points < 1) {
    std::fprintf(stderr, "error: --min-points must be at least 1\n");
    return 2;
  }
  core::EvaluationParams eval_params;
  eval_params.min_points = static_cast<std::size_t>(min_points);
  std::vector<core::DetectorScoring> scoring(pipelines.size(), core::DetectorScoring(eval_params));
  std::vector<float> gt_range;
  std::map<std::string, std::size_t> fg_composition;   // foreground points by dataset class
  std::unique_ptr<core::KittiBoxQuality> box_quality;  // first detector's
  if (!kitti_dir.empty())
    box_quality.reset(new core::KittiBoxQuality(kitti_dir, params.box_fitting));
  std::ostringstream rows;
  bool first_row = true;
  std::size_t failed = 0, frames = 0;
  Frame f;
  core::FrameMatch match;
  if (details) std::printf("per-object details (missed GT objects, false detections):\n");
  std::size_t trained_on = 0;  // scored scans of sequences the classifier was trained on
  while (frames < max_frames_n) {
    std::string err;
    const Dataset::Status status = dataset->next(&f, &err);
    if (status == Dataset::Status::kEnd) break;
    ++frames;
    if (status == Dataset::Status::kSkipped) {
      std::fprintf(stderr, "warning: skipping frame %zu: %s\n", frames - 1, err.c_str());
      ++failed;
      continue;
    }
    if (external && !external->load(f, &err)) {
      std::fprintf(stderr, "warning: skipping frame %s: %s\n", f.id.c_str(), err.c_str());
      ++failed;
      continue;
    }
    if (classifier && !skitti_dir.empty()) {  // a scan of a sequence the model learned from?
      const auto& seqs = pipelines[0]->classifier().model().trainingGroups();
      trained_on +=
          std::find(seqs.begin(), seqs.end(), f.id.substr(0, f.id.find('/'))) != seqs.end();
    }
    gt_range = core::gtObjectRanges(f.gt, f.cloud);
    // The detector alone (pipeline k): scored before the classifier changes the objects.
    auto detectorAlone = [&](std::size_t k, const urban_detection::LabeledCloud& fg,
                             const std::vector<core::DetectedObject>& objects) {
      scoring[k].addDetectorAlone(f.gt, objects, gt_range, &match);
      if (!features_out) return;
      feature_extractor.computeAll(fg, objects, &feature_rows);
      for (std::size_t d = 0; d < objects.size(); ++d) {
        std::fprintf(features_out, "%s,%s,%s,%s,%s", dataset->name().c_str(), f.id.c_str(),
                     pipelines[k]->detector().name().c_str(), core::toString(match.verdict[d]),
                     detectionContent(f, *dataset, objects[d]).c_str());
        for (const float v : feature_rows[d]) std::fprintf(features_out, ",%.6g", v);
        std::fprintf(features_out, "\n");
      }
    };
    // The first pipeline runs the whole chain; the others take its foreground.
    const core::PipelineResult& first = pipelines[0]->process(
        f.cloud,
        [&](const urban_detection::LabeledCloud& fg,
            const std::vector<core::DetectedObject>& objects) { detectorAlone(0, fg, objects); });
    const std::vector<core::SegmentClass>& seg = first.labels;
    const urban_detection::LabeledCloud& foreground = first.foreground;
    // What the foreground is made of (dataset classes): shows walls or vegetation leaking in.
    for (const auto& p : foreground) {
      if (p.index >= f.point_class.size()) continue;
      const std::int32_t g = f.gt.object_of_point[p.index];
      ++fg_composition[g >= 0 ? "gt_object:" + f.gt.objects[g].label
                              : dataset->className(f.point_class[p.index])];
    }
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      const core::PipelineResult& r =
          k == 0 ? first
                 : pipelines[k]->detect(foreground,
                                        [&](const urban_detection::LabeledCloud& fg,
                                            const std::vector<core::DetectedObject>& objects) {
                                          detectorAlone(k, fg, objects);
                                        });
      const std::vector<core::DetectedObject>& objects = r.objects;
      scoring[k].add(f, *dataset, seg, objects, r.rejected, gt_range, classifier,
                     pipelines[k]->detector().name(), details ? stdout : nullptr, &match);
      if (box_quality && k == 0) box_quality->addFrame(f.id, f.cloud, f.gt, objects, match);
      if (!png_dir.empty() && k == 0) {
        std::string id = f.id;
        std::replace(id.begin(), id.end(), '/', '_');
        core::writeFramePng(png_dir + "/" + dataset->name() + "_" + id + ".png", f, foreground,
                            objects, match, png_view);
      }
      rows << (first_row ? "" : ",\n") << "    {\"frame\": \"" << jsonEscape(f.id)
           << "\", \"detector\": \"" << pipelines[k]->detector().name() << "\", "
           << core::scoreJsonMembers(match.score) << "}";
      first_row = false;
    }
  }

  if (features_out) std::fclose(features_out);
  if (frames == 0) {
    std::error_code ec;
    std::fprintf(stderr, "error: %s %s\n", dataset_path.c_str(),
                 fs::exists(dataset_path, ec) ? "holds no frames" : "not found");
    return 1;
  }
  std::printf(
      "\nsmall objects (< %ld points) count only when matched (--min-points %ld); N = 1: "
      "every object counts\n",
      min_points, min_points);
  std::printf("%-15s %-18s %-11s %6s %5s %5s %5s %5s %9s %7s %7s\n", "dataset", "detector",
              "classifier", "frames", "NO", "MO", "FO", "ign", "precision", "recall", "F-rate");
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    const std::pair<const char*, const core::DetectionEvaluator*> rows_k[] = {
        {classifier ? "on" : "off", &scoring[k].scored()},
        {classifier ? "on, N=1" : "off, N=1", &scoring[k].allObjects()},
        {"off", &scoring[k].detectorAlone()},
        {"off, N=1", &scoring[k].detectorAloneAllObjects()}};
    for (int r = 0; r < (classifier ? 4 : 2); ++r) {
      const core::DetectionScore& t = rows_k[r].second->total();
      std::printf("%-15s %-18s %-11s %6zu %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
                  dataset->name().c_str(), pipelines[k]->detector().name().c_str(), rows_k[r].first,
                  frames - failed, t.no, t.mo, t.fo, t.ignored, t.precision(), t.recall(),
                  t.fRate());
    }
  }
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    std::printf("\n%s, classifier %s:\n%s", pipelines[k]->detector().name().c_str(),
                classifier ? "on" : "off", scoring[k].breakdown().table("  ").c_str());
    if (classifier) {
      std::printf("%s, classifier off (the detector alone):\n%s",
                  pipelines[k]->detector().name().c_str(),
                  scoring[k].breakdownDetectorAlone().table("  ").c_str());
    }
  }
  std::printf("\n");
  for (std::size_t k = 0; k < pipelines.size() && scoring[k].byGroup().size() > 1; ++k) {
    for (const auto& g : scoring[k].byGroup()) {
      const core::DetectionScore& t = g.second;
      std::printf("%-15s %-18s %6s %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
                  (dataset->name() + ":" + g.first).c_str(),
                  pipelines[k]->detector().name().c_str(), "", t.no, t.mo, t.fo, t.ignored,
                  t.precision(), t.recall(), t.fRate());
    }
  }
  if (box_quality) printBoxQuality(*box_quality);
  std::printf("classifier: %s\n",
              classifier ? params.classifier.model_path.c_str() : "off (objects unclassified)");
  if (trained_on > 0) {
    std::string seqs;
    for (const std::string& g : pipelines[0]->classifier().model().trainingGroups())
      seqs += " " + g;
    std::printf(
        "note: %zu of the %zu scans scored are of sequences the classifier was trained on "
        "(%s): the classifier-on figures are optimistic there; held-out figures: "
        "urban_detection_train_classifier's leave-one-sequence-out run (scripts/run eval)\n",
        trained_on, frames - failed, seqs.c_str() + 1);
  }
  std::printf("foreground points by class: %s\n", core::countsJson(fg_composition).c_str());
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    if (classifier) {
      std::printf(
          "%s: classifier rejected by content %s; matched objects' class "
          "(truth->given) %s\n",
          pipelines[k]->detector().name().c_str(),
          core::countsJson(scoring[k].classifierRejected()).c_str(),
          core::countsJson(scoring[k].classPairs()).c_str());
    }
    std::printf("%s: missed by cause %s; false by content %s\n",
                pipelines[k]->detector().name().c_str(),
                core::countsJson(scoring[k].diagnostics().missed_by_cause).c_str(),
                core::countsJson(scoring[k].diagnostics().false_by_class).c_str());
    if (details) {
      std::printf("%s: false parts of GT objects by kind %s\n",
                  pipelines[k]->detector().name().c_str(),
                  core::countsJson(scoring[k].diagnostics().false_fragments).c_str());
    }
  }

  if (!json_path.empty()) {
    std::ofstream out(json_path);
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
    out << "{\n  \"dataset\": \"" << dataset->name() << "\",\n  \"path\": \""
        << jsonEscape(dataset_path) << "\",\n  \"frames_evaluated\": " << frames - failed
        << ",\n  \"frames_failed\": " << failed
        << ",\n  \"min_iou\": " << jsonNumber(eval_params.min_iou)
        << ",\n  \"min_points\": " << min_points << ",\n  \"classifier\": "
        << (classifier ? "\"" + jsonEscape(params.classifier.model_path) + "\"" : "null")
        << ",\n  \"configs\": [";
    for (std::size_t c = 0; c < configs.size(); ++c) {
      out << (c ? ", " : "") << "\"" << jsonEscape(configs[c]) << "\"";
    }
    out << "],\n  \"detectors\": [";
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      out << (k ? ", " : "") << "\"" << pipelines[k]->detector().name() << "\"";
    }
    out << "],\n  \"frames\": [\n" << rows.str() << "\n  ],\n";
    out << "  \"overall\": {" << core::scoreJsonMembers(scoring[0].scored().total()) << "},\n";
    out << "  \"by_detector\": {";
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      out << (k ? ",\n" : "\n") << "    \"" << pipelines[k]->detector().name() << "\": {"
          << scoring[k].jsonMembers() << "}";
    }
    out << "\n  },\n  \"foreground_points_by_class\": " << core::countsJson(fg_composition);
    if (box_quality) out << ",\n  \"box_quality\": " << box_quality->json();
    out << "\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: writing %s failed\n", json_path.c_str());
      return 1;
    }
  }
  return failed == frames ? 1 : 0;
}
