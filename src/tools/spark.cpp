// urban_detection_spark: 2-D semantic segmentation transferred to 3-D point clouds (the
// second seed paper, "SPARK").
//
//   urban_detection_spark run --cloud CLOUD --path PATH.json (--model NET.onnx | --masks DIR |
//                             --render-only) --out DIR [options]
//       Offline workflow (paper Sec. 3.2-3.5): orthographic virtual camera along the path ->
//       images + a JSON record per image, network on each image, every n-th mask pixel cast
//       back into the cloud (first point hit, z-buffer of point splats), DBSCAN per class ->
//       DIR/instances.json; optional per-instance PCD sub-clouds and the cloud with classes cut.
//       --render-only stops after the images (for an external segmenter, as the paper's Python
//       script); --masks DIR then casts its label images DIR/img_NNNNN.png back (8-bit class id
//       per pixel, 255 = no class).
//   urban_detection_spark synthetic --out DIR
//       Writes the coloured synthetic street (scene.pcd, x y z rgb) and a path (path.json) to try
//       `run` with the colour network of test/spark_colour_model.py.
//   urban_detection_spark kitti --kitti DIR (--model NET | --model-config YAML | --box-oracle)
//       The network on KITTI object frames (image_2, calib, velodyne, label_2). Per
//       labelled object in the camera view: its camera category vs. the KITTI type (Car, Van,
//       Truck -> vehicle; Pedestrian, Person_sitting -> pedestrian; Cyclist -> cyclist) by range;
//       then the precision of the in-view detections (hierarchical grid + LiDAR classifier) with
//       LiDAR classes only and fused (veto only, veto + relabel). Table + --json FILE.
//       --box-oracle paints the label_2 2-D boxes as the "segmentation" (no network): what
//       projection, occlusion handling and voting lose with a perfect 2-D input.
//   Model options of all modes: --model NET (any cv::dnn::readNet file), --model-config YAML
//   (the nodelet's config, e.g. config/spark_enet_cityscapes.yaml) with --model-dir DIR for its
//   relative files, --classes, --colours, --input-size WxH, --mean, --scale, --bgr.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "tool_common.h"
#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/spark/kitti_spark_eval.h"
#include "urban_detection/core/spark/spark_capture.h"
#include "urban_detection/core/spark/spark_instances.h"
#include "urban_detection/core/spark/spark_io.h"
#include "urban_detection/core/spark/spark_scene.h"
#include "urban_detection/core/spark/spark_segmenter.h"
#include "urban_detection/ros/object_conversions.h"

namespace ud = urban_detection;
namespace core = urban_detection::core;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

[[noreturn]] void fail(const std::string& msg) {
  std::fprintf(stderr, "error: %s\n", msg.c_str());
  std::exit(1);
}

// The camera model: config/image_label_transfer.yaml's settings (--model-config, read and checked
// as the nodelet reads them: core::CameraStageParams), then the command line's overrides.
struct ModelOptions {
  core::CameraStageParams stage;
  core::CameraModel model;   // after loadModel()
  std::string colours_file;  // one "r g b" line per class (masks as colour PNGs)
};

// --model-config wherever it stands, so every other option overrides the file.
ModelOptions readModelConfig(int argc, char** argv) {
  ModelOptions mo;
  std::string error;
  for (int i = 2; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--model-config" &&
        !core::loadCameraStageParamsYaml(argv[i + 1], &mo.stage, &error))
      fail(error);
  }
  return mo;
}

// Common model options (core::applyCameraModelOption); true when argv[*i] was one of them.
bool modelOption(int argc, char** argv, int* i, ModelOptions* m) {
  std::string error;
  const int r = core::applyCameraModelOption(
      argv[*i], [&] { return ud::tools::optionValue(argc, argv, i, argv[*i]); }, &m->stage,
      &m->colours_file, &error);
  if (r < 0) fail(error);
  return r > 0;
}

// The nodelet's model loading (core::loadCameraModel); the colours file is also found in the
// model folder.
void loadModel(ModelOptions* m, bool load_network) {
  std::string error;
  if (!core::loadCameraModel(m->stage.model, load_network, &m->model, &error)) fail(error);
  m->colours_file = core::inModelDir(m->stage.model.dir, m->colours_file);
}

