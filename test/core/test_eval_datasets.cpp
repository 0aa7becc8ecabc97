// Dataset readers of the evaluation: KITTI box -> LiDAR geometry on a hand-computed box, the
// camera frustum and DontCare rules, SemanticKITTI label decoding, file readers, and the
// replay of a short simulated drive (pcap + ground truth) with its exact instances.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "test_files.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace urban_detection {
namespace core {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

// A calibration whose transform is easy to invert by hand: camera x = -LiDAR y,
// camera y = -LiDAR z - 0.08, camera z = LiDAR x - 0.27; no rectification; a 700 px focal
// length with the principal point at (600, 180).
KittiCalibration handCalibration() {
  KittiCalibration c;
  c.tr_velo_to_cam << 0, -1, 0, 0,  //
      0, 0, -1, -0.08,              //
      1, 0, 0, -0.27;
  c.r0_rect.setIdentity();
  c.p2 << 700, 0, 600, 0,  //
      0, 700, 180, 0,      //
      0, 0, 1, 0;
  return c;
}

KittiLabel carLabel() {
  // Car 4.0 m long, 1.6 m wide, 1.5 m high, bottom centre at camera (2.0, 1.7, 15.0), heading
  // along the camera z axis (rotation_y = pi/2).
  KittiLabel l;
  EXPECT_TRUE(parseKittiLabelLine(
      "Car 0.00 0 0.0 500 150 700 250 1.50 1.60 4.00 2.00 1.70 15.00 1.5707963267948966", &l));
  return l;
}

TEST(KittiObject, ParsesLabelLine) {
  const KittiLabel l = carLabel();
  EXPECT_EQ(l.type, "Car");
  EXPECT_DOUBLE_EQ(l.height_m, 1.5);
  EXPECT_DOUBLE_EQ(l.width_m, 1.6);
  EXPECT_DOUBLE_EQ(l.length_m, 4.0);
  EXPECT_DOUBLE_EQ(l.location.z(), 15.0);
  EXPECT_DOUBLE_EQ(l.bbox[2], 700.0);
  KittiLabel bad;
  EXPECT_FALSE(parseKittiLabelLine("Car 0.00 0 0.0 500 150", &bad));
  EXPECT_FALSE(parseKittiLabelLine("Car x 0 0.0 500 150 700 250 1 1 1 1 1 1 1", &bad));
}

TEST(KittiObject, BoxCornersInLidarFrameByHand) {
  // By hand: with rotation_y = pi/2 the length runs along camera z and the width along camera
  // x, so the box spans camera x in [1.2, 2.8], y in [0.2, 1.7], z in [13, 17]. In the LiDAR
  // frame: x = z_cam + 0.27 in [13.27, 17.27], y = -x_cam in [-2.8, -1.2], z = -(y_cam + 0.08):
  // bottom -1.78, top -0.28. Corner 0 (+l, +w) is camera (2.8, 1.7, 13).
  const auto c = kittiBoxCornersVelo(carLabel(), handCalibration());
  const Eigen::Vector3d expected[8] = {
      {13.27, -2.8, -1.78}, {13.27, -1.2, -1.78}, {17.27, -1.2, -1.78}, {17.27, -2.8, -1.78},
      {13.27, -2.8, -0.28}, {13.27, -1.2, -0.28}, {17.27, -1.2, -0.28}, {17.27, -2.8, -0.28}};
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR((c[k] - expected[k]).norm(), 0.0, 1e-9)
        << "corner " << k << ": " << c[k].transpose();
  }
}

TEST(KittiObject, CalibrationRoundTripWithRectification) {
  KittiCalibration c = handCalibration();
  const double a = 10.0 * kPi / 180.0;
  c.r0_rect << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  const Eigen::Vector3d p(12.0, -3.0, 0.5);
  EXPECT_NEAR((c.rectToVelo(c.veloToRect(p)) - p).norm(), 0.0, 1e-12);
  // Without rectification the hand formula holds.
  const Eigen::Vector3d r = handCalibration().veloToRect(p);
  EXPECT_NEAR((r - Eigen::Vector3d(3.0, -0.58, 11.73)).norm(), 0.0, 1e-12);
}

