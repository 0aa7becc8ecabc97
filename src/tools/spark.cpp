// urban_detection_spark: 2-D semantic segmentation transferred to 3-D point clouds (issue 9,
// second seed paper "SPARK").
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
//   urban_detection_spark kitti --data DIR (--model NET.onnx | --box-oracle) [options]
//       Live transfer evaluated on KITTI object frames (image_2, calib, velodyne, label_2): the
//       points of each labelled 3-D box form an object; its voted class is compared with the
//       label. --box-oracle paints the label_2 2-D boxes as the "segmentation" (no network): it
//       measures what projection, occlusion handling and voting lose with a perfect 2-D input.
//       Also times the transfer on all objects the hierarchical grid detector finds in the
//       revolution (the added cost per revolution beyond the network).
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <pcl/io/pcd_io.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "tool_common.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/spark/spark_capture.h"
#include "urban_detection/core/spark/spark_instances.h"
#include "urban_detection/core/spark/spark_scene.h"
#include "urban_detection/core/spark/spark_segmenter.h"
#include "urban_detection/ros/image_label_transfer_ros.h"
#include "urban_detection/ros/object_conversions.h"

namespace ud = urban_detection;
namespace core = urban_detection::core;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

[[noreturn]] void fail(const std::string& msg) {
  std::fprintf(stderr, "error: %s\n", msg.c_str());
  std::exit(1);
}

// The `model:` map of config/image_label_transfer.yaml (the nodelet's file), so one tuned file
// serves both. Only the keys present override the defaults.
void loadModelYaml(const std::string& path, core::SegmentationModelParams* m,
                   std::vector<std::string>* keep, std::string* names_file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    fail("cannot read " + path + ": " + e.what());
  }
  const YAML::Node n = root["model"];
  if (!n || !n.IsMap()) fail(path + " has no `model:` map");
  try {
    if (n["path"] && !n["path"].as<std::string>().empty())
      m->model_path = n["path"].as<std::string>();
    if (n["input_width_px"]) m->input_width_px = n["input_width_px"].as<int>();
    if (n["input_height_px"]) m->input_height_px = n["input_height_px"].as<int>();
    if (n["input_rgb"]) m->input_rgb = n["input_rgb"].as<bool>();
    if (n["output_softmax"]) m->output_softmax = n["output_softmax"].as<bool>();
    for (const char* key : {"mean", "scale"}) {
      if (!n[key]) continue;
      const auto v = n[key].as<std::vector<double>>();
      if (v.size() != 3) fail(std::string("model/") + key + " needs 3 numbers");
      auto& dst = std::string(key) == "mean" ? m->mean : m->scale;
      std::copy(v.begin(), v.end(), dst.begin());
    }
    if (n["keep_classes"]) *keep = n["keep_classes"].as<std::vector<std::string>>();
    if (n["class_names_file"] && !n["class_names_file"].as<std::string>().empty())
      *names_file = n["class_names_file"].as<std::string>();
  } catch (const YAML::Exception& e) {
    fail(path + ": " + e.what());
  }
}

struct ModelOptions {
  core::SegmentationModelParams params;
  std::vector<std::string> keep;
  std::string names_file;
  std::vector<std::string> names;
};

// Common model options; returns true when argv[*i] was one of them.
bool modelOption(int argc, char** argv, int* i, ModelOptions* m) {
  const std::string a = argv[*i];
  auto value = [&](const char* o) { return ud::tools::optionValue(argc, argv, i, o); };
  auto triple = [&](const char* o, std::array<double, 3>* dst) {
    const auto v = splitList(value(o));
    if (v.size() != 3) fail(std::string(o) + " needs three comma-separated numbers");
    for (int c = 0; c < 3; ++c) (*dst)[c] = std::stod(v[c]);
  };
  if (a == "--model")
    m->params.model_path = value("--model");
  else if (a == "--model-config")
    loadModelYaml(value("--model-config"), &m->params, &m->keep, &m->names_file);
  else if (a == "--classes")
    m->names_file = value("--classes");
  else if (a == "--keep")
    m->keep = splitList(value("--keep"));
  else if (a == "--input-size") {
    int w = 0, h = 0;
    if (std::sscanf(value("--input-size").c_str(), "%dx%d", &w, &h) != 2) fail("--input-size WxH");
    m->params.input_width_px = w;
    m->params.input_height_px = h;
  } else if (a == "--mean")
    triple("--mean", &m->params.mean);
  else if (a == "--scale")
    triple("--scale", &m->params.scale);
  else if (a == "--bgr")
    m->params.input_rgb = false;
  else if (a == "--probabilities")
    m->params.output_softmax = false;
  else
    return false;
  return true;
}

