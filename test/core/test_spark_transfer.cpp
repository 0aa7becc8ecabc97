// Segmentation scores, the ONNX segmentation model (tiny colour network built at test time) and
// the live image -> object label transfer: synthetic camera with hand-computed projections, and
// KITTI object frames (calibration, label_2 2-D boxes) from the shared data.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <opencv2/core.hpp>

#include "spark_test_model.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace {

using core::ImageLabelTransfer;
using core::ImageLabelTransferParams;
using core::ObjectClassVote;
using core::PinholeCamera;
using core::SegmentationScores;

cv::Mat blob(int c, int h, int w) {
  const int sizes[4] = {1, c, h, w};
  return cv::Mat(4, sizes, CV_32F, cv::Scalar(0));
}
float& at(cv::Mat& b, int c, int y, int x) {
  return b.ptr<float>()[(c * b.size[2] + y) * b.size[3] + x];
}

TEST(SegmentationScores, ArgmaxAndSoftmaxConfidence) {
  cv::Mat b = blob(3, 2, 2);
  // pixel (0,0): logits 1, 3, 2 -> class 1, p = e^3 / (e^1 + e^3 + e^2)
  at(b, 0, 0, 0) = 1.0f;
  at(b, 1, 0, 0) = 3.0f;
  at(b, 2, 0, 0) = 2.0f;
  // pixel (1,1): class 2 with a NaN in another channel is still decided by the comparisons.
  at(b, 2, 1, 1) = 5.0f;
  SegmentationScores s;
  ASSERT_TRUE(s.assign(b, true));
  EXPECT_EQ(s.classes(), 3);
  EXPECT_EQ(s.width(), 2);
  EXPECT_EQ(s.height(), 2);
  float conf = 0.0f;
  EXPECT_EQ(s.classAt(0, 0, &conf), 1);
  EXPECT_NEAR(conf, std::exp(3.0) / (std::exp(1.0) + std::exp(3.0) + std::exp(2.0)), 1e-6);
  EXPECT_EQ(s.classAt(1, 1, &conf), 2);
  EXPECT_NEAR(conf, std::exp(5.0) / (std::exp(5.0) + 2.0), 1e-6);
  // All equal: the lowest id wins with p = 1/3.
  EXPECT_EQ(s.classAt(1, 0, &conf), 0);
  EXPECT_NEAR(conf, 1.0 / 3.0, 1e-6);
  // Probabilities: the best score is the confidence.
  ASSERT_TRUE(s.assign(b, false));
  EXPECT_EQ(s.classAt(0, 0, &conf), 1);
  EXPECT_FLOAT_EQ(conf, 1.0f);  // clamped score 3
  const cv::Mat labels = s.labelImage();
  EXPECT_EQ(labels.at<std::uint8_t>(0, 0), 1);
  EXPECT_EQ(labels.at<std::uint8_t>(1, 1), 2);
}

TEST(SegmentationScores, RejectsBadBlobsAndHandlesLabelMaps) {
  SegmentationScores s;
  EXPECT_FALSE(s.assign(cv::Mat(4, 4, CV_32F), true));  // 2-D
  const int sizes[4] = {2, 3, 4, 4};
  EXPECT_FALSE(s.assign(cv::Mat(4, sizes, CV_32F), true));  // batch 2
  EXPECT_TRUE(s.empty());
  cv::Mat labels(2, 3, CV_8U, cv::Scalar(7));
  labels.at<std::uint8_t>(1, 2) = 255;
  s.assignLabels(labels, 255);
  EXPECT_EQ(s.classIdBound(), 256);
  float conf = 0.0f;
  EXPECT_EQ(s.classAt(0, 0, &conf), 7);
  EXPECT_FLOAT_EQ(conf, 1.0f);
  EXPECT_EQ(s.classAt(2, 1, &conf), -1);
}

TEST(SegmentationModel, RefusesMissingOrBadModels) {
  core::SegmentationModel model;
  core::SegmentationModelParams p;
  std::string error;
  EXPECT_FALSE(model.load(p, &error));
  EXPECT_NE(error.find("model_path is empty"), std::string::npos) << error;
  p.model_path = "/nonexistent/model.onnx";
  EXPECT_FALSE(model.load(p, &error));
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  const std::string dir = test::scratchDir("badmodel");
  p.model_path = dir + "/garbage.onnx";
  { std::ofstream(p.model_path) << "this is not a protobuf"; }
  EXPECT_FALSE(model.load(p, &error));
  EXPECT_FALSE(model.loaded());
  cv::Mat img(10, 10, CV_8UC3);
  SegmentationScores s;
  EXPECT_FALSE(model.run(img, &s, &error));
}