TEST(KittiObject, CameraFrustum) {
  const KittiCalibration c = handCalibration();
  // Straight ahead: camera (0, -0.08, 9.73) -> u = 600, v = 180 - 700 * 0.08 / 9.73.
  double u, v;
  ASSERT_TRUE(c.project({10.0, 0.0, 0.0}, &u, &v));
  EXPECT_NEAR(u, 600.0, 1e-9);
  EXPECT_NEAR(v, 180.0 - 700.0 * 0.08 / 9.73, 1e-9);
  EXPECT_TRUE(inKittiCameraFrustum(c, {10.0, 0.0, 0.0}, 1242, 375));
  // Behind the camera and beside it.
  EXPECT_FALSE(inKittiCameraFrustum(c, {-5.0, 0.0, 0.0}, 1242, 375));
  EXPECT_FALSE(inKittiCameraFrustum(c, {0.2, 0.0, 0.0}, 1242, 375));  // depth -0.07
  EXPECT_FALSE(inKittiCameraFrustum(c, {1.0, 10.0, 0.0}, 1242, 375));
  // Right edge at depth 14 m (LiDAR x 14.27): u = 600 + 50 * x_cam -> x_cam 12.8 gives
  // u = 1240 (inside), 12.9 gives 1245 (outside).
  EXPECT_TRUE(inKittiCameraFrustum(c, {14.27, -12.8, -0.08}, 1242, 375));
  EXPECT_FALSE(inKittiCameraFrustum(c, {14.27, -12.9, -0.08}, 1242, 375));
  // Bottom edge: y_cam 3.0 gives v = 330 (inside), 4.5 gives v = 405 (outside).
  EXPECT_TRUE(inKittiCameraFrustum(c, {14.27, 0.0, -3.08}, 1242, 375));
  EXPECT_FALSE(inKittiCameraFrustum(c, {14.27, 0.0, -4.58}, 1242, 375));
  // A smaller image moves the edge.
  EXPECT_FALSE(inKittiCameraFrustum(c, {14.27, 0.0, -3.08}, 1242, 320));
}

TEST(KittiObject, GroundTruthRoles) {
  KittiLabel dont_care;
  ASSERT_TRUE(parseKittiLabelLine(
      "DontCare -1 -1 -10 690 170 720 190 -1 -1 -1 -1000 -1000 -1000 -10", &dont_care));
  KittiLabel ped;
  ASSERT_TRUE(parseKittiLabelLine("Pedestrian 0 0 0 0 0 10 10 1.8 0.6 0.8 -1.0 1.7 8.0 0.0", &ped));
  CloudXYZIRT cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.push_back(makePoint(15.27f, -2.0f, -1.0f));   // 0 car, 0.78 m above its bottom
  cloud.push_back(makePoint(15.27f, -2.0f, -1.7f));   // 1 car, 0.08 m above bottom: excluded
  cloud.push_back(makePoint(15.27f, -2.85f, -1.0f));  // 2 0.05 m outside the side: within margin
  cloud.push_back(
      makePoint(15.27f, -2.95f, -1.0f));            // 3 0.15 m outside: background, u 737.7 v 222.9
  cloud.push_back(makePoint(-5.0f, 0.0f, 0.0f));    // 4 behind the camera: don't care
  cloud.push_back(makePoint(1.0f, 10.0f, 0.0f));    // 5 left of the image: don't care
  cloud.push_back(makePoint(20.27f, -3.0f, 0.0f));  // 6 projects to (705, 177.2): DontCare box
  cloud.push_back(makePoint(17.2f, -2.0f, -0.35f));  // 7 car, near the top rear corner
  cloud.push_back(makePoint(17.45f, -2.0f, -1.0f));  // 8 0.18 m behind the car: background
  cloud.push_back(makePoint(nan, 0.0f, 0.0f));       // 9 non-finite: excluded
  cloud.push_back(makePoint(8.27f, 1.0f, -1.08f));   // 10 pedestrian: camera (-1.0, 1.0, 8.0)
  KittiGroundTruthParams params;
  params.min_points = 1;
  EvalFrame gt;
  buildKittiGroundTruth(cloud, {carLabel(), dont_care, ped}, handCalibration(), params, 1242, 375,
                        &gt);
  ASSERT_EQ(gt.objects.size(), 2u);
  EXPECT_EQ(gt.objects[0].label, "Car");
  EXPECT_EQ(gt.objects[1].label, "Pedestrian");
  EXPECT_EQ(gt.objects[1].id, 3u);  // third label line
  const std::vector<std::int32_t> obj = {0, -1, 0, -1, -1, -1, -1, 0, -1, -1, 1};
  const std::vector<PointRole> role = {
      PointRole::kScored,   PointRole::kExcluded, PointRole::kScored,   PointRole::kScored,
      PointRole::kDontCare, PointRole::kDontCare, PointRole::kDontCare, PointRole::kScored,
      PointRole::kScored,   PointRole::kExcluded, PointRole::kScored};
  EXPECT_EQ(gt.object_of_point, obj);
  EXPECT_EQ(gt.role, role);
  EXPECT_EQ(gt.objects[0].num_points, 3u);
  EXPECT_EQ(gt.objects[1].num_points, 1u);
}