void loadModel(ModelOptions* m, core::SegmentationModel* model) {
  std::string error;
  if (!model->load(m->params, &error)) fail(error);
  if (!m->names_file.empty() && !core::readClassNames(m->names_file, &m->names, &error))
    fail(error);
}

std::string className(const std::vector<std::string>& names, int id) {
  if (id >= 0 && static_cast<std::size_t>(id) < names.size() && !names[id].empty())
    return names[id];
  return id < 0 ? "unknown" : "class_" + std::to_string(id);
}

// ---------------------------------------------------------------------------------------------
// Cloud I/O: PCD (x y z, optional rgb/rgba and intensity) or KITTI .bin.
bool readCloud(const std::string& path, ud::CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb,
               std::string* error) {
  rgb->clear();
  if (fs::path(path).extension() == ".bin") return core::readKittiBin(path, cloud, error);
  pcl::PCLPointCloud2 blob;
  if (pcl::io::loadPCDFile(path, blob) != 0) {
    *error = "cannot read PCD file '" + path + "'";
    return false;
  }
  bool has_rgb = false, has_intensity = false;
  for (const auto& f : blob.fields) {
    has_rgb |= f.name == "rgb" || f.name == "rgba";
    has_intensity |= f.name == "intensity";
  }
  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  cloud->clear();
  cloud->reserve(xyz.size());
  for (const auto& p : xyz) {
    cloud->push_back(ud::makePoint(p.x, p.y, p.z));
  }
  if (has_intensity) {
    pcl::PointCloud<pcl::PointXYZI> xyzi;
    pcl::fromPCLPointCloud2(blob, xyzi);
    for (std::size_t i = 0; i < xyzi.size() && i < cloud->size(); ++i)
      (*cloud)[i].intensity = xyzi[i].intensity;
  }
  if (has_rgb) {
    pcl::PointCloud<pcl::PointXYZRGB> c;
    pcl::fromPCLPointCloud2(blob, c);
    rgb->reserve(c.size());
    for (const auto& p : c) rgb->emplace_back(p.b, p.g, p.r);
  }
  return true;
}

bool writeSubCloud(const std::string& path, const ud::CloudXYZIRT& cloud,
                   const std::vector<cv::Vec3b>& rgb, const std::vector<std::uint32_t>& idx) {
  pcl::PointCloud<pcl::PointXYZRGB> out;
  out.reserve(idx.size());
  for (const std::uint32_t i : idx) {
    pcl::PointXYZRGB p;
    p.x = cloud[i].x;
    p.y = cloud[i].y;
    p.z = cloud[i].z;
    const cv::Vec3b c = i < rgb.size() ? rgb[i] : cv::Vec3b(128, 128, 128);
    p.b = c[0];
    p.g = c[1];
    p.r = c[2];
    out.push_back(p);
  }
  out.width = static_cast<std::uint32_t>(out.size());
  out.height = 1;
  return out.empty() ? pcl::io::savePCDFileASCII(path, out) == 0
                     : pcl::io::savePCDFileBinary(path, out) == 0;
}

