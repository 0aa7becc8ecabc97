// Offline SPARK workflow: capture path, orthographic z-buffer rendering, back-projection,
// DBSCAN (against a brute-force oracle), instances on a synthetic scene with known classes
// segmented by the tiny colour network, JSON export read back with OpenCV's JSON parser.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <opencv2/core.hpp>
#include <random>
#include <set>

#include "spark_test_model.h"
#include "urban_detection/core/spark/spark_capture.h"
#include "urban_detection/core/spark/spark_instances.h"
#include "urban_detection/core/spark/spark_scene.h"
#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace {

using core::CapturePathParams;
using core::OrthoCamera;

TEST(SparkCapture, PosesEveryIntervalAlongThePolyline) {
  CapturePathParams p;
  p.path = {{0, 0, 2}, {10, 0, 2}, {10, 10, 2}};
  p.interval_m = 4.0;
  p.rotations = 2;
  const auto poses = core::capturePoses(p);
  // Capture points at arc length 0, 4, 8 (first segment), 12, 16, 20 (second): (10, 2), ...
  ASSERT_EQ(poses.size(), 12u);
  const double xs[6] = {0, 4, 8, 10, 10, 10}, ys[6] = {0, 0, 0, 2, 6, 10};
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(poses[2 * k].position.x(), xs[k], 1e-9) << k;
    EXPECT_NEAR(poses[2 * k].position.y(), ys[k], 1e-9) << k;
    EXPECT_NEAR(poses[2 * k + 1].position.x(), xs[k], 1e-9);
  }
  EXPECT_NEAR(poses[0].yaw_deg, 0.0, 1e-9);
  EXPECT_NEAR(poses[1].yaw_deg, 180.0, 1e-9);
  EXPECT_NEAR(poses[6].yaw_deg, 90.0, 1e-9);
  EXPECT_NEAR(poses[7].yaw_deg, 270.0, 1e-9);
}

