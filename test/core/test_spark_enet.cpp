// the camera stage with a real network. The fusion rule, the owned label map the
// inference thread hands over, and the mask history, and ENet (Cityscapes,
// Torch7, ../shared/data/models/enet-cityscapes) on a real KITTI frame: the near car of frame
// 000003 must come out as a vehicle. Tests that need the shared data skip visibly without it.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/spark/kitti_spark_eval.h"
#include "urban_detection/core/spark/mask_history.h"
#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace {

using core::CameraEvidence;
using core::CameraFusionParams;
using core::FusionMode;
using core::ObjectCategory;

const std::vector<std::string> kEnetNames = {
    "Unlabeled",    "Road",        "Sidewalk",   "Building", "Wall",       "Fence",  "Pole",
    "TrafficLight", "TrafficSign", "Vegetation", "Terrain",  "Sky",        "Person", "Rider",
    "Car",          "Truck",       "Bus",        "Train",    "Motorcycle", "Bicycle"};

core::CameraClassMap enetMap() {
  core::CameraClassMap map;
  std::string error;
  EXPECT_TRUE(core::buildCameraClassMap(
      kEnetNames, {"Car", "Truck", "Bus"}, {"Person"}, {"Rider", "Bicycle", "Motorcycle"},
      {"Pole", "TrafficSign", "TrafficLight"},
      {"Road", "Sidewalk", "Building", "Wall", "Fence", "Vegetation", "Terrain", "Sky"}, &map,
      &error))
      << error;
  return map;
}

// Per-class summed confidences of an object with `visible` points.
CameraEvidence evidence(const std::vector<std::pair<const char*, float>>& shares, int visible) {
  std::vector<float> scores(kEnetNames.size(), 0.0f);
  for (const auto& [name, share] : shares) {
    const auto it = std::find(kEnetNames.begin(), kEnetNames.end(), name);
    scores[static_cast<std::size_t>(it - kEnetNames.begin())] = share * visible;
  }
  return core::cameraEvidence(scores.data(), static_cast<int>(scores.size()),
                              static_cast<std::uint32_t>(visible), enetMap());
}

TEST(CameraClassMap, MapsNamesCaseInsensitiveAndRefusesUnknownOrTwice) {
  const core::CameraClassMap map = enetMap();
  EXPECT_EQ(map.categoryOf(14), ObjectCategory::kVehicle);     // Car
  EXPECT_EQ(map.categoryOf(12), ObjectCategory::kPedestrian);  // Person
  EXPECT_EQ(map.categoryOf(9), ObjectCategory::kNonObject);    // Vegetation
  EXPECT_EQ(map.categoryOf(17), ObjectCategory::kUnknown);     // Train: in no list
  EXPECT_EQ(map.categoryOf(-1), ObjectCategory::kUnknown);
  EXPECT_EQ(map.categoryOf(99), ObjectCategory::kUnknown);
  core::CameraClassMap m;
  std::string error;
  EXPECT_TRUE(core::buildCameraClassMap(kEnetNames, {"car", "15"}, {}, {}, {}, {}, &m, &error));
  EXPECT_EQ(m.categoryOf(15), ObjectCategory::kVehicle);
  EXPECT_FALSE(core::buildCameraClassMap(kEnetNames, {"Tram"}, {}, {}, {}, {}, &m, &error));
  EXPECT_NE(error.find("'Tram'"), std::string::npos) << error;
  EXPECT_FALSE(core::buildCameraClassMap(kEnetNames, {"Car"}, {}, {}, {}, {"Car"}, &m, &error));
  EXPECT_NE(error.find("both"), std::string::npos) << error;
}

TEST(CameraFusion, EvidenceSharesPerCategory) {
  const CameraEvidence e = evidence({{"Car", 0.5f}, {"Truck", 0.2f}, {"Road", 0.2f}}, 10);
  EXPECT_EQ(e.visible, 10u);
  EXPECT_EQ(e.best, ObjectCategory::kVehicle);
  EXPECT_NEAR(e.best_share, 0.7f, 1e-5);
  EXPECT_NEAR(e.background_share(), 0.2f, 1e-5);
  const CameraEvidence none = core::cameraEvidence(nullptr, 0, 10, enetMap());
  EXPECT_EQ(none.best, ObjectCategory::kUnknown);
}

