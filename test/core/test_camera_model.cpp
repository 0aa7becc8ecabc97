// The camera stage's configuration and labelling, ROS-free: the field-table types it needs
// (enum, list of strings, fixed-size list of numbers), config/image_label_transfer.yaml read and
// refused through its table, the one model-loading path (loadCameraModel) and the labelling of
// objects under each fusion mode (CameraLabeller) on a synthetic camera.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "spark_test_model.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/spark/camera_labeller.h"
#include "urban_detection/core/spark/camera_model.h"

namespace urban_detection {
namespace core {

// A struct with one field of each type the camera stage added to the tables.
struct TypesDemoParams {
  enum class Mode { kSlow = 0, kFast = 1 };
  Mode mode = Mode::kFast;
  std::vector<std::string> names = {"car", "bus"};
  std::array<double, 3> gains = {1.0, 2.0, 3.0};
};

template <>
struct ParamFields<TypesDemoParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo::choice("mode", {"slow", "fast"}, "how"), p.mode);
    f({"names", "class names"}, p.names);
    f({"gains", "", 0.5, 4.0, "per channel"}, p.gains);
  }
};

namespace {

namespace fs = std::filesystem;

TEST(FieldTableTypes, EnumListAndFixedListAreCheckedAndPrinted) {
  TypesDemoParams p;
  EXPECT_EQ(checkFieldRanges(p), "");
  p.gains[2] = 5.0;
  EXPECT_EQ(checkFieldRanges(p), "parameter 'gains[2]' = 5 is out of range: accepted [0.5, 4]");
  p = TypesDemoParams();
  p.mode = static_cast<TypesDemoParams::Mode>(7);
  EXPECT_EQ(checkFieldRanges(p), "parameter 'mode' = '7' is not one of: slow, fast");
  const std::string md = fieldTableMarkdown(TypesDemoParams());
  EXPECT_NE(md.find("| `mode` | fast | slow, fast | | how |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `names` | [car, bus] | | | class names |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `gains` | [1, 2, 3] | [0.5, 4] each |  | per channel |"), std::string::npos)
      << md;
  FieldInfo info = FieldInfo::choice("mode", {"slow", "fast"}, "");
  TypesDemoParams::Mode m = TypesDemoParams::Mode::kFast;
  EXPECT_TRUE(parseChoice(info, "slow", &m));
  EXPECT_EQ(m, TypesDemoParams::Mode::kSlow);
  EXPECT_FALSE(parseChoice(info, "Slow", &m));  // names are exact
  EXPECT_EQ(choiceName(info, m), "slow");
}

std::string configFile(const std::string& name) {
  return std::string(UD_SOURCE_DIR) + "/config/" + name;
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const fs::path p = fs::path(test::scratchDir("camera_model")) / name;
  std::ofstream(p.string()) << text;
  return p.string();
}

// The key paths of a YAML file's maps, "a/b" for nested maps, in file order.
void flattenKeys(const YAML::Node& map, const std::string& prefix, std::vector<std::string>* out) {
  for (const auto& kv : map) {
    const std::string key = prefix + kv.first.as<std::string>();
    if (kv.second.IsMap()) {
      flattenKeys(kv.second, key + "/", out);
    } else {
      out->push_back(key);
    }
  }
}

TEST(CameraStageYaml, ShippedFileBindsEveryTableKeyInOrder) {
  std::vector<std::string> keys, table;
  flattenKeys(YAML::LoadFile(configFile("image_label_transfer.yaml")), "", &keys);
  const CameraStageParams defaults;
  forEachField(defaults, [&](const FieldInfo& info, const auto&) { table.push_back(info.name); });
  EXPECT_EQ(keys, table);
  CameraStageParams p;
  p.model.inference_nice = 3;  // overwritten by the file
  std::string error;
  ASSERT_TRUE(loadCameraStageParamsYaml(configFile("image_label_transfer.yaml"), &p, &error))
      << error;
  EXPECT_EQ(p.fusion.mode, FusionMode::kCamera);
  EXPECT_EQ(p.model.inference_nice, 19);
  EXPECT_NEAR(p.model.network.scale[1], 0.017507, 1e-9);
  EXPECT_TRUE(p.model.keep_classes.empty());
}

TEST(CameraStageYaml, PresetLoadsOverTheDefaultFile) {
  CameraStageParams p;
  std::string error;
  ASSERT_TRUE(loadCameraStageParamsYaml(configFile("image_label_transfer.yaml"), &p, &error));
  ASSERT_TRUE(loadCameraStageParamsYaml(configFile("spark_enet_cityscapes.yaml"), &p, &error))
      << error;
  EXPECT_EQ(p.fusion.mode, FusionMode::kFused);
  EXPECT_EQ(p.model.network.model_path, "enet-model.net");
  EXPECT_EQ(p.model.network.input_width_px, 1248);
  EXPECT_EQ(p.model.network.mean, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_EQ(p.model.vehicle_classes, (std::vector<std::string>{"Car", "Truck", "Bus"}));
  EXPECT_EQ(p.model.keep_classes.size(), 10u);
  EXPECT_DOUBLE_EQ(p.max_mask_gap_s, 0.6);
  EXPECT_DOUBLE_EQ(p.transfer.min_confidence, 0.3);  // the default file's, kept
}

// Each refusal names the key (as a typo must not be silently ignored) and says why.
TEST(CameraStageYaml, RefusesUnknownKeysBadValuesAndTypesNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"model:\n  pathh: net.onnx\n", "model/pathh: unknown parameter"},
      {"model:\n  input_width_px: 4\n", "'model/input_width_px' = 4 is out of range"},
      {"model:\n  scale: [0.1, 0.0, 0.1]\n", "'model/scale[1]' = 0 is out of range"},
      {"model:\n  mean: [1, 2]\n", "'model/mean' needs 3 numbers, has 2"},
      {"model:\n  keep_classes: car\n", "model/keep_classes: wrong type"},
      {"model:\n  inference_nice: 20\n", "'model/inference_nice' = 20 is out of range"},
      {"fusion: fusd\n", "'fusion' = 'fusd' is not one of: lidar, camera, fused"},
      {"fusion_rule:\n  veto_share: -1\n", "'fusion_rule/veto_share' = -1 is out of range"},
      {"transfer:\n  max_mask_gap_s: 11\n", "'transfer/max_mask_gap_s' = 11 is out of range"},
      {"transfer:\n  queue: 3\n", "transfer/queue: unknown parameter"},
      {"fusion: fused\n", "fusion 'fused' needs model/class_names_file"},
  };
  for (const auto& [text, expected] : cases) {
    CameraStageParams p;
    std::string error;
    const std::string f = writeTemp("bad.yaml", text);
    EXPECT_FALSE(loadCameraStageParamsYaml(f, &p, &error)) << text;
    EXPECT_NE(error.find(expected), std::string::npos) << text << " gave: " << error;
    EXPECT_EQ(error.rfind(f, 0), 0u) << "the file is named first: " << error;
  }
}