TEST(SegmentationModel, ColourNetworkLabelsPixelsByColour) {
  const std::string dir = test::scratchDir("colour");
  core::SegmentationModelParams p;
  std::string names_path, why;
  if (!test::makeColourModel(dir, 32, 16, &p, &names_path, &why)) GTEST_SKIP() << why;
  core::SegmentationModel model;
  std::string error;
  ASSERT_TRUE(model.load(p, &error)) << error;
  // A 64 x 32 BGR image (twice the network size): four vertical bands.
  cv::Mat img(32, 64, CV_8UC3, cv::Scalar(128, 128, 128));    // grey background
  img(cv::Rect(16, 0, 16, 32)).setTo(cv::Scalar(0, 0, 255));  // red (BGR)
  img(cv::Rect(32, 0, 16, 32)).setTo(cv::Scalar(0, 255, 0));  // green
  img(cv::Rect(48, 0, 16, 32)).setTo(cv::Scalar(255, 0, 0));  // blue
  SegmentationScores s;
  ASSERT_TRUE(model.run(img, &s, &error)) << error;
  EXPECT_EQ(s.classes(), 4);
  EXPECT_EQ(s.width(), 32);
  EXPECT_EQ(s.height(), 16);
  float conf = 0.0f;
  // Logits by hand: grey (0.5 each) -> 4 * relu(0.5, 0, 0, 0) = (2, 0, 0, 0);
  // pure red -> 4 * relu(0.5, 2, -1, -1) = (2, 8, 0, 0).
  EXPECT_EQ(s.classAt(3, 8, &conf), test::kBackground);
  EXPECT_NEAR(conf, std::exp(2.0) / (std::exp(2.0) + 3.0), 1e-4);
  EXPECT_EQ(s.classAt(11, 8, &conf), test::kCar);
  EXPECT_NEAR(conf, std::exp(8.0) / (std::exp(8.0) + std::exp(2.0) + 2.0), 1e-4);
  EXPECT_EQ(s.classAt(19, 8, &conf), test::kVegetation);
  EXPECT_EQ(s.classAt(27, 8, &conf), test::kPole);
  std::vector<std::string> names;
  ASSERT_TRUE(core::readClassNames(names_path, &names, &error)) << error;
  EXPECT_EQ(names, (std::vector<std::string>{"background", "car", "vegetation", "pole"}));
  std::vector<bool> kept;
  ASSERT_TRUE(core::resolveKeptClasses({"car", "3"}, names, s.classIdBound(), &kept, &error));
  EXPECT_EQ(kept, (std::vector<bool>{false, true, false, true}));
  EXPECT_FALSE(core::resolveKeptClasses({"bus"}, names, 4, &kept, &error));
  EXPECT_NE(error.find("'bus'"), std::string::npos);
  EXPECT_FALSE(core::resolveKeptClasses({"4"}, names, 4, &kept, &error));
}

// ---------------------------------------------------------------------------------------------
// Synthetic camera: f = 50 px, principal point (50, 40), 100 x 80 image; LiDAR x forward, y left,
// z up, camera at the LiDAR origin. A LiDAR point (x, y, z) projects to u = 50 - 50 y / x,
// v = 40 - 50 z / x.
PinholeCamera syntheticCamera() {
  PinholeCamera cam;
  cam.projection << 50, 0, 50, 0, 0, 50, 40, 0, 0, 0, 1, 0;
  cam.width_px = 100;
  cam.height_px = 80;
  return cam;
}
Eigen::Isometry3d opticalFromLidar() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  return t;
}
void addPoint(LabeledCloud* c, std::uint32_t id, float x, float y, float z) {
  c->push_back(makeLabeledPoint(x, y, z, id, static_cast<std::uint32_t>(c->size())));
}

// Label map at half the camera resolution (50 x 40): car left of u = 50, vegetation right of
// it, background (not kept) for v >= 60.
SegmentationScores syntheticLabels() {
  cv::Mat labels(40, 50, CV_8U, cv::Scalar(test::kVegetation));
  labels(cv::Rect(0, 0, 25, 40)).setTo(test::kCar);
  labels(cv::Rect(0, 30, 50, 10)).setTo(test::kBackground);
  SegmentationScores s;
  s.assignLabels(labels);
  return s;
}

const ObjectClassVote* find(const std::vector<ObjectClassVote>& v, std::uint32_t id) {
  for (const auto& x : v)
    if (x.object_id == id) return &x;
  return nullptr;
}