TEST(KittiObject, CalibrationFileErrors) {
  const fs::path dir = fs::temp_directory_path() / "ud_eval_calib_test";
  fs::create_directories(dir);
  const std::string good = (dir / "good.txt").string(), bad = (dir / "bad.txt").string();
  {
    std::ofstream f(good);
    f << "P2: 700 0 600 0 0 700 180 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n"
      << "Tr_velo_to_cam: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n";
    std::ofstream g(bad);
    g << "P2: 700 0 600 0 0 700 180 0 0 0 1 0\nR0_rect: 1 0 0\n";
  }
  KittiCalibration c;
  std::string err;
  ASSERT_TRUE(readKittiCalibration(good, &c, &err)) << err;
  EXPECT_TRUE(c.tr_velo_to_cam.isApprox(handCalibration().tr_velo_to_cam));
  EXPECT_FALSE(readKittiCalibration(bad, &c, &err));
  EXPECT_NE(err.find("R0_rect"), std::string::npos) << err;
  EXPECT_FALSE(readKittiCalibration((dir / "missing.txt").string(), &c, &err));
  fs::remove_all(dir);
}

TEST(FileReaders, PngHeaderAndListing) {
  const fs::path dir = fs::temp_directory_path() / "ud_eval_png_test";
  fs::create_directories(dir);
  // Signature, IHDR chunk length 13, "IHDR", width 0x04DA = 1242, height 0x0177 = 375.
  const unsigned char png[24] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0,    13,
                                 'I',  'H', 'D', 'R', 0,    0,    0x04, 0xDA, 0, 0, 0x01, 0x77};
  {
    std::ofstream f((dir / "b.png").string(), std::ios::binary);
    f.write(reinterpret_cast<const char*>(png), sizeof(png));
    std::ofstream g((dir / "a.png").string(), std::ios::binary);
    g.write(reinterpret_cast<const char*>(png), 20);  // truncated header
    std::ofstream h((dir / "c.txt").string());
    h << "not a png, long enough to fill a header......";
  }
  int w = 0, h = 0;
  ASSERT_TRUE(readPngSize((dir / "b.png").string(), &w, &h));
  EXPECT_EQ(w, 1242);
  EXPECT_EQ(h, 375);
  EXPECT_FALSE(readPngSize((dir / "a.png").string(), &w, &h));
  EXPECT_FALSE(readPngSize((dir / "c.txt").string(), &w, &h));
  EXPECT_FALSE(readPngSize((dir / "missing.png").string(), &w, &h));
  const auto files = listFiles(dir.string(), ".png");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(fs::path(files[0]).filename(), "a.png");
  EXPECT_EQ(fs::path(files[1]).filename(), "b.png");
  EXPECT_TRUE(listFiles((dir / "nope").string(), ".png").empty());
  fs::remove_all(dir);
}

TEST(SemanticKitti, LabelDecoding) {
  // Low 16 bits class, high 16 bits instance.
  EXPECT_EQ(semanticKittiClass(0x00D5000Au), 10);
  EXPECT_EQ(semanticKittiInstance(0x00D5000Au), 213);
  EXPECT_EQ(semanticKittiClass((1u << 16) | 255u), 255);
  EXPECT_EQ(semanticKittiInstance((1u << 16) | 255u), 1);
  EXPECT_EQ(semanticKittiClass(0xFFFF0000u), 0);
  EXPECT_EQ(semanticKittiInstance(0xFFFF0000u), 65535);
  EXPECT_EQ(semanticKittiCategory(10), SemanticKittiCategory::kThing);
  EXPECT_EQ(semanticKittiCategory(254), SemanticKittiCategory::kThing);
  EXPECT_EQ(semanticKittiCategory(80), SemanticKittiCategory::kDontCare);
  EXPECT_EQ(semanticKittiCategory(99), SemanticKittiCategory::kDontCare);
  EXPECT_EQ(semanticKittiCategory(50), SemanticKittiCategory::kBackground);
  EXPECT_EQ(semanticKittiCategory(72), SemanticKittiCategory::kBackground);
  EXPECT_EQ(semanticKittiClassName(31), "bicyclist");
}

