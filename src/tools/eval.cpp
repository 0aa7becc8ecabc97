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
#include "urban_detection/core/evaluation/feature_table.h"
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
  core::TrackingEvalInput source;  // the dataset: one of them (KITTI object: no tracking)
  std::string json_path, detector_arg = "hierarchical";
  std::vector<std::string> configs;
  long max_frames = -1;
  long min_points = 30;
  bool details = false;
  std::string png_dir, features_path, classifier_arg, detections_dir;
  core::PngView png_view;
  bool tracking = false;
  std::string tracker_config;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const urban_detection::tools::OptionArgs arg{argc, argv, &i};
    if (a == "--kitti-object")
      source.kitti_object_dir = arg.value("--kitti-object");
    else if (a == "--semantic-kitti")
      source.semantic_kitti_dir = arg.value("--semantic-kitti");
    else if (a == "--sim")
      source.sim_gt = arg.value("--sim");
    else if (a == "--pcap")
      source.sim_pcap = arg.value("--pcap");
    else if (a == "--calibration")
      source.calibration_path = arg.value("--calibration");
    else if (a == "--cut-angle") {
      const std::string v = arg.value("--cut-angle");
      char* end = nullptr;
      source.cut_angle_deg = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(source.cut_angle_deg)) {
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
      source.kitti_tracking_dir = arg.value("--kitti-tracking");
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
  if ((!source.kitti_object_dir.empty() + !source.semantic_kitti_dir.empty() +
       !source.sim_gt.empty() + !source.kitti_tracking_dir.empty()) != 1 ||
      (tracking && !source.kitti_object_dir.empty())) {
    std::fprintf(stderr, "error: give exactly one dataset\n");
    usage();
    return 2;
  }
  if (source.sim_gt.empty() != source.sim_pcap.empty()) {
    std::fprintf(stderr, "error: --sim GTFILE and --pcap PCAP go together\n");
    usage();
    return 2;
  }
  if (source.sim_gt.empty() && (!source.calibration_path.empty() || source.cut_angle_deg != 0.0)) {
    std::fprintf(stderr, "error: --calibration and --cut-angle apply to --sim only\n");
    return 2;
  }

  // Parameters: in-class defaults, then each --config file in order.
  core::PipelineParams params;
  if (!urban_detection::tools::loadConfigs(configs, &params)) return 2;
  core::ObjectFeatureParams feature_params;
  feature_params.sensor_height_m = params.segmentation.sensor_height_m;
  core::ObjectFeatureExtractor feature_extractor(feature_params);
  std::vector<core::ObjectFeatureVector> feature_rows;
  core::FeatureCsvWriter features_out(features_path, "dataset,frame,detector,verdict,content");
  if (!features_out.ok()) {
    std::fprintf(stderr, "error: cannot write %s\n", features_path.c_str());
    return 1;
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
  if (tracking || !source.kitti_tracking_dir.empty()) {
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
    std::string text, json;
    if (!core::runTrackingEvaluation(tp, source, &text, &json, &tracker_error)) {
      std::fprintf(stderr, "error: %s\n", tracker_error.c_str());
      return 1;
    }
    std::fputs(text.c_str(), stdout);
    return writeJsonFile(json_path, json);
  }

  const std::string& dataset_path = source.path();
  std::unique_ptr<Dataset> dataset;
  try {
    dataset = core::openEvalDataset(source);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
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
  if (!source.kitti_object_dir.empty())
    box_quality.reset(new core::KittiBoxQuality(source.kitti_object_dir, params.box_fitting));
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
    if (classifier &&
        !source.semantic_kitti_dir.empty()) {  // a scan of a sequence the model learned from?
      const auto& seqs = pipelines[0]->classifier().model().trainingGroups();
      trained_on +=
          std::find(seqs.begin(), seqs.end(), f.id.substr(0, f.id.find('/'))) != seqs.end();
    }
    gt_range = core::gtObjectRanges(f.gt, f.cloud);
    // The detector alone (pipeline k): scored before the classifier changes the objects.
    auto detectorAlone = [&](std::size_t k, const urban_detection::LabeledCloud& fg,
                             const std::vector<core::DetectedObject>& objects) {
      scoring[k].addDetectorAlone(f.gt, objects, gt_range, &match);
      if (!features_out.enabled()) return;
      feature_extractor.computeAll(fg, objects, &feature_rows);
      for (std::size_t d = 0; d < objects.size(); ++d) {
        features_out.row(dataset->name() + "," + f.id + "," + pipelines[k]->detector().name() +
                             "," + core::toString(match.verdict[d]) + "," +
                             detectionContent(f, *dataset, objects[d]),
                         feature_rows[d]);
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

  if (frames == 0) {
    std::error_code ec;
    std::fprintf(stderr, "error: %s %s\n", dataset_path.c_str(),
                 fs::exists(dataset_path, ec) ? "holds no frames" : "not found");
    return 1;
  }
  core::EvalRunSummary summary;
  summary.dataset = dataset->name();
  summary.path = dataset_path;
  summary.frames_evaluated = frames - failed;
  summary.frames_failed = failed;
  summary.params = eval_params;
  summary.classifier = classifier;
  summary.classifier_model = params.classifier.model_path;
  summary.configs = configs;
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    summary.detectors.push_back(pipelines[k]->detector().name());
    summary.scoring.push_back(&scoring[k]);
  }
  summary.foreground = fg_composition;
  std::fputs(core::scoreTables(summary).c_str(), stdout);
  if (box_quality) std::fputs(box_quality->tables().c_str(), stdout);
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
  std::fputs(core::diagnosticsLines(summary, details).c_str(), stdout);
  if (!json_path.empty() &&
      writeJsonFile(json_path, core::evalReportJson(summary, rows.str(),
                                                    box_quality ? box_quality->json() : "")) != 0)
    return 1;
  return failed == frames ? 1 : 0;
}