TEST(ImageLabelTransfer, VotesOcclusionAndRejection) {
  LabeledCloud pts;
  // Object 7 at 10 m: y in {1.6 .. 2.4} -> u = 42 .. 38, z = +-0.1 -> v = 39.5, 40.5 (car).
  for (float y : {1.6f, 1.8f, 2.0f, 2.2f, 2.4f})
    for (float z : {-0.1f, 0.1f}) addPoint(&pts, 7, 10.0f, y, z);
  // Object 3 at 20 m straight behind object 7 (same pixels): occluded.
  for (float y : {3.2f, 3.6f, 4.0f, 4.4f, 4.8f})
    for (float z : {-0.2f, 0.2f}) addPoint(&pts, 3, 20.0f, y, z);
  // Object 12 at 10 m on the right: 6 points on vegetation (v = 40), 4 on background
  // (z = -5 -> v = 65).
  for (int i = 0; i < 6; ++i) addPoint(&pts, 12, 10.0f, -2.0f - 0.1f * i, 0.0f);
  for (int i = 0; i < 4; ++i) addPoint(&pts, 12, 10.0f, -2.0f - 0.1f * i, -5.0f);
  // Object 20: two points on car pixels (too few), object 21 behind the camera, object 22
  // with NaN points and 3 valid ones out of the image (u = 50 + 50 * 30 / 10 > 100).
  addPoint(&pts, 20, 10.0f, 1.0f, 0.0f);
  addPoint(&pts, 20, 10.0f, 1.1f, 0.0f);
  for (int i = 0; i < 4; ++i) addPoint(&pts, 21, -5.0f, 0.1f * i, 0.0f);
  for (int i = 0; i < 3; ++i) addPoint(&pts, 22, 10.0f, -30.0f, 0.1f * i);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  addPoint(&pts, 22, nan, 0.0f, 0.0f);
  addPoint(&pts, 22, 1.0f, std::numeric_limits<float>::infinity(), 0.0f);

  ImageLabelTransferParams params;
  params.kept_classes = {false, true, true, true};  // background does not vote
  ImageLabelTransfer transfer(params);
  std::vector<ObjectClassVote> votes;
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), syntheticLabels(), &votes);
  ASSERT_EQ(votes.size(), 6u);
  EXPECT_EQ(votes[0].object_id, 3u);  // sorted by id
  const ObjectClassVote* v7 = find(votes, 7);
  EXPECT_EQ(v7->class_id, test::kCar);
  EXPECT_FLOAT_EQ(v7->confidence, 1.0f);
  EXPECT_EQ(v7->considered, 10u);
  const ObjectClassVote* v3 = find(votes, 3);
  EXPECT_EQ(v3->class_id, -1);
  EXPECT_EQ(v3->occluded, 10u);
  EXPECT_EQ(v3->considered, 0u);
  const ObjectClassVote* v12 = find(votes, 12);
  EXPECT_EQ(v12->class_id, test::kVegetation);
  EXPECT_FLOAT_EQ(v12->confidence, 0.6f);  // 6 of 10 considered points
  EXPECT_EQ(v12->considered, 10u);
  const ObjectClassVote* v20 = find(votes, 20);
  EXPECT_EQ(v20->class_id, -1);  // 2 < min_points
  EXPECT_EQ(v20->best_class_id, test::kCar);
  EXPECT_EQ(find(votes, 21)->class_id, -1);
  EXPECT_EQ(find(votes, 21)->considered, 0u);
  EXPECT_EQ(find(votes, 22)->points, 5u);
  EXPECT_EQ(find(votes, 22)->considered, 0u);
  EXPECT_EQ(transfer.stats().non_finite, 2u);
  EXPECT_EQ(transfer.stats().projected, 10u + 10u + 10u + 2u);

  // Without the occlusion test object 3 takes the class of the pixels in front of it.
  params.occlusion_margin_m = 0.0;
  transfer.setParams(params);
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), syntheticLabels(), &votes);
  EXPECT_EQ(find(votes, 3)->class_id, test::kCar);
  // A stricter confidence rejects object 12 (0.6).
  params.min_confidence = 0.7;
  transfer.setParams(params);
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), syntheticLabels(), &votes);
  EXPECT_EQ(find(votes, 12)->class_id, -1);
  EXPECT_EQ(find(votes, 12)->best_class_id, test::kVegetation);
  // Only vegetation kept: object 7 has no vote at all.
  params.kept_classes = {false, false, true, false};
  transfer.setParams(params);
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), syntheticLabels(), &votes);
  EXPECT_EQ(find(votes, 7)->class_id, -1);
  EXPECT_EQ(find(votes, 7)->best_class_id, -1);
}