TEST(LoadCameraModel, RefusalsNameTheParameter) {
  CameraModel m;
  std::string error;
  CameraModelParams p;
  EXPECT_FALSE(loadCameraModel(p, true, &m, &error));
  EXPECT_EQ(error.rfind("model/path: ", 0), 0u) << error;
  p.network.model_path = "/nonexistent/net.onnx";
  EXPECT_FALSE(loadCameraModel(p, true, &m, &error));
  EXPECT_NE(error.find("cannot open model file '/nonexistent/net.onnx'"), std::string::npos)
      << error;
  EXPECT_TRUE(loadCameraModel(p, false, &m, &error)) << error;  // no network asked for
  EXPECT_TRUE(m.names.empty());
  EXPECT_TRUE(m.kept_classes.empty());  // every class votes
  p.keep_classes = {"3", "car"};        // ids are fine without names, names are not
  EXPECT_FALSE(loadCameraModel(p, false, &m, &error));
  EXPECT_EQ(error.rfind("model/keep_classes: ", 0), 0u) << error;
  p.keep_classes = {"3"};
  EXPECT_TRUE(loadCameraModel(p, false, &m, &error)) << error;
  ASSERT_GT(m.kept_classes.size(), 3u);
  EXPECT_TRUE(m.kept_classes[3]);
  EXPECT_FALSE(m.kept_classes[2]);
  p.class_names_file = "/nonexistent/names.txt";
  EXPECT_FALSE(loadCameraModel(p, false, &m, &error));
  EXPECT_EQ(error.rfind("model/class_names_file: ", 0), 0u) << error;
  p = CameraModelParams();
  p.network.input_height_px = 9000;
  EXPECT_FALSE(loadCameraModel(p, false, &m, &error));
  EXPECT_NE(error.find("'input_height_px' = 9000 is out of range"), std::string::npos) << error;
}