// ---------------------------------------------------------------------------------------------
int runOffline(int argc, char** argv) {
  std::string cloud_path, path_json, out_dir;
  ModelOptions mo = readModelConfig(argc, argv);
  core::SparkParams sp;
  std::vector<std::string> cut;
  bool instance_pcd = false, write_images = true, write_masks = false, render_only = false;
  std::string masks_dir;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* o) { return ud::tools::optionValue(argc, argv, &i, o); };
    auto count = [&](const char* o) {
      return static_cast<int>(ud::tools::optionCount(argc, argv, &i, o));
    };
    if (modelOption(argc, argv, &i, &mo)) continue;
    if (a == "--cloud")
      cloud_path = value("--cloud");
    else if (a == "--path")
      path_json = value("--path");
    else if (a == "--out")
      out_dir = value("--out");
    else if (a == "--stride")
      sp.mask_stride_px = std::max(1, count("--stride"));
    else if (a == "--min-votes")
      sp.min_point_votes = count("--min-votes");
    else if (a == "--eps")
      sp.dbscan_eps_m = std::stod(value("--eps"));
    else if (a == "--min-points")
      sp.dbscan_min_points = count("--min-points");
    else if (a == "--min-instance-points")
      sp.min_instance_points = count("--min-instance-points");
    else if (a == "--box-margin")
      sp.box_margin_m = std::stod(value("--box-margin"));
    else if (a == "--cut")
      cut = core::splitCommaList(value("--cut"));
    else if (a == "--instance-pcd")
      instance_pcd = true;
    else if (a == "--no-images")
      write_images = false;
    else if (a == "--write-masks")
      write_masks = true;
    else if (a == "--render-only")
      render_only = true;
    else if (a == "--masks")
      masks_dir = value("--masks");
    else
      fail("unknown option " + a + " (see the file comment of src/tools/spark.cpp)");
  }
  if (cloud_path.empty() || path_json.empty() || out_dir.empty())
    fail("run needs --cloud, --path, --out and one of --model, --masks, --render-only");
  if (render_only + !masks_dir.empty() + !mo.stage.model.network.model_path.empty() != 1)
    fail("run needs exactly one of --model NET.onnx, --masks DIR and --render-only");
  if (render_only && !write_images) fail("--render-only writes images; drop --no-images");
  if (!(sp.dbscan_eps_m > 0.0)) fail("--eps must be > 0");
  std::string error;
  core::CapturePathParams cp;
  if (!core::readCapturePathJson(path_json, &cp, &error)) fail(error);
  loadModel(&mo, !mo.stage.model.network.model_path.empty());
  core::SegmentationModel& model = mo.model.network;
  const std::vector<std::string>& names = mo.model.names;
  sp.kept_classes = mo.model.kept_classes;
  ud::CloudXYZIRT cloud;
  std::vector<cv::Vec3b> rgb, colours;
  if (!core::readSparkCloud(cloud_path, &cloud, &rgb, &error)) fail(error);
  if (cp.colour == "rgb" && rgb.empty())
    std::fprintf(stderr,
                 "warning: %s has no rgb field; points are drawn grey (set \"colour\": "
                 "\"intensity\" or \"height\" in the path file)\n",
                 cloud_path.c_str());
  core::pointColours(cloud, rgb, cp, &colours);
  fs::create_directories(out_dir + "/images");
  if (write_masks) {
    fs::create_directories(out_dir + "/masks");
    fs::create_directories(out_dir + "/masks_colour");
  }
  std::vector<cv::Vec3b> palette;
  if (!core::classColours(mo.colours_file, &palette, &error)) fail(error);

  // Classes: names file, or class_<id> up to the network's class count (after the first run).
  const auto poses = core::capturePoses(cp);
  core::OrthoRenderer renderer;
  core::SegmentationScores scores;
  core::PointClassVotes votes;
  votes.reset(cloud.size());
  cv::Mat image;
  double render_ms = 0, net_ms = 0, cast_ms = 0, io_ms = 0;
  std::size_t drawn = 0, cast_votes = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto t0 = Clock::now();
    drawn += renderer.render(cloud, colours, poses[k], cp.splat_radius_px, &image);
    const auto t1 = Clock::now();
    char name[32];
    std::snprintf(name, sizeof name, "img_%05zu", k);
    if (write_images) {
      cv::imwrite(out_dir + "/images/" + name + ".png", image);
      if (!core::writeCaptureRecordJson(out_dir + "/images/" + name + ".json",
                                        std::string(name) + ".png", static_cast<int>(k), poses[k],
                                        &error))
        fail(error);
    }
    const auto t2 = Clock::now();
    if (render_only) {
      render_ms += msBetween(t0, t1);
      io_ms += msBetween(t1, t2);
      continue;
    }
    if (!masks_dir.empty()) {
      // Label images of an external segmenter (paper Sec. 3.3: a Python script): 8-bit class
      // id per pixel, 255 = no class, any size (sampled at the scaled pixel).
      const std::string mask_file = masks_dir + "/" + name + ".png";
      const cv::Mat mask = cv::imread(mask_file, cv::IMREAD_GRAYSCALE);
      if (mask.empty()) fail("cannot read mask " + mask_file);
      scores.assignLabels(mask, 255);
    } else if (!model.run(image, &scores, &error)) {
      fail(error);
    }
    const auto t3 = Clock::now();
    if (write_masks) {
      const cv::Mat labels = scores.labelImage();
      cv::imwrite(out_dir + "/masks/" + name + ".png", labels);
      // For a person: the class colours, and the image with them blended in.
      cv::Mat colour = core::colourMask(labels, palette), resized, blend;
      cv::imwrite(out_dir + "/masks_colour/" + name + ".png", colour);
      cv::resize(colour, resized, image.size(), 0, 0, cv::INTER_NEAREST);
      cv::addWeighted(image, 0.5, resized, 0.5, 0.0, blend);
      cv::imwrite(out_dir + "/masks_colour/" + name + "_overlay.png", blend);
    }
    const auto t4 = Clock::now();
    cast_votes += votes.castBack(renderer, scores, sp.mask_stride_px, sp.kept_classes);
    const auto t5 = Clock::now();
    render_ms += msBetween(t0, t1);
    io_ms += msBetween(t1, t2) + msBetween(t3, t4);
    net_ms += msBetween(t2, t3);
    cast_ms += msBetween(t4, t5);
  }
  if (render_only) {
    std::printf(
        "rendered %zu images to %s/images (PNG + JSON record each) in %.1f ms (%.1f "
        "images/s without I/O); segment them into %s/masks/img_NNNNN.png (8-bit class "
        "ids, 255 = none) and rerun with --masks\n",
        poses.size(), out_dir.c_str(), render_ms, 1000.0 * poses.size() / std::max(render_ms, 1e-9),
        out_dir.c_str());
    return 0;
  }
  const auto c0 = Clock::now();
  std::vector<int> point_class;
  votes.classify(sp.min_point_votes, &point_class);
  std::vector<core::SparkInstance> instances;
  core::buildInstances(cloud, point_class, sp, &instances);
  const double cluster_ms = msBetween(c0, Clock::now());
  std::size_t classified = 0;
  for (const int c : point_class) classified += c >= 0;

  if (!core::writeInstancesJson(out_dir + "/instances.json", cloud_path, instances, names, &error))
    fail(error);
  if (instance_pcd) {
    fs::create_directories(out_dir + "/instances");
    std::vector<std::uint32_t> idx;
    for (const auto& inst : instances) {
      core::pointsInBox(cloud, inst, sp.box_margin_m, &idx);
      char name[160];
      std::snprintf(name, sizeof name, "/instances/instance_%04u_%s.pcd", inst.id,
                    core::sparkClassName(names, inst.class_id).c_str());
      std::string file = out_dir + name;
      std::replace(file.begin() + static_cast<long>(out_dir.size()), file.end(), ' ', '_');
      if (!core::writeColouredCloud(file, cloud, rgb, idx)) fail("cannot write " + file);
    }
  }
  if (!cut.empty()) {
    std::vector<bool> cut_ids;
    const int bound = names.empty() ? scores.classIdBound() : static_cast<int>(names.size());
    if (!core::resolveKeptClasses(cut, names, bound, &cut_ids, &error)) fail("--cut: " + error);
    std::vector<std::uint32_t> kept;
    core::cutOutClasses(cloud, instances, cut_ids, sp.box_margin_m, &kept);
    if (!core::writeColouredCloud(out_dir + "/cloud_cut.pcd", cloud, rgb, kept))
      fail("cannot write cloud_cut.pcd");
    std::printf("cut: %zu of %zu points kept in %s/cloud_cut.pcd\n", kept.size(), cloud.size(),
                out_dir.c_str());
  }

  std::map<std::string, int> per_class;
  for (const auto& inst : instances) ++per_class[core::sparkClassName(names, inst.class_id)];
  std::printf("cloud: %s, %zu points; %zu images %dx%d (%d rotations, %.3f m/px)\n",
              cloud_path.c_str(), cloud.size(), poses.size(), cp.image_width_px, cp.image_height_px,
              cp.rotations, cp.metres_per_pixel);
  std::printf("instances: %zu", instances.size());
  for (const auto& [c, n] : per_class) std::printf("  %s=%d", c.c_str(), n);
  std::printf("\nclassified points: %zu (votes %zu, stride %d px)\n", classified, cast_votes,
              sp.mask_stride_px);
  const double n_img = static_cast<double>(std::max<std::size_t>(1, poses.size()));
  std::printf(
      "timing: render %.2f ms/image (%.1f images/s, %.2f M points/s splatted), "
      "segmentation (network or mask file) %.2f ms/image, back-projection %.3f ms/image (%.2f M "
      "rays/s, %.2f M "
      "classified points/s), clustering %.1f ms, image+record I/O %.2f ms/image\n",
      render_ms / n_img, 1000.0 * n_img / std::max(render_ms, 1e-9),
      1e-3 * static_cast<double>(cloud.size()) * n_img / std::max(render_ms, 1e-9), net_ms / n_img,
      cast_ms / n_img,
      1e-3 * n_img * (cp.image_width_px / sp.mask_stride_px + 1) *
          (cp.image_height_px / sp.mask_stride_px + 1) / std::max(cast_ms, 1e-9),
      1e-3 * static_cast<double>(cast_votes) / std::max(cast_ms, 1e-9), cluster_ms, io_ms / n_img);
  std::printf("wrote %s/instances.json%s\n", out_dir.c_str(),
              write_images ? " and images/ (PNG + JSON record per image)" : "");
  (void)drawn;
  return 0;
}