TEST(ImageLabelTransfer, EmptyAndInvalidInputsGiveUnknown) {
  ImageLabelTransfer transfer;
  std::vector<ObjectClassVote> votes(3);
  transfer.transfer(LabeledCloud(), opticalFromLidar(), syntheticCamera(), syntheticLabels(),
                    &votes);
  EXPECT_TRUE(votes.empty());
  LabeledCloud pts;
  for (int i = 0; i < 5; ++i) addPoint(&pts, 1, 10.0f, 2.0f + 0.01f * i, 0.0f);
  PinholeCamera bad = syntheticCamera();
  bad.projection(0, 0) = std::numeric_limits<double>::quiet_NaN();
  transfer.transfer(pts, opticalFromLidar(), bad, syntheticLabels(), &votes);
  ASSERT_EQ(votes.size(), 1u);
  EXPECT_EQ(votes[0].class_id, -1);
  EXPECT_EQ(votes[0].points, 5u);
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), SegmentationScores(), &votes);
  EXPECT_EQ(votes[0].class_id, -1);
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), syntheticLabels(), &votes);
  EXPECT_EQ(votes[0].class_id, test::kCar);
  // Ids far above the point count take the sorted-list path: same votes, ids in order.
  for (int i = 0; i < 4; ++i) addPoint(&pts, 4000000000u, 10.0f, -2.0f - 0.01f * i, 0.0f);
  transfer.transfer(pts, opticalFromLidar(), syntheticCamera(), syntheticLabels(), &votes);
  ASSERT_EQ(votes.size(), 2u);
  EXPECT_EQ(votes[0].object_id, 1u);
  EXPECT_EQ(votes[0].class_id, test::kCar);
  EXPECT_EQ(votes[1].object_id, 4000000000u);
  EXPECT_EQ(votes[1].class_id, test::kVegetation);
  EXPECT_EQ(votes[1].points, 4u);
}

// ---------------------------------------------------------------------------------------------
// KITTI object frames: LiDAR points inside a labelled 3-D box project inside its 2-D box.
struct KittiFrame {
  core::KittiCalibration calib;
  std::vector<core::KittiLabel> labels;
  CloudXYZIRT cloud;
  PinholeCamera camera;
  Eigen::Isometry3d cam_from_velo = Eigen::Isometry3d::Identity();
};

bool loadKitti(const std::string& id, KittiFrame* f, std::string* error) {
  const std::string dir = std::string(UD_SHARED_DATA) + "/kitti_object/";
  if (!core::readKittiCalibration(dir + "calib/" + id + ".txt", &f->calib, error) ||
      !core::readKittiLabels(dir + "label_2/" + id + ".txt", &f->labels, error) ||
      !core::readKittiBin(dir + "velodyne/" + id + ".bin", &f->cloud, error) ||
      !core::readPngSize(dir + "image_2/" + id + ".png", &f->camera.width_px, &f->camera.height_px))
    return false;
  f->camera.projection = f->calib.p2;
  f->cam_from_velo.linear() = f->calib.r0_rect * f->calib.tr_velo_to_cam.leftCols<3>();
  f->cam_from_velo.translation() = f->calib.r0_rect * f->calib.tr_velo_to_cam.col(3);
  return true;
}

// Points strictly inside the box (20 cm above its bottom, so the road under it is excluded).
std::vector<std::size_t> pointsInLabel(const KittiFrame& f, const core::KittiLabel& l) {
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < f.cloud.size(); ++i) {
    const auto& p = f.cloud[i];
    const Eigen::Vector3d b =
        core::kittiBoxLocal(l, f.calib.veloToRect(Eigen::Vector3d(p.x, p.y, p.z)));
    if (std::fabs(b.x()) <= 0.5 * l.length_m && b.y() >= 0.2 && b.y() <= l.height_m &&
        std::fabs(b.z()) <= 0.5 * l.width_m)
      in.push_back(i);
  }
  return in;
}