TEST(LoadCameraModel, FilesFromTheModelDirClassesAndRoles) {
  const std::string dir = test::scratchDir("camera_model_dir");
  // Names alone (no network): the names file is found in `dir`.
  { std::ofstream(dir + "/names.txt") << "background\ncar\nvegetation\npole\n"; }
  CameraModelParams p;
  p.dir = dir;
  p.class_names_file = "names.txt";
  p.keep_classes = {"car", "pole"};
  p.vehicle_classes = {"car"};
  p.background_classes = {"Vegetation"};  // case-insensitive
  CameraModel m;
  std::string error;
  ASSERT_TRUE(loadCameraModel(p, false, &m, &error)) << error;
  EXPECT_EQ(m.names, (std::vector<std::string>{"background", "car", "vegetation", "pole"}));
  EXPECT_EQ(m.kept_classes, (std::vector<bool>{false, true, false, true}));
  EXPECT_EQ(m.class_map.categoryOf(1), ObjectCategory::kVehicle);
  EXPECT_EQ(m.class_map.categoryOf(2), ObjectCategory::kNonObject);
  EXPECT_EQ(m.class_map.categoryOf(3), ObjectCategory::kUnknown);  // in no list
  EXPECT_EQ(inModelDir(dir, "/abs/x.png"), "/abs/x.png");
  EXPECT_EQ(inModelDir(dir, "x.png"), dir + "/x.png");
  p.pedestrian_classes = {"person"};  // no such class
  EXPECT_FALSE(loadCameraModel(p, false, &m, &error));
  EXPECT_EQ(error.rfind("model/*_classes: ", 0), 0u) << error;

  // The network too, named relative to `dir`.
  SegmentationModelParams net;
  std::string names_path, why;
  if (!test::makeColourModel(dir, 32, 16, &net, &names_path, &why)) GTEST_SKIP() << why;
  p = CameraModelParams();
  p.network = net;
  p.network.model_path = fs::path(net.model_path).filename().string();
  p.dir = dir;
  ASSERT_TRUE(loadCameraModel(p, true, &m, &error)) << error;
  EXPECT_TRUE(m.network.loaded());
  EXPECT_EQ(m.network.params().model_path, dir + "/" + p.network.model_path);
}

// A 100 x 80 camera, f = 50 px, principal point (50, 40), on the LiDAR origin looking along x:
// LiDAR (x, y, z) -> u = 50 - 50 y / x, v = 40 - 50 z / x. Label map: left half class 1 (car),
// right half class 2 (vegetation). Objects: 1 left, 2 right, 3 behind the camera (unseen).
struct SyntheticCamera {
  PinholeCamera camera;
  Eigen::Isometry3d camera_from_lidar = Eigen::Isometry3d::Identity();
  SegmentationScores scores;
  LabeledCloud points;

  SyntheticCamera() {
    camera.width_px = 100;
    camera.height_px = 80;
    camera.projection << 50, 0, 50, 0, 0, 50, 40, 0, 0, 0, 1, 0;
    Eigen::Matrix3d r;
    r << 0, -1, 0, 0, 0, -1, 1, 0, 0;  // optical (right, down, forward) <- LiDAR
    camera_from_lidar.linear() = r;
    cv::Mat labels(80, 100, CV_8U, cv::Scalar(2));
    labels.colRange(0, 50).setTo(1);
    scores.assignLabels(labels);
    const float ys[3] = {2.0f, -2.0f, 0.0f};
    const float xs[3] = {10.0f, 10.0f, -5.0f};
    for (std::uint32_t id = 1; id <= 3; ++id) {
      for (int k = 0; k < 8; ++k) {
        points.push_back(makeLabeledPoint(xs[id - 1], ys[id - 1] + 0.05f * k, 0.1f * (k % 3), id,
                                          static_cast<std::uint32_t>(points.size())));
      }
    }
  }

  std::vector<ObjectClassLabel> objects(const std::string& label, float confidence) const {
    std::vector<ObjectClassLabel> out;
    for (std::uint32_t id = 1; id <= 3; ++id) out.push_back({id, label, confidence, false});
    return out;
  }
};

const std::vector<std::string> kNames = {"background", "car", "vegetation"};