// ---------------------------------------------------------------------------------------------
int runOffline(int argc, char** argv) {
  std::string cloud_path, path_json, out_dir;
  ModelOptions mo;
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
      cut = splitList(value("--cut"));
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
  if (render_only + !masks_dir.empty() + !mo.params.model_path.empty() != 1)
    fail("run needs exactly one of --model NET.onnx, --masks DIR and --render-only");
  if (render_only && !write_images) fail("--render-only writes images; drop --no-images");
  if (!(sp.dbscan_eps_m > 0.0)) fail("--eps must be > 0");
  std::string error;
  core::CapturePathParams cp;
  if (!core::readCapturePathJson(path_json, &cp, &error)) fail(error);
  core::SegmentationModel model;
  std::string error_names;
  if (!mo.params.model_path.empty()) {
    loadModel(&mo, &model);
  } else if (!mo.names_file.empty() &&
             !core::readClassNames(mo.names_file, &mo.names, &error_names)) {
    fail(error_names);
  }
  ud::CloudXYZIRT cloud;
  std::vector<cv::Vec3b> rgb, colours;
  if (!readCloud(cloud_path, &cloud, &rgb, &error)) fail(error);
  if (cp.colour == "rgb" && rgb.empty())
    std::fprintf(stderr,
                 "warning: %s has no rgb field; points are drawn grey (set \"colour\": "
                 "\"intensity\" or \"height\" in the path file)\n",
                 cloud_path.c_str());
  core::pointColours(cloud, rgb, cp, &colours);
  fs::create_directories(out_dir + "/images");
  if (write_masks) fs::create_directories(out_dir + "/masks");

  // Classes: names file, or class_<id> up to the network's class count (after the first run).
  const auto poses = core::capturePoses(cp);
  core::OrthoRenderer renderer;
  core::SegmentationScores scores;
  core::PointClassVotes votes;
  votes.reset(cloud.size());
  cv::Mat image;
  double render_ms = 0, net_ms = 0, cast_ms = 0, io_ms = 0;
  std::size_t drawn = 0, cast_votes = 0;
  bool kept_resolved = false;
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
    if (!kept_resolved) {
      const int bound =
          mo.names.empty() ? scores.classIdBound() : static_cast<int>(mo.names.size());
      if (!core::resolveKeptClasses(mo.keep, mo.names, bound, &sp.kept_classes, &error))
        fail(error);
      if (mo.keep.empty()) sp.kept_classes.clear();
      kept_resolved = true;
    }
    if (write_masks) cv::imwrite(out_dir + "/masks/" + name + ".png", scores.labelImage());
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

  std::vector<std::string> names = mo.names;
  if (!core::writeInstancesJson(out_dir + "/instances.json", cloud_path, instances, names, &error))
    fail(error);
  if (instance_pcd) {
    fs::create_directories(out_dir + "/instances");
    std::vector<std::uint32_t> idx;
    for (const auto& inst : instances) {
      core::pointsInBox(cloud, inst, sp.box_margin_m, &idx);
      char name[160];
      std::snprintf(name, sizeof name, "/instances/instance_%04u_%s.pcd", inst.id,
                    className(names, inst.class_id).c_str());
      std::string file = out_dir + name;
      std::replace(file.begin() + static_cast<long>(out_dir.size()), file.end(), ' ', '_');
      if (!writeSubCloud(file, cloud, rgb, idx)) fail("cannot write " + file);
    }
  }
  if (!cut.empty()) {
    std::vector<bool> cut_ids;
    const int bound = names.empty() ? scores.classIdBound() : static_cast<int>(names.size());
    if (!core::resolveKeptClasses(cut, names, bound, &cut_ids, &error)) fail("--cut: " + error);
    std::vector<std::uint32_t> kept;
    core::cutOutClasses(cloud, instances, cut_ids, sp.box_margin_m, &kept);
    if (!writeSubCloud(out_dir + "/cloud_cut.pcd", cloud, rgb, kept))
      fail("cannot write cloud_cut.pcd");
    std::printf("cut: %zu of %zu points kept in %s/cloud_cut.pcd\n", kept.size(), cloud.size(),
                out_dir.c_str());
  }

  std::map<std::string, int> per_class;
  for (const auto& inst : instances) ++per_class[className(names, inst.class_id)];
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
  if (!writeSubCloud(out_dir + "/scene.pcd", cloud, rgb, all)) fail("cannot write scene.pcd");
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
// KITTI types and the segmentation class names that count as correct for them.
bool kittiMatch(const std::string& type, std::string voted) {
  std::transform(voted.begin(), voted.end(), voted.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  static const std::map<std::string, std::set<std::string>> ok = {
      {"Car", {"car"}},
      {"Van", {"car", "van", "truck"}},
      {"Truck", {"truck", "bus"}},
      {"Pedestrian", {"person", "pedestrian"}},
      {"Person_sitting", {"person", "pedestrian", "person_sitting"}},
      {"Cyclist", {"rider", "bicycle", "cyclist", "motorcycle"}},
      {"Tram", {"train", "tram", "bus"}}};
  const auto it = ok.find(type);
  return it != ok.end() && it->second.count(voted) > 0;
}

int runKitti(int argc, char** argv) {
  std::string data = std::string("../shared/data/kitti_object");
  ModelOptions mo;
  bool oracle = false;
  core::ImageLabelTransferParams tp;
  int repeat = 20;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (modelOption(argc, argv, &i, &mo)) continue;
    if (a == "--data")
      data = ud::tools::optionValue(argc, argv, &i, "--data");
    else if (a == "--box-oracle")
      oracle = true;
    else if (a == "--min-confidence")
      tp.min_confidence = std::stod(ud::tools::optionValue(argc, argv, &i, a.c_str()));
    else if (a == "--occlusion-margin")
      tp.occlusion_margin_m = std::stod(ud::tools::optionValue(argc, argv, &i, a.c_str()));
    else if (a == "--repeat")
      repeat = static_cast<int>(ud::tools::optionCount(argc, argv, &i, "--repeat"));
    else
      fail("unknown option " + a);
  }
  if (oracle == !mo.params.model_path.empty())
    fail("kitti needs exactly one of --model NET.onnx and --box-oracle");
  core::SegmentationModel model;
  if (oracle) {
    mo.names = {"background",     "Car",     "Van",  "Truck", "Pedestrian",
                "Person_sitting", "Cyclist", "Tram", "Misc"};
  } else {
    loadModel(&mo, &model);
  }
  const auto ids = core::listFiles(data + "/label_2", ".txt");
  if (ids.empty()) fail("no label_2/*.txt under " + data);
  std::string error;
  core::GridSegmenter segmenter;
  core::HierarchicalGridDetector detector;
  std::printf("%-7s %-15s %7s %6s %-16s %6s %s\n", "frame", "label", "points", "seen", "voted",
              "conf", "ok");
  int scored = 0, correct = 0, unknown = 0;
  double net_ms = 0, pre_ms = 0, transfer_gt_ms = 0, transfer_det_ms = 0;
  std::size_t det_objects = 0, det_points = 0;
  int frames = 0;
  for (const std::string& label_file : ids) {
    const std::string id = fs::path(label_file).stem().string();
    core::KittiCalibration calib;
    std::vector<core::KittiLabel> labels;
    ud::CloudXYZIRT cloud;
    if (!core::readKittiCalibration(data + "/calib/" + id + ".txt", &calib, &error) ||
        !core::readKittiLabels(label_file, &labels, &error) ||
        !core::readKittiBin(data + "/velodyne/" + id + ".bin", &cloud, &error)) {
      std::fprintf(stderr, "warning: skipping %s: %s\n", id.c_str(), error.c_str());
      continue;
    }
    const cv::Mat image = cv::imread(data + "/image_2/" + id + ".png", cv::IMREAD_COLOR);
    if (image.empty()) {
      std::fprintf(stderr, "warning: skipping %s: no image_2/%s.png\n", id.c_str(), id.c_str());
      continue;
    }
    ++frames;
    core::PinholeCamera camera;
    camera.projection = calib.p2;
    camera.width_px = image.cols;
    camera.height_px = image.rows;
    Eigen::Isometry3d cam_from_velo = Eigen::Isometry3d::Identity();
    cam_from_velo.linear() = calib.r0_rect * calib.tr_velo_to_cam.leftCols<3>();
    cam_from_velo.translation() = calib.r0_rect * calib.tr_velo_to_cam.col(3);

    // Objects: the points of each labelled box (20 cm above its bottom: no road).
    ud::LabeledCloud pts;
    for (std::size_t k = 0; k < labels.size(); ++k) {
      const auto& l = labels[k];
      if (l.type == "DontCare") continue;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud[i];
        const Eigen::Vector3d b =
            core::kittiBoxLocal(l, calib.veloToRect(Eigen::Vector3d(p.x, p.y, p.z)));
        if (std::fabs(b.x()) > 0.5 * l.length_m || b.y() < 0.2 || b.y() > l.height_m ||
            std::fabs(b.z()) > 0.5 * l.width_m)
          continue;
        pts.push_back(ud::makeLabeledPoint(p.x, p.y, p.z, static_cast<std::uint32_t>(k + 1),
                                           static_cast<std::uint32_t>(i), p.intensity));
      }
    }
    core::SegmentationScores scores;
    if (oracle) {
      std::vector<std::size_t> order;
      for (std::size_t k = 0; k < labels.size(); ++k) order.push_back(k);
      std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return labels[a].location.z() > labels[b].location.z();
      });
      cv::Mat mask(image.rows, image.cols, CV_8U, cv::Scalar(0));
      for (const std::size_t k : order) {
        const auto it = std::find(mo.names.begin(), mo.names.end(), labels[k].type);
        if (it == mo.names.end()) continue;
        const auto& b = labels[k].bbox;
        mask(cv::Rect(cv::Point(static_cast<int>(b[0]), static_cast<int>(b[1])),
                      cv::Point(static_cast<int>(b[2]) + 1, static_cast<int>(b[3]) + 1)) &
             cv::Rect(0, 0, mask.cols, mask.rows))
            .setTo(static_cast<int>(it - mo.names.begin()));
      }
      scores.assignLabels(mask, 0);
    } else {
      if (!model.run(image, &scores, &error)) fail(error);
      net_ms += model.stats().inference_ms;
      pre_ms += model.stats().preprocess_ms;
    }
    if (tp.kept_classes.empty() && !mo.keep.empty()) {
      const int bound =
          mo.names.empty() ? scores.classIdBound() : static_cast<int>(mo.names.size());
      if (!core::resolveKeptClasses(mo.keep, mo.names, bound, &tp.kept_classes, &error))
        fail(error);
    }
    core::ImageLabelTransfer transfer(tp);
    std::vector<core::ObjectClassVote> votes;
    auto t0 = Clock::now();
    for (int r = 0; r < repeat; ++r) transfer.transfer(pts, cam_from_velo, camera, scores, &votes);
    transfer_gt_ms += msBetween(t0, Clock::now()) / std::max(1, repeat);
    for (const auto& v : votes) {
      const auto& l = labels[v.object_id - 1];
      const std::string voted = className(mo.names, v.class_id);
      const bool score = l.type != "Misc" && v.points >= 10;
      const bool ok = kittiMatch(l.type, voted);
      if (score) {
        ++scored;
        correct += ok;
        unknown += v.class_id < 0;
      }
      std::printf("%-7s %-15s %7u %6u %-16s %6.2f %s\n", id.c_str(), l.type.c_str(), v.points,
                  v.considered, voted.c_str(), v.confidence, score ? (ok ? "yes" : "NO") : "-");
    }

    // Added cost per revolution: all the detector's objects of this revolution, as the nodelet
    // gets them (objects/points and the DetectedObjectArray), transfer + filling the message.
    std::vector<core::SegmentClass> seg;
    ud::LabeledCloud foreground, object_points;
    std::vector<core::DetectedObject> objects;
    segmenter.segment(cloud, &seg);
    core::extractForeground(cloud, seg, &foreground);
    detector.detect(foreground, &objects);
    std::unordered_map<std::uint32_t, std::uint32_t> scratch;
    ud::ros_conv::buildObjectPoints(foreground, objects, &object_points, &scratch);
    ud::DetectedObjectArray msg, out;
    ud::ros_conv::toMsg(objects, detector.name(), std_msgs::Header(), &msg);
    t0 = Clock::now();
    for (int r = 0; r < repeat; ++r) {
      transfer.transfer(object_points, cam_from_velo, camera, scores, &votes);
      ud::ros_conv::applyVotes(msg, votes, mo.names, &out);
    }
    transfer_det_ms += msBetween(t0, Clock::now()) / std::max(1, repeat);
    det_objects += objects.size();
    det_points += object_points.size();
  }
  if (frames == 0) fail("no usable frames under " + data);
  std::printf(
      "\n%s on %d KITTI frames: %d/%d labelled objects (>= 10 points, not Misc) voted "
      "correctly (%.1f%%), %d unknown\n",
      oracle ? "box oracle" : mo.params.model_path.c_str(), frames, correct, scored,
      scored ? 100.0 * correct / scored : 0.0, unknown);
  if (!oracle)
    std::printf("network: preprocess %.1f ms + inference %.1f ms per image (%dx%d input)\n",
                pre_ms / frames, net_ms / frames, mo.params.input_width_px,
                mo.params.input_height_px);
  std::printf(
      "transfer (beyond the network): %.3f ms per frame on the labelled objects; %.3f ms "
      "per revolution on the detector's objects (%.0f objects, %.0f points per "
      "revolution, transfer + message fill, mean of %d runs)\n",
      transfer_gt_ms / frames, transfer_det_ms / frames, static_cast<double>(det_objects) / frames,
      static_cast<double>(det_points) / frames, repeat);
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
      "       urban_detection_spark kitti [--data DIR] (--model NET.onnx | --box-oracle) "
      "[--classes NAMES.txt] [--keep a,b]\n"
      "         [--min-confidence C] [--occlusion-margin M] [--repeat N]\n");
  return 2;
}