TEST(ImageLabelTransferKitti, BoxPointsProjectIntoTheirTwoDimensionalBox) {
  const std::string dir = std::string(UD_SHARED_DATA) + "/kitti_object";
  if (!std::filesystem::exists(dir + "/image_2/000000.png"))
    GTEST_SKIP() << "KITTI object frames not found under " << dir;
  int checked = 0;
  for (const char* id : {"000000", "000001", "000002", "000003", "000004", "000005"}) {
    KittiFrame f;
    std::string error;
    ASSERT_TRUE(loadKitti(id, &f, &error)) << id << ": " << error;
    for (const core::KittiLabel& l : f.labels) {
      if (l.type == "DontCare") continue;
      const auto in = pointsInLabel(f, l);
      if (in.size() < 10) continue;
      std::size_t inside = 0, in_image = 0;
      for (const std::size_t i : in) {
        const Eigen::Vector3d p(f.cloud[i].x, f.cloud[i].y, f.cloud[i].z);
        double u = 0, v = 0;
        ASSERT_TRUE(f.camera.project(f.cam_from_velo * p, 0.1, &u, &v));
        // Same pixel by the dataset reader's own route (veloToRect, then P2).
        double u2 = 0, v2 = 0;
        ASSERT_TRUE(f.calib.project(p, &u2, &v2));
        EXPECT_NEAR(u, u2, 1e-6);
        EXPECT_NEAR(v, v2, 1e-6);
        if (u < 0 || v < 0 || u >= f.camera.width_px || v >= f.camera.height_px) continue;
        ++in_image;
        const double m = 3.0;  // [px] label boxes are hand-drawn
        inside +=
            u >= l.bbox[0] - m && u <= l.bbox[2] + m && v >= l.bbox[1] - m && v <= l.bbox[3] + m;
      }
      if (in_image < 10) continue;
      ++checked;
      EXPECT_GE(static_cast<double>(inside) / in_image, 0.95)
          << id << " " << l.type << " at " << l.location.transpose() << ": " << inside << "/"
          << in_image;
    }
  }
  EXPECT_GE(checked, 9);  // labelled objects with >= 10 points in the image (9 in the six frames)
}

// Oracle segmentation painted from label_2 2-D boxes (far boxes first, near ones over them):
// the objects made of the points in the labelled 3-D boxes must get their own class back.
TEST(ImageLabelTransferKitti, OracleMasksGiveEachLabelledObjectItsClass) {
  const std::string dir = std::string(UD_SHARED_DATA) + "/kitti_object";
  if (!std::filesystem::exists(dir + "/image_2/000000.png"))
    GTEST_SKIP() << "KITTI object frames not found under " << dir;
  const std::map<std::string, int> class_ids = {
      {"Car", 1},     {"Van", 2},  {"Truck", 3}, {"Pedestrian", 4}, {"Person_sitting", 5},
      {"Cyclist", 6}, {"Tram", 7}, {"Misc", 8}};
  ImageLabelTransfer transfer;
  int objects = 0, correct = 0;
  for (const char* id : {"000000", "000001", "000002", "000003", "000004", "000005"}) {
    KittiFrame f;
    std::string error;
    ASSERT_TRUE(loadKitti(id, &f, &error)) << error;
    std::vector<std::size_t> order(f.labels.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return f.labels[a].location.z() > f.labels[b].location.z();
    });
    cv::Mat mask(f.camera.height_px, f.camera.width_px, CV_8U, cv::Scalar(0));
    LabeledCloud pts;
    std::map<std::uint32_t, int> truth;
    for (const std::size_t k : order) {
      const core::KittiLabel& l = f.labels[k];
      const auto it = class_ids.find(l.type);
      if (it == class_ids.end()) continue;
      const cv::Point a(static_cast<int>(l.bbox[0]), static_cast<int>(l.bbox[1]));
      const cv::Point b(static_cast<int>(l.bbox[2]), static_cast<int>(l.bbox[3]));
      mask(cv::Rect(a, b + cv::Point(1, 1)) & cv::Rect(0, 0, mask.cols, mask.rows))
          .setTo(it->second);
      for (const std::size_t i : pointsInLabel(f, l))
        addPoint(&pts, static_cast<std::uint32_t>(k + 1), f.cloud[i].x, f.cloud[i].y, f.cloud[i].z);
      if (l.occluded == 0 && l.truncated < 0.3)
        truth[static_cast<std::uint32_t>(k + 1)] = it->second;
    }
    SegmentationScores scores;
    scores.assignLabels(mask, 0);
    std::vector<ObjectClassVote> votes;
    transfer.transfer(pts, f.cam_from_velo, f.camera, scores, &votes);
    for (const ObjectClassVote& v : votes) {
      const auto t = truth.find(v.object_id);
      if (t == truth.end() || v.points < 20) continue;
      ++objects;
      correct += v.class_id == t->second;
      EXPECT_EQ(v.class_id, t->second) << id << " object " << v.object_id << " conf "
                                       << v.confidence << " considered " << v.considered;
    }
  }
  EXPECT_GE(objects, 8);
  EXPECT_EQ(correct, objects);
}

}  // namespace
}  // namespace urban_detection