TEST(SemanticKitti, GroundTruthFromLabels) {
  auto lab = [](std::uint32_t cls, std::uint32_t inst) { return (inst << 16) | cls; };
  std::vector<std::uint32_t> labels;
  for (int i = 0; i < 12; ++i) labels.push_back(lab(10, 5));   // car 5: 12 points
  for (int i = 0; i < 3; ++i) labels.push_back(lab(10, 7));    // car 7: 3 points, too few
  labels.push_back(lab(10, 0));                                // car without instance
  labels.push_back(lab(80, 0));                                // pole
  labels.push_back(lab(40, 0));                                // road
  for (int i = 0; i < 10; ++i) labels.push_back(lab(252, 5));  // moving car, same instance id
  SemanticKittiGroundTruthParams params;
  params.min_points = 10;
  EvalFrame gt;
  buildSemanticKittiGroundTruth(labels, params, &gt);
  ASSERT_EQ(gt.objects.size(), 3u);
  EXPECT_EQ(gt.objects[0].label, "car");
  EXPECT_EQ(gt.objects[0].num_points, 12u);
  EXPECT_FALSE(gt.objects[0].ignored);
  EXPECT_TRUE(gt.objects[1].ignored);
  EXPECT_EQ(gt.objects[2].label, "moving-car");
  EXPECT_EQ(gt.object_of_point[0], 0);
  EXPECT_EQ(gt.object_of_point[12], 1);
  EXPECT_EQ(gt.object_of_point[15], -1);
  EXPECT_EQ(gt.role[15], PointRole::kDontCare);
  EXPECT_EQ(gt.role[16], PointRole::kDontCare);
  EXPECT_EQ(gt.role[17], PointRole::kScored);
  EXPECT_EQ(gt.object_of_point[18], 2);
}