TEST(SparkCapture, OrthographicProjectionByHand) {
  // Yaw 0, pitch 0: forward +x, right -y, down -z. 10 x 10 px, 1 m/px, centre at the origin.
  const OrthoCamera c = OrthoCamera::make({0, 0, 0}, 0.0, 0.0, 10, 10, 1.0, 100.0);
  double x = 0, y = 0, d = 0;
  c.project({5, -2, 1}, &x, &y, &d);
  EXPECT_NEAR(x, 7.0, 1e-12);  // right = 2 m -> 5 + 2
  EXPECT_NEAR(y, 4.0, 1e-12);  // down = -1 m -> 5 - 1
  EXPECT_NEAR(d, 5.0, 1e-12);
  EXPECT_TRUE(c.unproject(x, y, d).isApprox(Eigen::Vector3d(5, -2, 1), 1e-12));
  // Nadir camera: forward is -z, whatever the yaw.
  const OrthoCamera n = OrthoCamera::make({0, 0, 10}, 37.0, -90.0, 10, 10, 1.0, 100.0);
  EXPECT_TRUE(n.rotation.row(2).transpose().isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_NEAR(n.rotation.determinant(), 1.0, 1e-12);
}

TEST(SparkCapture, ZBufferKeepsTheFirstPointHit) {
  CloudXYZIRT cloud;
  cloud.push_back(makePoint(5, -2, 1));  // pixel (7, 4), depth 5
  cloud.push_back(makePoint(3, -2, 1));  // same pixel, nearer
  cloud.push_back(makePoint(-3, 0, 0));  // behind the camera
  cloud.push_back(makePoint(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  cloud.push_back(makePoint(50, 100, 0));  // outside the image
  const std::vector<cv::Vec3b> colours = {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {4, 4, 4}, {5, 5, 5}};
  const OrthoCamera c = OrthoCamera::make({0, 0, 0}, 0.0, 0.0, 10, 10, 1.0, 100.0);
  core::OrthoRenderer r;
  cv::Mat img;
  EXPECT_EQ(r.render(cloud, colours, c, 0, &img), 2u);
  EXPECT_EQ(r.hit(7, 4), 1);
  EXPECT_FLOAT_EQ(r.depth(7, 4), 3.0f);
  EXPECT_EQ(img.at<cv::Vec3b>(4, 7), cv::Vec3b(2, 2, 2));
  EXPECT_EQ(r.hit(6, 4), -1);
  EXPECT_EQ(cv::countNonZero(img.reshape(1) != 0), 3);  // one pixel, three channels
  // Radius 1: a 3 x 3 splat.
  EXPECT_EQ(r.render(cloud, colours, c, 1, &img), 2u);
  for (int y = 3; y <= 5; ++y)
    for (int x = 6; x <= 8; ++x) EXPECT_EQ(r.hit(x, y), 1) << x << "," << y;
  EXPECT_EQ(r.hit(9, 4), -1);
}

TEST(SparkCapture, PathJsonIsValidated) {
  const std::string dir = test::scratchDir("pathjson");
  auto write = [&](const std::string& text) {
    std::ofstream(dir + "/p.json") << text;
    return dir + "/p.json";
  };
  CapturePathParams p;
  std::string error;
  ASSERT_TRUE(core::readCapturePathJson(
      write(R"({"path": [[0, 0, 3], [30.5, 0, 3]], "interval_m": 2.5, "rotations": 3,
                "pitch_deg": -20, "image_width_px": 320, "image_height_px": 200,
                "metres_per_pixel": 0.1, "colour": "height"})"),
      &p, &error))
      << error;
  ASSERT_EQ(p.path.size(), 2u);
  EXPECT_DOUBLE_EQ(p.path[1].x(), 30.5);
  EXPECT_DOUBLE_EQ(p.interval_m, 2.5);
  EXPECT_EQ(p.rotations, 3);
  EXPECT_EQ(p.image_height_px, 200);
  EXPECT_EQ(p.colour, "height");
  EXPECT_DOUBLE_EQ(p.max_depth_m, 80.0);  // default kept
  EXPECT_FALSE(
      core::readCapturePathJson(write(R"({"path": [[0,0,0]], "rotation": 3})"), &p, &error));
  EXPECT_NE(error.find("unknown key 'rotation'"), std::string::npos) << error;
  EXPECT_FALSE(core::readCapturePathJson(write(R"({"path": [[0,0]]})"), &p, &error));
  EXPECT_FALSE(core::readCapturePathJson(write(R"({"path": []})"), &p, &error));
  EXPECT_FALSE(
      core::readCapturePathJson(write(R"({"path": [[0,0,0]], "rotations": 0})"), &p, &error));
  EXPECT_NE(error.find("rotations"), std::string::npos) << error;
  EXPECT_FALSE(
      core::readCapturePathJson(write(R"({"path": [[0,0,0]], "rotations": 2.5})"), &p, &error));
  EXPECT_FALSE(
      core::readCapturePathJson(write(R"({"path": [[0,0,0]], "colour": "x"})"), &p, &error));
  EXPECT_FALSE(core::readCapturePathJson(write("{\"path\": [[0,0,0]"), &p, &error));
  EXPECT_FALSE(core::readCapturePathJson(dir + "/missing.json", &p, &error));
}

// Brute-force DBSCAN facts the kd-tree version must satisfy: core points (>= min_pts within
// eps, itself included) connected through core points share a cluster; points within eps of
// no core point are noise; a border point belongs to the cluster of one of its core neighbours.
TEST(SparkDbscan, MatchesBruteForceDefinition) {
  std::mt19937 rng(7);
  std::normal_distribution<float> g(0.0f, 0.4f);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f);
  CloudXYZIRT cloud;
  for (const Eigen::Vector3f& c :
       {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(3, 0, 0), Eigen::Vector3f(-4, 5, 1)})
    for (int i = 0; i < 120; ++i)
      cloud.push_back(makePoint(c.x() + g(rng), c.y() + g(rng), c.z() + g(rng)));
  for (int i = 0; i < 60; ++i) cloud.push_back(makePoint(u(rng), u(rng), u(rng)));
  cloud.push_back(makePoint(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  std::vector<std::uint32_t> members;
  for (std::uint32_t i = 0; i < cloud.size(); i += 1) members.push_back(i);
  const double eps = 0.35;
  const int min_pts = 5;
  std::vector<int> cluster;
  const int k = core::dbscan(cloud, members, eps, min_pts, &cluster);
  const std::size_t n = members.size();
  auto near = [&](std::size_t a, std::size_t b) {
    const auto &p = cloud[a], &q = cloud[b];
    const float dx = p.x - q.x, dy = p.y - q.y, dz = p.z - q.z;
    return dx * dx + dy * dy + dz * dz <= eps * eps;
  };
  std::vector<bool> core_pt(n, false);
  for (std::size_t a = 0; a + 1 < n; ++a) {  // the NaN point (last) is never core
    int c = 0;
    for (std::size_t b = 0; b + 1 < n; ++b) c += near(a, b);
    core_pt[a] = c >= min_pts;
  }
  // Connected components of core points (union-find).
  std::vector<std::size_t> parent(n);
  for (std::size_t i = 0; i < n; ++i) parent[i] = i;
  std::function<std::size_t(std::size_t)> root = [&](std::size_t i) {
    return parent[i] == i ? i : parent[i] = root(parent[i]);
  };
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b)
      if (core_pt[a] && core_pt[b] && near(a, b)) parent[root(a)] = root(b);
  std::set<std::size_t> components;
  for (std::size_t a = 0; a < n; ++a)
    if (core_pt[a]) components.insert(root(a));
  EXPECT_EQ(static_cast<std::size_t>(k), components.size());
  EXPECT_GE(k, 3);
  for (std::size_t a = 0; a < n; ++a) {
    if (core_pt[a]) {
      ASSERT_GE(cluster[a], 0);
      for (std::size_t b = 0; b < n; ++b) {
        if (core_pt[b]) {
          EXPECT_EQ(cluster[a] == cluster[b], root(a) == root(b));
        }
      }
      continue;
    }
    bool border = false, joined_neighbour = false;
    for (std::size_t b = 0; b + 1 < n; ++b) {
      if (core_pt[b] && near(a, b)) {
        border = true;
        joined_neighbour |= cluster[a] == cluster[b];
      }
    }
    if (border) {
      EXPECT_TRUE(joined_neighbour) << a;
    } else {
      EXPECT_EQ(cluster[a], -1) << a;
    }
  }
  EXPECT_EQ(cluster.back(), -1);  // NaN
}

TEST(SparkInstances, VotesClassifyAndBoxesCut) {
  CloudXYZIRT cloud;
  for (int i = 0; i < 20; ++i) cloud.push_back(makePoint(0.1f * i, 0, 0));       // 0..19: class 1
  for (int i = 0; i < 20; ++i) cloud.push_back(makePoint(10 + 0.1f * i, 0, 0));  // 20..39: class 2
  cloud.push_back(makePoint(0.5f, 0.05f, 0.0f));  // 40: inside the first box, never hit
  std::vector<int> point_class(cloud.size(), -1);
  for (int i = 0; i < 20; ++i) point_class[i] = 1;
  for (int i = 20; i < 40; ++i) point_class[i] = 2;
  core::SparkParams params;
  params.dbscan_eps_m = 0.15;
  params.dbscan_min_points = 2;
  params.min_instance_points = 5;
  std::vector<core::SparkInstance> inst;
  core::buildInstances(cloud, point_class, params, &inst);
  ASSERT_EQ(inst.size(), 2u);
  EXPECT_EQ(inst[0].class_id, 1);
  EXPECT_EQ(inst[0].id, 1u);
  EXPECT_EQ(inst[0].indices.size(), 20u);
  EXPECT_TRUE(inst[0].min_pt.isApprox(Eigen::Vector3f(0, 0, 0)));
  EXPECT_TRUE(inst[0].max_pt.isApprox(Eigen::Vector3f(1.9f, 0, 0)));
  EXPECT_NEAR(inst[0].centroid.x(), 0.95f, 1e-5);
  std::vector<std::uint32_t> box;
  core::pointsInBox(cloud, inst[0], 0.1, &box);
  EXPECT_EQ(box.size(), 21u);  // the 20 hits and point 40
  std::vector<std::uint32_t> kept;
  core::cutOutClasses(cloud, inst, {false, true, false}, 0.1, &kept);
  ASSERT_EQ(kept.size(), 20u);
  EXPECT_EQ(kept.front(), 20u);
  params.min_instance_points = 21;
  core::buildInstances(cloud, point_class, params, &inst);
  EXPECT_TRUE(inst.empty());
}

// The whole workflow on the synthetic scene: render along a path, segment with the colour
// network, cast every 4th pixel back, DBSCAN per class.
TEST(SparkWorkflow, SyntheticSceneGivesTheKnownInstances) {
  const std::string dir = test::scratchDir("workflow");
  CapturePathParams path;
  path.path = {{0, 0, 3}, {35, 0, 3}};
  path.interval_m = 5.0;
  path.rotations = 4;
  path.pitch_deg = -25.0;
  path.image_width_px = 320;
  path.image_height_px = 240;
  path.metres_per_pixel = 0.1;
  path.splat_radius_px = 1;
  core::SegmentationModelParams mp;
  std::string names_path, why, error;
  if (!test::makeColourModel(dir, path.image_width_px, path.image_height_px, &mp, &names_path,
                             &why))
    GTEST_SKIP() << why;
  core::SegmentationModel model;
  ASSERT_TRUE(model.load(mp, &error)) << error;

  CloudXYZIRT cloud;
  std::vector<cv::Vec3b> rgb, colours;
  std::vector<core::SparkSceneObject> truth;
  core::makeSparkScene(0.1, &cloud, &rgb, &truth);
  core::pointColours(cloud, rgb, path, &colours);
  core::SparkParams sp;
  sp.mask_stride_px = 4;
  sp.dbscan_eps_m = 0.8;
  sp.kept_classes = {false, true, true, true};
  core::PointClassVotes votes;
  votes.reset(cloud.size());
  core::OrthoRenderer renderer;
  core::SegmentationScores scores;
  cv::Mat image;
  const auto poses = core::capturePoses(path);
  ASSERT_EQ(poses.size(), 8u * 4u);
  for (const OrthoCamera& cam : poses) {
    renderer.render(cloud, colours, cam, path.splat_radius_px, &image);
    ASSERT_TRUE(model.run(image, &scores, &error)) << error;
    votes.castBack(renderer, scores, sp.mask_stride_px, sp.kept_classes);
  }
  std::vector<int> point_class;
  votes.classify(sp.min_point_votes, &point_class);
  std::vector<core::SparkInstance> inst;
  core::buildInstances(cloud, point_class, sp, &inst);

  ASSERT_EQ(inst.size(), truth.size());
  // Sorted by class (car, car, vegetation, pole); each instance must be exactly one scene object.
  std::set<std::size_t> matched;
  for (std::size_t k = 0; k < inst.size(); ++k) {
    ASSERT_FALSE(inst[k].indices.empty());
    std::size_t m = 0;
    while (m < truth.size() && !(inst[k].indices[0] >= truth[m].first &&
                                 inst[k].indices[0] < truth[m].first + truth[m].count))
      ++m;
    ASSERT_LT(m, truth.size()) << "instance " << k << " starts on the ground";
    EXPECT_TRUE(matched.insert(m).second) << "two instances for scene object " << m;
    const core::SparkSceneObject& t = truth[m];
    EXPECT_EQ(inst[k].class_id, t.class_id) << k;
    for (const std::uint32_t i : inst[k].indices) {  // purity: only the object's own points
      ASSERT_GE(i, t.first) << k;
      ASSERT_LT(i, t.first + t.count) << k;
    }
    EXPECT_GT(inst[k].indices.size(), t.count / 10) << k;
    // Hits lie on the object, so the box is inside the true box and, seen from 32 views,
    // reaches each true face to within 0.3 m (the tree's underside is hidden from a camera
    // 3 m up looking down, hence the looser bottom for vegetation).
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(inst[k].min_pt[a], t.min_pt[a] - 1e-4) << k << " axis " << a;
      EXPECT_LE(inst[k].max_pt[a], t.max_pt[a] + 1e-4) << k << " axis " << a;
      EXPECT_NEAR(inst[k].max_pt[a], t.max_pt[a], 0.3) << k << " axis " << a;
      const double lo_tol = (t.class_id == 2 && a == 2) ? 1.0 : 0.3;
      EXPECT_NEAR(inst[k].min_pt[a], t.min_pt[a], lo_tol) << k << " axis " << a;
    }
  }

  // JSON export, read back with OpenCV's own JSON parser.
  std::vector<std::string> names;
  ASSERT_TRUE(core::readClassNames(names_path, &names, &error));
  const std::string json = dir + "/instances.json";
  ASSERT_TRUE(core::writeInstancesJson(json, "scene \"1\".pcd", inst, names, &error)) << error;
  cv::FileStorage fs(json, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON);
  ASSERT_TRUE(fs.isOpened());
  EXPECT_EQ(static_cast<std::string>(fs["cloud"]), "scene \"1\".pcd");
  const cv::FileNode arr = fs["instances"];
  ASSERT_EQ(arr.size(), inst.size());
  EXPECT_EQ(static_cast<std::string>(arr[0]["class"]), "car");
  EXPECT_EQ(static_cast<std::string>(arr[3]["class"]), "pole");
  EXPECT_EQ(static_cast<int>(arr[2]["point_count"]), static_cast<int>(inst[2].indices.size()));
  ASSERT_EQ(arr[1]["indices"].size(), inst[1].indices.size());
  EXPECT_EQ(static_cast<int>(arr[1]["indices"][5]), static_cast<int>(inst[1].indices[5]));
  EXPECT_NEAR(static_cast<double>(arr[0]["box"]["max"][2]), inst[0].max_pt.z(), 1e-5);

  // The capture record relates a pixel to the cloud again.
  const std::string rec = dir + "/record.json";
  ASSERT_TRUE(core::writeCaptureRecordJson(rec, "img_0003.png", 3, poses[3], &error));
  cv::FileStorage rs(rec, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON);
  ASSERT_TRUE(rs.isOpened());
  Eigen::Matrix3d rot;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rot(r, c) = static_cast<double>(rs["rotation"][r][c]);
  EXPECT_TRUE(rot.isApprox(poses[3].rotation, 1e-9));
  EXPECT_EQ(static_cast<int>(rs["width_px"]), 320);
}

}  // namespace
}  // namespace urban_detection