TEST(CameraLabeller, CameraModeNamesSeenObjectsAndKeepsUnseenOnes) {
  const SyntheticCamera s;
  CameraFusionParams fusion;
  fusion.mode = FusionMode::kCamera;
  CameraLabeller labeller(fusion, ImageLabelTransferParams(), kNames, CameraClassMap());
  auto objects = s.objects("vehicle", 0.7f);
  labeller.label(s.points, s.camera_from_lidar, s.camera, s.scores, &objects);
  EXPECT_EQ(objects[0].class_label, "car");
  EXPECT_FLOAT_EQ(objects[0].class_confidence, 1.0f);
  EXPECT_EQ(objects[1].class_label, "vegetation");
  EXPECT_EQ(objects[2].class_label, "vehicle");  // behind the camera: LiDAR class stays
  EXPECT_FLOAT_EQ(objects[2].class_confidence, 0.7f);
  for (const auto& o : objects) EXPECT_FALSE(o.vetoed);
  EXPECT_EQ(labeller.votes().size(), 3u);

  // Only car votes: the right object is seen but nothing it sees votes -> unknown.
  ImageLabelTransferParams transfer;
  transfer.kept_classes = {false, true, false};
  CameraLabeller kept(fusion, transfer, {"background"}, CameraClassMap());  // names run out
  objects = s.objects("vehicle", 0.7f);
  kept.label(s.points, s.camera_from_lidar, s.camera, s.scores, &objects);
  EXPECT_EQ(objects[0].class_label, "class_1");
  EXPECT_EQ(objects[1].class_label, "unknown");
  EXPECT_FLOAT_EQ(objects[1].class_confidence, 0.0f);

  // Fewer visible points than min_visible_points: the camera has no say.
  fusion.min_visible_points = 9;
  CameraLabeller strict(fusion, ImageLabelTransferParams(), kNames, CameraClassMap());
  objects = s.objects("vehicle", 0.7f);
  strict.label(s.points, s.camera_from_lidar, s.camera, s.scores, &objects);
  EXPECT_EQ(objects[0].class_label, "vehicle");
}

TEST(CameraLabeller, FusedConfirmsVetoesAndKeepsUnseenVerbatim) {
  const SyntheticCamera s;
  CameraClassMap map;
  std::string error;
  ASSERT_TRUE(buildCameraClassMap(kNames, {"car"}, {}, {}, {}, {"vegetation"}, &map, &error));
  CameraFusionParams fusion;
  fusion.mode = FusionMode::kFused;
  CameraLabeller labeller(fusion, ImageLabelTransferParams(), kNames, map);
  auto objects = s.objects("vehicle", 0.6f);
  objects[2].class_label = "bin";  // no category: kept verbatim as it is unseen
  labeller.label(s.points, s.camera_from_lidar, s.camera, s.scores, &objects);
  EXPECT_EQ(objects[0].class_label, "vehicle");
  EXPECT_GT(objects[0].class_confidence, 0.6f);  // confirmed: noisy-or of both
  EXPECT_FALSE(objects[0].vetoed);
  EXPECT_TRUE(objects[1].vetoed);  // all its visible points on background
  EXPECT_EQ(objects[2].class_label, "bin");
  EXPECT_FLOAT_EQ(objects[2].class_confidence, 0.6f);
  EXPECT_FALSE(objects[2].vetoed);

  // A pedestrian the camera sees as a car, without relabel: the LiDAR class stays.
  objects = s.objects("pedestrian", 0.6f);
  labeller.label(s.points, s.camera_from_lidar, s.camera, s.scores, &objects);
  EXPECT_EQ(objects[0].class_label, "pedestrian");
  EXPECT_FLOAT_EQ(objects[0].class_confidence, 0.6f);
}

TEST(CameraLabeller, LidarModeLeavesEveryObjectAsItCame) {
  const SyntheticCamera s;
  CameraFusionParams fusion;
  fusion.mode = FusionMode::kLidar;
  CameraLabeller labeller(fusion, ImageLabelTransferParams(), kNames, CameraClassMap());
  auto objects = s.objects("cyclist", 0.4f);
  labeller.label(s.points, s.camera_from_lidar, s.camera, s.scores, &objects);
  for (const auto& o : objects) {
    EXPECT_EQ(o.class_label, "cyclist");
    EXPECT_FLOAT_EQ(o.class_confidence, 0.4f);
    EXPECT_FALSE(o.vetoed);
  }
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