// On the shared frames, checked against counts obtained separately with numpy.
TEST(SemanticKitti, PosesInTheLidarFrame) {
  const fs::path dir =
      fs::temp_directory_path() / ("ud_eval_poses_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  // Scan 1: the camera 2 m ahead along its z (= LiDAR x) and turned 90 deg left (about camera
  // -y = LiDAR z).
  std::ofstream(dir / "poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                      "0 0 -1 0 0 1 0 0 1 0 0 2\n";
  std::vector<Eigen::Isometry3d> poses;
  bool nominal = false;
  std::string error;
  ASSERT_TRUE(readSemanticKittiPoses(dir.string(), &poses, &nominal, &error)) << error;
  EXPECT_TRUE(nominal);  // no calib.txt: nominal axes
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_TRUE(poses[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(poses[1].translation().isApprox(Eigen::Vector3d(2, 0, 0))) << poses[1].translation();
  // LiDAR x now points along the first scan's LiDAR y (a left turn).
  EXPECT_TRUE((poses[1].linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  // A Tr line is used; a short one is an error naming the file.
  std::ofstream(dir / "calib.txt")
      << "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
  ASSERT_TRUE(readSemanticKittiPoses(dir.string(), &poses, &nominal, &error)) << error;
  EXPECT_FALSE(nominal);
  EXPECT_TRUE(poses[1].translation().isApprox(Eigen::Vector3d(2, 0, 0)));
  std::ofstream(dir / "calib.txt") << "Tr: 0 -1 0\n";
  EXPECT_FALSE(readSemanticKittiPoses(dir.string(), &poses, &nominal, &error));
  EXPECT_NE(error.find("calib.txt"), std::string::npos) << error;
  fs::remove(dir / "calib.txt");
  std::ofstream(dir / "poses.txt") << "1 0 0\n";
  EXPECT_FALSE(readSemanticKittiPoses(dir.string(), &poses, &nominal, &error));
  EXPECT_NE(error.find("poses.txt:1"), std::string::npos) << error;
  fs::remove_all(dir);
}

TEST(SharedData, KittiAndSemanticKittiFrames) {
  const fs::path root(UD_SHARED_DATA);
  const fs::path ko = root / "kitti_object", sk = root / "semantic_kitti/sequences/00";
  if (!fs::exists(ko / "velodyne/000000.bin") || !fs::exists(sk / "labels/000000.label")) {
    GTEST_SKIP() << "shared data not found under " << root;
  }
  CloudXYZIRT cloud;
  std::string err;
  ASSERT_TRUE(readKittiBin((ko / "velodyne/000000.bin").string(), &cloud, &err)) << err;
  EXPECT_EQ(cloud.size(), 115384u);
  KittiCalibration calib;
  ASSERT_TRUE(readKittiCalibration((ko / "calib/000000.txt").string(), &calib, &err)) << err;
  std::vector<KittiLabel> labels;
  ASSERT_TRUE(readKittiLabels((ko / "label_2/000000.txt").string(), &labels, &err)) << err;
  EvalFrame gt;
  buildKittiGroundTruth(cloud, labels, calib, KittiGroundTruthParams(), 1242, 375, &gt);
  ASSERT_EQ(gt.objects.size(), 1u);
  EXPECT_EQ(gt.objects[0].label, "Pedestrian");
  EXPECT_GT(gt.objects[0].num_points, 100u);  // a pedestrian at 8.4 m

  std::vector<std::uint32_t> sl;
  ASSERT_TRUE(readSemanticKittiLabels((sk / "labels/000000.label").string(), &sl, &err)) << err;
  EXPECT_EQ(sl.size(), 124668u);
  buildSemanticKittiGroundTruth(sl, SemanticKittiGroundTruthParams(), &gt);
  // 13 cars and one moving motorcyclist; car 217 has 5 points (< 10): ignored.
  ASSERT_EQ(gt.objects.size(), 14u);
  int ignored = 0;
  for (const auto& o : gt.objects) ignored += o.ignored ? 1 : 0;
  EXPECT_EQ(ignored, 1);
}

}  // namespace
}  // namespace core
}  // namespace urban_detection

namespace urban_detection {
namespace core {
namespace {

// ------------------------------------------------------------------------------------------
// Simulated drives: pcap + ground-truth file of the simulator, replayed for the evaluation.

namespace sim_test {

struct Drive {
  std::string pcap, gt;
  std::vector<GroundTruthFrame> frames;  // as written
};

// Simulates `revolutions` revolutions of the demo drive; writes every revolution's packets and
// the ground-truth frames whose index is not in `drop_gt`. The files are named after `name` and
// this process's pid, so concurrent runs of the test binary (two checkouts, the sanitizer build)
// never read or delete each other's files.
Drive simulate(const std::string& name, int revolutions, const std::set<int>& drop_gt = {}) {
  const SimulationConfig c =
      loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  LidarSimulator sim(generateScene(c.scene, c.drive), c.scene, c.drive,
                     Calibration::nominalHdl64eS2(), c.sensor);
  Drive d;
  const std::string base = ud_test::tempPath(name);
  d.pcap = base + ".pcap";
  d.gt = base + ".gt";
  PcapWriter pcap(d.pcap);
  GroundTruthWriter gt(d.gt);
  SimRevolution rev;
  for (int r = 0; r < revolutions; ++r) {
    sim.simulateNext(&rev);
    for (std::size_t i = 0; i < rev.packets.size(); ++i) {
      pcap.write(rev.packets[i], rev.packet_stamps_s[i]);
    }
    d.frames.emplace_back();
    makeGroundTruthFrame(sim, rev, &d.frames.back());
    if (!drop_gt.count(r)) gt.write(d.frames.back());
  }
  gt.close();
  return d;
}

}  // namespace sim_test

TEST(SimulatedDrive, ReplaysEveryRevolutionWithItsGroundTruth) {
  const sim_test::Drive d = sim_test::simulate("ud_eval_sim", 3);
  SimulatedDriveReader reader(d.pcap, d.gt, Calibration::nominalHdl64eS2());
  CloudXYZIRT cloud;
  GroundTruthFrame gt;
  std::string msg;
  for (std::size_t r = 0; r < 3; ++r) {
    ASSERT_EQ(reader.next(&cloud, &gt, &msg), SimulatedDriveReader::Result::kFrame) << msg;
    EXPECT_EQ(gt.revolution, r);
    EXPECT_EQ(cloud.size(), d.frames[r].instance_ids.size());
    EXPECT_EQ(gt.instance_ids, d.frames[r].instance_ids);
    EXPECT_GT(cloud.size(), 100000u);  // a full HDL-64E revolution
  }
  EXPECT_EQ(reader.next(&cloud, &gt, &msg), SimulatedDriveReader::Result::kEnd);
  EXPECT_EQ(reader.revolutions(), 3u);
  EXPECT_EQ(reader.badPackets(), 0u);
  std::remove(d.pcap.c_str());
  std::remove(d.gt.c_str());
}

TEST(SimulatedDrive, RevolutionsArePairedByStampNotByPosition) {
  // The GT file lacks revolution 1: revolution 1 is skipped (with a message), revolution 2
  // still gets its own frame, not the next one in the file.
  const sim_test::Drive d = sim_test::simulate("ud_eval_sim_gap", 3, {1});
  SimulatedDriveReader reader(d.pcap, d.gt, Calibration::nominalHdl64eS2());
  CloudXYZIRT cloud;
  GroundTruthFrame gt;
  std::string msg;
  ASSERT_EQ(reader.next(&cloud, &gt, &msg), SimulatedDriveReader::Result::kFrame) << msg;
  EXPECT_EQ(gt.revolution, 0u);
  EXPECT_EQ(reader.next(&cloud, &gt, &msg), SimulatedDriveReader::Result::kSkipped);
  EXPECT_NE(msg.find("no ground-truth frame"), std::string::npos) << msg;
  ASSERT_EQ(reader.next(&cloud, &gt, &msg), SimulatedDriveReader::Result::kFrame) << msg;
  EXPECT_EQ(gt.revolution, 2u);
  EXPECT_EQ(cloud.size(), d.frames[2].instance_ids.size());
  EXPECT_EQ(reader.next(&cloud, &gt, &msg), SimulatedDriveReader::Result::kEnd);
  EXPECT_THROW(SimulatedDriveReader(d.pcap + ".missing", d.gt, Calibration::nominalHdl64eS2()),
               std::runtime_error);
  std::remove(d.pcap.c_str());
  std::remove(d.gt.c_str());
}

TEST(SimulatedDrive, GroundTruthRulesAndAPerfectDetector) {
  const sim_test::Drive d = sim_test::simulate("ud_eval_sim_gt", 1);
  const GroundTruthFrame& frame = d.frames[0];
  SimulatedGroundTruthParams params;
  params.min_points = 10;
  EvalFrame gt;
  buildSimulatedGroundTruth(frame, params, &gt);
  // The number of GT objects, from the simulator's own per-object point counts.
  std::size_t expected = 0, expected_ignored = 0;
  for (const GroundTruthObject& o : frame.objects) {
    if (!isStreetObject(o.object_class) || o.num_points == 0) continue;
    ++(o.num_points >= params.min_points ? expected : expected_ignored);
  }
  ASSERT_GT(expected, 10u);
  std::size_t counted = 0, ignored = 0;
  for (const EvalObject& o : gt.objects) ++(o.ignored ? ignored : counted);
  EXPECT_EQ(counted, expected);
  EXPECT_EQ(ignored, expected_ignored);

  // Detections made of the exact instances: every GT object matched, nothing false.
  std::map<std::uint32_t, DetectedObject> by_instance;
  std::vector<std::uint32_t> wall, pole;
  for (std::size_t i = 0; i < frame.instance_ids.size(); ++i) {
    const auto cls = static_cast<ObjectClass>(frame.classes[i]);
    if (frame.instance_ids[i] > 0 && isStreetObject(cls)) {
      by_instance[frame.instance_ids[i]].indices.push_back(static_cast<std::uint32_t>(i));
    } else if (cls == ObjectClass::kWall && wall.size() < 50) {
      wall.push_back(static_cast<std::uint32_t>(i));
    } else if (cls == ObjectClass::kPole && pole.size() < 50) {
      pole.push_back(static_cast<std::uint32_t>(i));
    }
  }
  std::vector<DetectedObject> dets;
  for (auto& kv : by_instance) dets.push_back(kv.second);
  DetectionEvaluator eval;
  FrameMatch m;
  eval.evaluate(gt, dets, &m);
  EXPECT_EQ(m.score.no, expected);
  EXPECT_EQ(m.score.tp, expected);
  EXPECT_EQ(m.score.mo, 0u);
  EXPECT_EQ(m.score.fo, 0u);
  EXPECT_EQ(m.score.ignored, expected_ignored);  // detections of too-small objects
  EXPECT_DOUBLE_EQ(m.score.fRate(), 1.0);
  // A piece of a wall is a false detection; a pole is a real object without a target class:
  // ignored.
  ASSERT_FALSE(wall.empty());
  ASSERT_FALSE(pole.empty());
  DetectedObject w, p;
  w.indices = wall;
  p.indices = pole;
  dets.push_back(w);
  dets.push_back(p);
  eval.evaluate(gt, dets, &m);
  EXPECT_EQ(m.score.fo, 1u);
  EXPECT_EQ(m.verdict[dets.size() - 2], DetectionVerdict::kFalse);
  EXPECT_EQ(m.verdict[dets.size() - 1], DetectionVerdict::kIgnored);
  EXPECT_EQ(m.score.tp, expected);
  std::remove(d.pcap.c_str());
  std::remove(d.gt.c_str());
}

TEST(SimulatedDrive, VegetationAndTerrainAreScoredBackgroundTrunksPolesSignsDontCare) {
  // As SemanticKITTI's protocol: a detection made mostly of foliage (crowns, hedges, bushes) or
  // terrain is a false object; trunks, poles and signs are real objects without a target class.
  const sim_test::Drive d = sim_test::simulate("ud_eval_sim_veg", 1);
  const GroundTruthFrame& frame = d.frames[0];
  EvalFrame gt;
  buildSimulatedGroundTruth(frame, SimulatedGroundTruthParams(), &gt);
  ASSERT_EQ(gt.role.size(), frame.classes.size());
  std::map<ObjectClass, std::vector<std::uint32_t>> by_class;
  for (std::size_t i = 0; i < frame.classes.size(); ++i) {
    const auto cls = static_cast<ObjectClass>(frame.classes[i]);
    by_class[cls].push_back(static_cast<std::uint32_t>(i));
    switch (cls) {
      case ObjectClass::kVegetation:
      case ObjectClass::kTerrain:
      case ObjectClass::kGround:
      case ObjectClass::kWall:
        ASSERT_EQ(gt.role[i], PointRole::kScored) << toString(cls);
        ASSERT_EQ(gt.object_of_point[i], -1) << toString(cls);
        break;
      case ObjectClass::kTrunk:
      case ObjectClass::kPole:
      case ObjectClass::kSign:
        ASSERT_EQ(gt.role[i], PointRole::kDontCare) << toString(cls);
        ASSERT_EQ(gt.object_of_point[i], -1) << toString(cls);
        break;
      default:
        ASSERT_TRUE(isStreetObject(cls)) << toString(cls);
        ASSERT_GE(gt.object_of_point[i], 0);
    }
  }
  for (ObjectClass c : {ObjectClass::kVegetation, ObjectClass::kTerrain, ObjectClass::kTrunk}) {
    ASSERT_GE(by_class[c].size(), 50u) << toString(c);
  }
  // Foliage points come from hedge, bush and tree objects; terrain is background.
  std::set<std::uint32_t> foliage_objects;
  for (std::uint32_t i : by_class[ObjectClass::kVegetation]) {
    EXPECT_GT(frame.instance_ids[i], 0u);
    foliage_objects.insert(frame.instance_ids[i]);
  }
  EXPECT_GT(foliage_objects.size(), 5u);
  for (std::uint32_t i : by_class[ObjectClass::kTerrain]) EXPECT_EQ(frame.instance_ids[i], 0u);

  std::vector<DetectedObject> dets(3);
  for (int k = 0; k < 3; ++k) {
    const ObjectClass c =
        k == 0 ? ObjectClass::kVegetation : (k == 1 ? ObjectClass::kTerrain : ObjectClass::kTrunk);
    dets[k].indices.assign(by_class[c].begin(), by_class[c].begin() + 50);
  }
  DetectionEvaluator eval;
  FrameMatch m;
  eval.evaluate(gt, dets, &m);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kFalse);    // a piece of foliage
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kFalse);    // a piece of grass
  EXPECT_EQ(m.verdict[2], DetectionVerdict::kIgnored);  // a trunk
  EXPECT_EQ(m.score.fo, 2u);
  std::remove(d.pcap.c_str());
  std::remove(d.gt.c_str());
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