TEST(CameraFusion, FusedRuleVetoAgreementAndUnseenObjects) {
  CameraFusionParams p;
  p.mode = FusionMode::kFused;
  // Unseen (too few visible points): LiDAR class and confidence stay.
  auto r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.7f, evidence({{"Road", 1.0f}}, 3), p);
  EXPECT_EQ(r.category, ObjectCategory::kVehicle);
  EXPECT_FLOAT_EQ(r.confidence, 0.7f);
  EXPECT_FALSE(r.camera_used);
  // Veto: most visible points on background classes.
  r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.7f,
                            evidence({{"Vegetation", 0.5f}, {"Building", 0.2f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kNonObject);
  EXPECT_TRUE(r.vetoed);
  // Agreement: noisy-or confidence.
  r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.6f, evidence({{"Car", 0.5f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kVehicle);
  EXPECT_NEAR(r.confidence, 1.0f - 0.4f * 0.5f, 1e-5);
  // Disagreement without relabel: LiDAR stays; with relabel and a confident camera: camera.
  r = core::fuseObjectClass(ObjectCategory::kPedestrian, 0.6f, evidence({{"Car", 0.8f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kPedestrian);
  EXPECT_FLOAT_EQ(r.confidence, 0.6f);
  p.relabel = true;
  r = core::fuseObjectClass(ObjectCategory::kPedestrian, 0.6f, evidence({{"Car", 0.8f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kVehicle);
  EXPECT_NEAR(r.confidence, 0.8f, 1e-5);
  r = core::fuseObjectClass(ObjectCategory::kPedestrian, 0.6f, evidence({{"Car", 0.3f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kPedestrian);
  // A veto share above 1 disables the veto.
  p.veto_share = 1.01;
  r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.7f, evidence({{"Road", 1.0f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kVehicle);
  // Lidar mode: never changes anything.
  p.mode = FusionMode::kLidar;
  p.veto_share = 0.6;
  r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.7f, evidence({{"Road", 1.0f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kVehicle);
  EXPECT_FALSE(r.camera_used);
}

TEST(CameraFusion, CameraModeTakesTheCameraCategory) {
  CameraFusionParams p;
  p.mode = FusionMode::kCamera;
  auto r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.9f,
                                 evidence({{"Person", 0.6f}, {"Road", 0.3f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kPedestrian);
  EXPECT_NEAR(r.confidence, 0.6f, 1e-5);
  r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.9f, evidence({{"Sky", 0.7f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kNonObject);
  r = core::fuseObjectClass(ObjectCategory::kVehicle, 0.9f, evidence({{"Train", 0.9f}}, 20), p);
  EXPECT_EQ(r.category, ObjectCategory::kUnknown);  // no mapped class: camera unsure
}

TEST(CameraFusion, ValidateAndParse) {
  CameraFusionParams p;
  EXPECT_EQ(core::validate(p), "");
  p.veto_share = 0.0;
  EXPECT_NE(core::validate(p).find("veto_share"), std::string::npos);
  p = CameraFusionParams();
  p.min_visible_points = 0;
  EXPECT_NE(core::validate(p).find("min_visible_points"), std::string::npos);
  FusionMode m = FusionMode::kLidar;
  EXPECT_TRUE(core::parseFusionMode("fused", &m));
  EXPECT_EQ(m, FusionMode::kFused);
  EXPECT_FALSE(core::parseFusionMode("both", &m));
  EXPECT_STREQ(core::toString(FusionMode::kCamera), "camera");
}

// The owned label map handed to another thread gives the same class and confidence as the
// scores it came from, at every pixel (random logits, ties impossible in practice).
TEST(SegmentationScores, ReducedLabelMapMatchesScoresEverywhere) {
  std::mt19937 rng(27);
  std::normal_distribution<float> n(0.0f, 3.0f);
  const int sizes[4] = {1, 7, 9, 13};
  cv::Mat blob(4, sizes, CV_32F);
  for (std::size_t i = 0; i < blob.total(); ++i) blob.ptr<float>()[i] = n(rng);
  blob.ptr<float>()[5] = std::numeric_limits<float>::quiet_NaN();  // class 0 at pixel 5: NaN
  for (const bool softmax : {true, false}) {
    core::SegmentationScores scores, reduced;
    ASSERT_TRUE(scores.assign(blob, softmax));
    scores.reduceTo(&reduced);
    ASSERT_EQ(reduced.width(), 13);
    ASSERT_EQ(reduced.height(), 9);
    EXPECT_EQ(reduced.classes(), 1);
    std::vector<int> expected;
    for (int y = 0; y < 9; ++y) {
      for (int x = 0; x < 13; ++x) {
        float c1 = 0, c2 = 0;
        const int a = scores.classAt(x, y, &c1);
        const int b = reduced.classAt(x, y, &c2);
        EXPECT_EQ(a, b) << x << "," << y;
        EXPECT_NEAR(c1, c2, 1e-5) << x << "," << y;
        expected.push_back(a);
      }
    }
    EXPECT_EQ(expected[5], -1);  // the NaN pixel has no class
    // The reduced map owns its memory: new scores in the blob do not change it.
    for (std::size_t i = 0; i < blob.total(); ++i) blob.ptr<float>()[i] = n(rng);
    for (int y = 0, k = 0; y < 9; ++y) {
      for (int x = 0; x < 13; ++x, ++k) {
        float c = 0;
        EXPECT_EQ(reduced.classAt(x, y, &c), expected[static_cast<std::size_t>(k)]);
      }
    }
    blob.ptr<float>()[5] = std::numeric_limits<float>::quiet_NaN();
  }
}

TEST(MaskHistory, NewestWithinTheGap) {
  core::MaskHistory<int> h(3);
  EXPECT_EQ(h.newestWithin(10.0, 1.0), nullptr);
  for (int k = 0; k < 5; ++k) h.push(10.0 + 0.1 * k, std::make_shared<const int>(k));
  double gap = 0;
  EXPECT_EQ(*h.newestWithin(10.2, 0.05, &gap), 2);
  EXPECT_NEAR(gap, 0.0, 1e-9);
  EXPECT_EQ(*h.newestWithin(10.25, 0.2), 4);       // newest first
  EXPECT_EQ(h.newestWithin(10.0, 0.05), nullptr);  // 10.0 and 10.1 fell out (capacity 3)
  EXPECT_EQ(h.newestWithin(11.0, 0.5), nullptr);
}

TEST(SegmentationModel, RefusesAGarbageTorchFile) {
  const auto dir = std::filesystem::temp_directory_path() / "ud_spark_enet_garbage";
  std::filesystem::create_directories(dir);
  core::SegmentationModelParams p;
  p.model_path = (dir / "garbage.net").string();
  { std::ofstream(p.model_path) << "not a torch file"; }
  core::SegmentationModel model;
  std::string error;
  EXPECT_FALSE(model.load(p, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(model.loaded());
  std::filesystem::remove_all(dir);
}

// ENet (Cityscapes) on KITTI 000003: the car 13 m ahead is a Car (a vehicle) to the camera, at
// both input sizes, from the scores and from the owned label map alike.
TEST(SegmentationModelEnet, NearCarOfKittiFrameIsAVehicle) {
  const std::string model_dir = std::string(UD_SHARED_DATA) + "/models/enet-cityscapes";
  const std::string kitti = std::string(UD_SHARED_DATA) + "/kitti_object";
  if (!std::filesystem::exists(model_dir + "/enet-model.net"))
    GTEST_SKIP() << "ENet not found under " << model_dir << " (shared data absent)";
  if (!std::filesystem::exists(kitti + "/image_2/000003.png"))
    GTEST_SKIP() << "KITTI object frames not found under " << kitti;
  core::SegmentationModelParams p;
  p.model_path = model_dir + "/enet-model.net";
  p.mean = {0.0, 0.0, 0.0};
  p.scale = {1.0 / 255, 1.0 / 255, 1.0 / 255};
  p.input_rgb = true;
  core::SegmentationModel model;
  std::string error;
  ASSERT_TRUE(model.load(p, &error)) << error;
  std::vector<std::string> names;
  ASSERT_TRUE(core::readClassNames(model_dir + "/enet-classes.txt", &names, &error)) << error;
  ASSERT_EQ(names, kEnetNames);

  core::KittiSparkFrame f;
  ASSERT_TRUE(core::loadKittiSparkFrame(kitti, "000003", true, &f, &error)) << error;
  // The near car: the Car label 13 m ahead.
  std::size_t car = f.labels.size();
  for (std::size_t k = 0; k < f.labels.size(); ++k)
    if (f.labels[k].type == "Car" && f.labels[k].location.z() < 15.0) car = k;
  ASSERT_LT(car, f.labels.size());
  EXPECT_LT(core::kittiLabelRange(f, f.labels[car]), 15.0);
  LabeledCloud points;
  core::kittiLabelObjects(f, &points);
  // Cityscapes' size (the image squeezed) and the preset's (the image at its own scale): a
  // fresh network per size (setInputSize reads the file again).
  for (const cv::Size size : {cv::Size(1024, 512), cv::Size(1248, 384)}) {
    SCOPED_TRACE(std::to_string(size.width) + "x" + std::to_string(size.height));
    ASSERT_TRUE(model.setInputSize(size.width, size.height, &error)) << error;
    core::SegmentationScores scores, reduced;
    ASSERT_TRUE(model.run(f.image, &scores, &error)) << error;
    ASSERT_EQ(scores.classes(), 20);
    ASSERT_EQ(scores.width(), size.width);
    ASSERT_EQ(scores.height(), size.height);
    scores.reduceTo(&reduced);
    core::ImageLabelTransfer transfer;
    std::vector<core::ObjectClassVote> votes;
    for (const core::SegmentationScores* s : {&scores, &reduced}) {
      transfer.transfer(points, f.camera_from_velo, f.camera, *s, &votes);
      const auto it = std::find_if(votes.begin(), votes.end(), [&](const core::ObjectClassVote& v) {
        return v.object_id == car + 1;
      });
      ASSERT_NE(it, votes.end());
      EXPECT_GT(it->considered, 100u);
      ASSERT_GE(it->class_id, 0);
      EXPECT_EQ(names[static_cast<std::size_t>(it->class_id)], "Car")
          << "voted " << it->class_id << " share " << it->confidence;
      const CameraEvidence e =
          core::cameraEvidence(transfer.classScores(static_cast<std::size_t>(it - votes.begin())),
                               transfer.classBound(), it->considered, enetMap());
      EXPECT_EQ(e.best, ObjectCategory::kVehicle);
      EXPECT_GT(e.best_share, 0.6f);
      EXPECT_LT(e.background_share(), 0.3f);
    }
  }
}

}  // namespace
}  // namespace urban_detection