// ---------------------------------------------------------------------------------------------
int runSynthetic(int argc, char** argv) {
  std::string out_dir;
  double step = 0.1;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out")
      out_dir = ud::tools::optionValue(argc, argv, &i, "--out");
    else if (a == "--step")
      step = std::stod(ud::tools::optionValue(argc, argv, &i, "--step"));
    else
      fail("unknown option " + a);
  }
  if (out_dir.empty()) fail("synthetic needs --out DIR");
  fs::create_directories(out_dir);
  ud::CloudXYZIRT cloud;
  std::vector<cv::Vec3b> rgb;
  std::vector<core::SparkSceneObject> objects;
  core::makeSparkScene(step, &cloud, &rgb, &objects);
  std::vector<std::uint32_t> all(cloud.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
  if (!core::writeColouredCloud(out_dir + "/scene.pcd", cloud, rgb, all))
    fail("cannot write scene.pcd");
  FILE* f = std::fopen((out_dir + "/path.json").c_str(), "w");
  if (!f) fail("cannot write path.json");
  std::fprintf(
      f,
      "{\n  \"path\": [[0, 0, 3], [35, 0, 3]],\n  \"interval_m\": 5,\n  \"rotations\": 4,\n"
      "  \"pitch_deg\": -25,\n  \"image_width_px\": 320,\n  \"image_height_px\": 240,\n"
      "  \"metres_per_pixel\": 0.1,\n  \"splat_radius_px\": 1,\n  \"colour\": \"rgb\"\n}\n");
  std::fclose(f);
  std::printf("wrote %s/scene.pcd (%zu points, %zu objects) and %s/path.json\n", out_dir.c_str(),
              cloud.size(), objects.size(), out_dir.c_str());
  for (const auto& o : objects)
    std::printf("  class %d box [%.2f %.2f %.2f] - [%.2f %.2f %.2f], points %u..%u\n", o.class_id,
                o.min_pt.x(), o.min_pt.y(), o.min_pt.z(), o.max_pt.x(), o.max_pt.y(), o.max_pt.z(),
                o.first, o.first + o.count - 1);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// KITTI object frames, real network. Two questions:
// 1. What class does the camera give the labelled objects it sees? The points of each labelled
//    3-D box form an object; its camera category (fuseObjectClass in camera mode over the
//    class map) is compared with the KITTI type's category, split by range.
// 2. What does the fusion do to the precision of the in-view detections? The hierarchical grid
//    detector and the LiDAR classifier run on the cloud; each kept detection made mostly of
//    points in the camera's view is true when most of its points lie in one labelled box (10 cm
//    margin) and class-correct when its class is the box type's category. Detections made
//    mostly of DontCare-rectangle points are left out. Precision: LiDAR classes only, fused
//    veto-only (the shipped rule) and fused with relabelling.
struct RangeCounts {
  int n = 0, correct = 0, unknown = 0;
  std::map<std::string, int> got;  // camera category -> count
};

int runKitti(int argc, char** argv) {
  std::string data = "../shared/data/kitti_object", json_path, config_dir = "config";
  std::string classifier_model;
  std::vector<std::string> configs;
  ModelOptions mo = readModelConfig(argc, argv);
  bool oracle = false;
  core::ImageLabelTransferParams tp = mo.stage.transfer;
  double near_m = 30.0;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* o) { return ud::tools::optionValue(argc, argv, &i, o); };
    if (modelOption(argc, argv, &i, &mo)) continue;
    if (a == "--data" || a == "--kitti")
      data = value(a.c_str());
    else if (a == "--box-oracle")
      oracle = true;
    else if (a == "--json")
      json_path = value("--json");
    else if (a == "--config")
      configs.push_back(value("--config"));
    else if (a == "--config-dir")
      config_dir = value("--config-dir");
    else if (a == "--classifier")
      classifier_model = value("--classifier");
    else if (a == "--near")
      near_m = std::stod(value("--near"));
    else if (a == "--min-confidence")
      tp.min_confidence = std::stod(value(a.c_str()));
    else if (a == "--occlusion-margin")
      tp.occlusion_margin_m = std::stod(value(a.c_str()));
    else if (a == "--veto-share")
      mo.stage.fusion.veto_share = std::stod(value(a.c_str()));
    else
      fail("unknown option " + a);
  }
  if (oracle == !mo.stage.model.network.model_path.empty())
    fail("kitti needs exactly one of --model NET (or --model-config) and --box-oracle");
  const std::string fusion_error = core::validate(mo.stage.fusion);
  if (!fusion_error.empty()) fail(fusion_error);
  std::string error;
  if (oracle) {  // the KITTI types painted as classes: no network, no names file
    mo.model.names = {"background",     "Car",     "Van",  "Truck", "Pedestrian",
                      "Person_sitting", "Cyclist", "Tram", "Misc"};
    const int bound = static_cast<int>(mo.model.names.size());
    if (!core::resolveKeptClasses(mo.stage.model.keep_classes, mo.model.names, bound,
                                  &mo.model.kept_classes, &error) ||
        !core::buildCameraClassMap(mo.model.names, {"Car", "Van", "Truck", "Tram"},
                                   {"Pedestrian", "Person_sitting"}, {"Cyclist"}, {"Misc"}, {},
                                   &mo.model.class_map, &error))
      fail(error);
    if (mo.stage.model.keep_classes.empty()) mo.model.kept_classes.clear();
  } else {
    loadModel(&mo, true);
  }
  if (mo.model.names.empty())
    fail("kitti needs the class names (--classes or model/class_names_file)");
  core::SegmentationModel& model = mo.model.network;
  const std::vector<std::string>& names = mo.model.names;
  const core::CameraClassMap& class_map = mo.model.class_map;
  tp.kept_classes = mo.model.kept_classes;

  // The LiDAR chain: segmentation, hierarchical grid detector, classifier.
  if (configs.empty()) {
    for (const char* f : {"segmentation.yaml", "hierarchical_grid.yaml", "classification.yaml"}) {
      const std::string path = config_dir + "/" + f;
      if (!fs::exists(path))
        fail(path + " not found: run from the package folder or give --config-dir");
      configs.push_back(path);
    }
  }
  core::PipelineParams pp;
  if (!ud::tools::loadConfigs(configs, &pp)) return 2;
  if (!classifier_model.empty()) {
    pp.classifier.enabled = true;
    pp.classifier.model_path = classifier_model;
  }
  pp.detector = "hierarchical_grid";
  std::unique_ptr<core::Pipeline> pipeline;
  try {
    pipeline = std::make_unique<core::Pipeline>(pp);
  } catch (const std::exception& e) {
    fail(std::string("pipeline: ") + e.what());
  }

  const auto ids = core::listFiles(data + "/label_2", ".txt");
  if (ids.empty()) fail("no label_2/*.txt under " + data);
  std::map<std::string, RangeCounts> near_counts, all_counts;  // by KITTI category
  core::SparkPrecisionCounts lidar_p, veto_p, relabel_p;
  std::vector<double> net_ms, pre_ms, transfer_ms;
  std::ostringstream objects_json, detections_json;
  int frames = 0;
  std::printf("%-7s %-15s %6s %7s %7s %-13s %-12s %6s %6s %s\n", "frame", "KITTI type", "range",
              "points", "visible", "camera class", "category", "share", "bg", "ok");
  for (const std::string& label_file : ids) {
    const std::string id = fs::path(label_file).stem().string();
    core::KittiSparkFrame f;
    if (!core::loadKittiSparkFrame(data, id, true, &f, &error)) {
      std::fprintf(stderr, "warning: skipping %s: %s\n", id.c_str(), error.c_str());
      continue;
    }
    ++frames;
    core::SegmentationScores scores;
    if (oracle) {
      scores.assignLabels(core::kittiBoxOracleMask(f, names), -1);
    } else {
      if (!model.run(f.image, &scores, &error)) fail(error);
      net_ms.push_back(model.stats().inference_ms);
      pre_ms.push_back(model.stats().preprocess_ms);
    }
    core::ImageLabelTransfer transfer(tp);
    core::CameraFusionParams camera_mode = mo.stage.fusion;
    camera_mode.mode = core::FusionMode::kCamera;

    // 1. Labelled objects.
    ud::LabeledCloud pts;
    core::kittiLabelObjects(f, &pts);
    std::vector<core::ObjectClassVote> votes;
    transfer.transfer(pts, f.camera_from_velo, f.camera, scores, &votes);
    for (std::size_t s = 0; s < votes.size(); ++s) {
      const auto& v = votes[s];
      const core::KittiLabel& l = f.labels[v.object_id - 1];
      const core::ObjectCategory truth = core::kittiTypeCategory(l.type);
      const core::CameraEvidence e = core::cameraEvidence(
          transfer.classScores(s), transfer.classBound(), v.considered, class_map);
      const core::FusedClass cam =
          core::fuseObjectClass(core::ObjectCategory::kUnknown, 0.0f, e, camera_mode);
      const double range = core::kittiLabelRange(f, l);
      const bool in_view = cam.camera_used;
      const bool scored = in_view && truth != core::ObjectCategory::kUnknown;
      const bool ok = cam.category == truth;
      const std::string cam_name = cam.camera_used ? core::toString(cam.category) : "-";
      // The single network class with the most votes (among all classes).
      int best_class = -1;
      if (const float* cs = transfer.classScores(s)) {
        float best = 0.0f;
        for (int c = 0; c < transfer.classBound(); ++c)
          if (cs[c] > best) best = cs[c], best_class = c;
      }
      std::printf("%-7s %-15s %6.1f %7u %7u %-13s %-12s %6.2f %6.2f %s\n", id.c_str(),
                  l.type.c_str(), range, v.points, v.considered,
                  core::sparkClassName(names, best_class).c_str(), cam_name.c_str(), e.best_share,
                  e.background_share(), scored ? (ok ? "yes" : "NO") : "-");
      objects_json << (objects_json.tellp() > 0 ? ",\n  " : "  ") << "{\"frame\": \"" << id
                   << "\", \"type\": \"" << l.type
                   << "\", \"range_m\": " << ud::tools::jsonNumber(range)
                   << ", \"points\": " << v.points << ", \"visible\": " << v.considered
                   << ", \"camera_class\": \""
                   << ud::tools::jsonEscape(core::sparkClassName(names, best_class))
                   << "\", \"camera_category\": \"" << cam_name
                   << "\", \"share\": " << ud::tools::jsonNumber(e.best_share)
                   << ", \"background_share\": " << ud::tools::jsonNumber(e.background_share())
                   << ", \"scored\": " << (scored ? "true" : "false")
                   << ", \"correct\": " << (ok ? "true" : "false") << "}";
      if (!scored) continue;
      for (auto* counts : {&all_counts, &near_counts}) {
        if (counts == &near_counts && range > near_m) continue;
        RangeCounts& c = (*counts)[core::toString(truth)];
        ++c.n;
        c.correct += ok;
        c.unknown += cam.category == core::ObjectCategory::kUnknown;
        ++c.got[cam_name];
      }
    }

    // 2. Detections: LiDAR chain, then the fusion on the in-view ones.
    const core::PipelineResult& lidar = pipeline->process(f.cloud);
    const ud::LabeledCloud& foreground = lidar.foreground;
    const std::vector<core::DetectedObject>& objects = lidar.objects;
    ud::LabeledCloud object_points;
    std::unordered_map<std::uint32_t, std::uint32_t> scratch;
    ud::ros_conv::buildObjectPoints(foreground, objects, &object_points, &scratch);
    const auto t0 = Clock::now();
    transfer.transfer(object_points, f.camera_from_velo, f.camera, scores, &votes);
    transfer_ms.push_back(msBetween(t0, Clock::now()));
    const std::vector<int> owner = core::kittiPointOwners(f);
    for (const core::DetectedObject& o : objects) {
      const core::KittiDetectionTruth t = core::kittiDetectionTruth(f, owner, o);
      if (!t.scored) continue;
      const auto vit = std::lower_bound(
          votes.begin(), votes.end(), o.id,
          [](const core::ObjectClassVote& v, std::uint32_t i) { return v.object_id < i; });
      core::CameraEvidence e;
      if (vit != votes.end() && vit->object_id == o.id)
        e = core::cameraEvidence(
            transfer.classScores(static_cast<std::size_t>(vit - votes.begin())),
            transfer.classBound(), vit->considered, class_map);
      core::CameraFusionParams veto = mo.stage.fusion, relabel = mo.stage.fusion;
      veto.mode = relabel.mode = core::FusionMode::kFused;
      veto.relabel = false;
      relabel.relabel = true;
      const core::FusedClass fv = core::fuseObjectClass(o.category, o.class_confidence, e, veto);
      const core::FusedClass fr = core::fuseObjectClass(o.category, o.class_confidence, e, relabel);
      lidar_p.add(o.category, t);
      veto_p.add(fv.category, t);
      relabel_p.add(fr.category, t);
      detections_json << (detections_json.tellp() > 0 ? ",\n  " : "  ") << "{\"frame\": \"" << id
                      << "\", \"points\": " << o.indices.size() << ", \"range_m\": "
                      << ud::tools::jsonNumber(std::hypot(o.centroid.x(), o.centroid.y()))
                      << ", \"truth\": \""
                      << (t.is_true ? f.labels[static_cast<std::size_t>(t.label)].type : "none")
                      << "\", \"lidar\": \"" << core::toString(o.category)
                      << "\", \"camera_best\": \"" << core::toString(e.best)
                      << "\", \"camera_share\": " << ud::tools::jsonNumber(e.best_share)
                      << ", \"background_share\": " << ud::tools::jsonNumber(e.background_share())
                      << ", \"visible\": " << e.visible << ", \"fused_veto\": \""
                      << core::toString(fv.category) << "\", \"fused_relabel\": \""
                      << core::toString(fr.category) << "\"}";
    }
  }
  if (frames == 0) fail("no usable frames under " + data);

  // Tables.
  auto pct = [](int a, int b) { return b ? 100.0 * a / b : 0.0; };
  std::printf("\ncamera class of labelled objects in the camera view (%s, %d frames)\n",
              oracle ? "box oracle" : mo.stage.model.network.model_path.c_str(), frames);
  std::printf("%-11s %-8s %5s %8s %7s  %s\n", "KITTI", "range", "n", "correct", "%", "got");
  std::ostringstream by_type;
  for (const char* cat : {"vehicle", "pedestrian", "cyclist"}) {
    for (int r = 0; r < 2; ++r) {
      const auto& counts = r == 0 ? near_counts : all_counts;
      const auto it = counts.find(cat);
      const RangeCounts c = it == counts.end() ? RangeCounts() : it->second;
      std::string got;
      for (const auto& [k, n] : c.got) got += k + "=" + std::to_string(n) + " ";
      char range[16];
      std::snprintf(range, sizeof range, r == 0 ? "<=%.0f m" : "all", near_m);
      std::printf("%-11s %-8s %5d %8d %6.1f%%  %s\n", cat, range, c.n, c.correct,
                  pct(c.correct, c.n), got.c_str());
      by_type << (by_type.tellp() > 0 ? ",\n  " : "  ") << "{\"category\": \"" << cat
              << "\", \"range\": \"" << (r == 0 ? "near" : "all") << "\", \"n\": " << c.n
              << ", \"correct\": " << c.correct << ", \"unknown\": " << c.unknown << "}";
    }
  }
  std::printf("\nin-view detections (hierarchical grid + LiDAR classifier), precision\n");
  std::printf("%-22s %5s %5s %7s %9s %7s %11s\n", "classes", "kept", "true", "P", "class ok",
              "P_class", "vetoed(true)");
  const std::pair<const char*, const core::SparkPrecisionCounts*> rows[] = {
      {"lidar", &lidar_p}, {"fused (veto only)", &veto_p}, {"fused (veto+relabel)", &relabel_p}};
  for (const auto& [name, c] : rows)
    std::printf("%-22s %5d %5d %6.1f%% %9d %6.1f%% %7d(%d)\n", name, c->kept, c->true_objects,
                pct(c->true_objects, c->kept), c->class_correct, pct(c->class_correct, c->kept),
                c->vetoed, c->vetoed_true);
  const double mean_net = net_ms.empty() ? 0.0 : ud::tools::median(net_ms);
  const double mean_pre = pre_ms.empty() ? 0.0 : ud::tools::median(pre_ms);
  const double mean_tr = ud::tools::median(transfer_ms);
  if (!oracle)
    std::printf(
        "\nnetwork: median preprocess %.1f ms + inference %.1f ms per image (%dx%d input)\n",
        mean_pre, mean_net, mo.stage.model.network.input_width_px,
        mo.stage.model.network.input_height_px);
  std::printf("transfer on the detector's objects: median %.3f ms per revolution\n", mean_tr);
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    if (!out) fail("cannot write " + json_path);
    out << "{\n\"what\": \"urban_detection_spark kitti: camera classes of labelled KITTI objects "
           "in view, and precision of in-view detections with and without the camera\",\n"
        << "\"model\": \""
        << ud::tools::jsonEscape(oracle ? "box oracle" : mo.stage.model.network.model_path)
        << "\",\n\"input_px\": [" << mo.stage.model.network.input_width_px << ", "
        << mo.stage.model.network.input_height_px << "],\n\"frames\": " << frames
        << ",\n\"near_m\": " << ud::tools::jsonNumber(near_m)
        << ",\n\"veto_share\": " << ud::tools::jsonNumber(mo.stage.fusion.veto_share)
        << ",\n\"min_camera_share\": " << ud::tools::jsonNumber(mo.stage.fusion.min_camera_share)
        << ",\n\"inference_ms_median\": " << ud::tools::jsonNumber(mean_net)
        << ",\n\"preprocess_ms_median\": " << ud::tools::jsonNumber(mean_pre)
        << ",\n\"transfer_ms_median\": " << ud::tools::jsonNumber(mean_tr)
        << ",\n\"by_category\": [\n"
        << by_type.str() << "\n],\n\"precision\": {\"lidar\": " << lidar_p.json()
        << ",\n \"fused_veto\": " << veto_p.json() << ",\n \"fused_relabel\": " << relabel_p.json()
        << "},\n\"objects\": [\n"
        << objects_json.str() << "\n],\n\"detections\": [\n"
        << detections_json.str() << "\n]\n}\n";
    std::printf("wrote %s\n", json_path.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "run") return runOffline(argc, argv);
  if (mode == "synthetic") return runSynthetic(argc, argv);
  if (mode == "kitti") return runKitti(argc, argv);
  std::fprintf(
      stderr,
      "usage: urban_detection_spark run --cloud CLOUD.pcd|.bin --path PATH.json "
      "(--model NET.onnx | --masks DIR | --render-only) --out DIR\n"
      "         [--classes NAMES.txt] [--keep a,b] [--model-config image_label_transfer.yaml]\n"
      "         [--input-size WxH] [--mean r,g,b] [--scale r,g,b] [--bgr] [--probabilities]\n"
      "         [--stride N] [--min-votes N] [--eps M] [--min-points N] "
      "[--min-instance-points N]\n"
      "         [--box-margin M] [--instance-pcd] [--cut a,b] [--no-images] [--write-masks]\n"
      "       urban_detection_spark synthetic --out DIR [--step M]\n"
      "       urban_detection_spark kitti [--kitti DIR] (--model NET | --model-config YAML | "
      "--box-oracle)\n"
      "         [--model-dir DIR] [--classes NAMES.txt] [--keep a,b] [--json FILE] [--near M]\n"
      "         [--config-dir DIR | --config YAML...] [--classifier MODEL] [--veto-share S]\n"
      "         [--min-confidence C] [--occlusion-margin M]\n");
  return 2;
}
