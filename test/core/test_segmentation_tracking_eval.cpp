// The segmentation and tracking evaluations as a library (core/evaluation/segmentation_eval.h,
// tracking_eval.h): group rules, ground precision / recall / F1 and foreground shares on a
// hand-made labelling, and the CLEAR-MOT evaluation of a short simulated drive, where the
// tracker fed the ground-truth boxes themselves must track every object without a switch.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "test_files.h"
#include "urban_detection/core/evaluation/segmentation_eval.h"
#include "urban_detection/core/evaluation/tracking_eval.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/core/simulation/ground_truth.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace ud = urban_detection::core;
namespace fs = std::filesystem;
namespace sk = urban_detection::core::semantic_kitti;

TEST(SegmentationEval, GroupsOfBothDatasets) {
  EXPECT_EQ(ud::semanticKittiGroup(sk::kUnlabeled), ud::SegGroup::kIgnore);
  EXPECT_EQ(ud::semanticKittiGroup(sk::kBuilding), ud::SegGroup::kWall);
  EXPECT_EQ(ud::semanticKittiGroup(sk::kFence), ud::SegGroup::kWall);
  EXPECT_EQ(ud::semanticKittiGroup(sk::kCar | (5u << 16)), ud::SegGroup::kCar);  // instance 5
  EXPECT_EQ(ud::semanticKittiGroup(sk::kBicyclist), ud::SegGroup::kCyclist);
  EXPECT_EQ(ud::semanticKittiGroup(sk::kTruck), ud::SegGroup::kOtherVehicle);
  EXPECT_EQ(ud::semanticKittiGroup(sk::kPole), ud::SegGroup::kVegPole);
  using C = ud::ObjectClass;
  auto sim = [](C c) { return ud::simulatedGroup(static_cast<std::uint8_t>(c)); };
  EXPECT_EQ(sim(C::kGround), ud::SegGroup::kGround);
  EXPECT_EQ(sim(C::kWall), ud::SegGroup::kWall);
  EXPECT_EQ(sim(C::kVan), ud::SegGroup::kOtherVehicle);
  EXPECT_EQ(sim(C::kBench), ud::SegGroup::kStreetObject);
  EXPECT_EQ(sim(C::kUnlabeled), ud::SegGroup::kIgnore);
}

TEST(SegmentationEval, CountsOfAHandMadeLabelling) {
  using G = ud::SegGroup;
  using S = ud::SegmentClass;
  // 4 ground points (3 called ground), 2 wall points (1 called ground, 1 tall), 3 car points
  // (2 short), 1 ignored point called ground.
  const std::vector<G> gt = {G::kGround, G::kGround, G::kGround, G::kGround, G::kWall,
                             G::kWall,   G::kCar,    G::kCar,    G::kCar,    G::kIgnore};
  const std::vector<S> pred = {S::kGround, S::kGround, S::kGround, S::kShort, S::kGround,
                               S::kTall,   S::kShort,  S::kShort,  S::kTall,  S::kGround};
  ud::SegCounts c;
  ud::accumulate(gt, pred, &c);
  EXPECT_EQ(c.ground_tp, 3);
  EXPECT_EQ(c.ground_fp, 1);
  EXPECT_EQ(c.ground_fn, 1);
  EXPECT_DOUBLE_EQ(ud::groundPrecision(c), 0.75);
  EXPECT_DOUBLE_EQ(ud::groundRecall(c), 0.75);
  EXPECT_DOUBLE_EQ(ud::groundF1(c), 0.75);
  EXPECT_EQ(c.of(G::kWall).total, 2);
  EXPECT_DOUBLE_EQ(ud::notForeground(c.of(G::kWall)), 1.0);
  EXPECT_DOUBLE_EQ(ud::foreground(c.of(G::kCar)), 2.0 / 3.0);
  EXPECT_EQ(c.of(G::kIgnore).total, 0);
  // Confusion rows: ground, wall, car, person+cyclist, other; columns: SegmentClass.
  EXPECT_EQ(c.confusion[0][static_cast<int>(S::kGround)], 3);
  EXPECT_EQ(c.confusion[2][static_cast<int>(S::kShort)], 2);
  EXPECT_DOUBLE_EQ(ud::segRatio(1, 0), 0.0);
}

TEST(SegmentationEval, UnreadableInputsAreReportedNotScored) {
  ud::SegmentationEvaluator ev{ud::GridSegmenterParams()};
  EXPECT_FALSE(ud::evaluateSemanticKittiSegmentation(ud_test::tempPath("none"), "", &ev));
  std::string error;
  EXPECT_FALSE(ud::evaluateSimulatedSegmentation(
      ud_test::tempPath("none.gt"), ud_test::tempPath("none.pcap"), "", -1, "", &ev, &error));
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(ev.on().frames, 0);
  ud::KittiObjectSegmentation k;
  EXPECT_FALSE(ud::evaluateKittiObjectSegmentation(ud_test::tempPath("none"),
                                                   ud::GridSegmenterParams(), &k));
}

TEST(TrackingEval, ShortSimulatedDrive) {
  // 12 revolutions of the demo drive written as pcap + ground truth, as urban_detection_simulate
  // writes them.
  const ud::SimulationConfig c =
      ud::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  const ud::Calibration cal = ud::Calibration::nominalHdl64eS2();
  ud::LidarSimulator sim(ud::generateScene(c.scene, c.drive), c.scene, c.drive, cal, c.sensor);
  const std::string pcap = ud_test::tempPath("track.pcap"), gt = ud_test::tempPath("track.gt");
  {
    ud::PcapWriter pw(pcap);
    ud::GroundTruthWriter gw(gt);
    ud::SimRevolution rev;
    ud::GroundTruthFrame frame;
    for (int r = 0; r < 12; ++r) {
      sim.simulateNext(&rev);
      for (std::size_t i = 0; i < rev.packets.size(); ++i) {
        pw.write(rev.packets[i], rev.packet_stamps_s[i]);
      }
      ud::makeGroundTruthFrame(sim, rev, &frame);
      gw.write(frame);
    }
    gw.close();
  }
  ud::TrackingEvalParams p;
  p.params.classifier.enabled = false;
  p.max_frames = 10;
  ud::SimTrackingResult r;
  std::string error;
  ASSERT_TRUE(ud::evaluateSimTracking(p, gt, pcap, cal, c.sensor.cut_angle_deg, &r, &error))
      << error;
  EXPECT_EQ(r.frames, 10u);
  EXPECT_EQ(r.tracker.frames, 10u);
  EXPECT_EQ(r.update_ms.size(), 10u);
  // The same scored ground truth on the three sides.
  EXPECT_GT(r.tracker.gt, 0u);
  EXPECT_EQ(r.detector.gt, r.tracker.gt);
  EXPECT_EQ(r.oracle.gt, r.tracker.gt);
  EXPECT_EQ(r.tracker.matches + r.tracker.misses, r.tracker.gt);
  // Perfect boxes: every object tracked once confirmed, no identity switch, no false track.
  EXPECT_EQ(r.oracle.id_switches, 0u);
  EXPECT_EQ(r.oracle.false_positives, 0u);
  EXPECT_GT(r.oracle.recall(), 0.5);
  EXPECT_GE(r.oracle.mota(), r.tracker.mota());
  const std::string json = ud::motJson(r.oracle);
  EXPECT_NE(json.find("\"id_switches\": 0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"frames\": 10"), std::string::npos) << json;
  std::remove(pcap.c_str());
  std::remove(gt.c_str());
}

TEST(TrackingEval, MissingDatasetsAreErrors) {
  ud::TrackingEvalParams p;
  std::string error;
  ud::KittiTrackingEvalResult k;
  EXPECT_FALSE(ud::evaluateKittiTracking(p, ud_test::tempPath("none"), &k, &error));
  EXPECT_NE(error.find("label_02"), std::string::npos) << error;
  ud::SemanticKittiTrackingEvalResult s;
  EXPECT_FALSE(ud::evaluateSemanticKittiTracking(p, ud_test::tempPath("none"), &s, &error));
  EXPECT_NE(error.find("no SemanticKITTI sequence"), std::string::npos) << error;
  ud::SimTrackingResult r;
  EXPECT_FALSE(ud::evaluateSimTracking(p, ud_test::tempPath("none.gt"),
                                       ud_test::tempPath("none.pcap"),
                                       ud::Calibration::nominalHdl64eS2(), 0.0, &r, &error));
  EXPECT_FALSE(error.empty());
}

TEST(TrackingEval, SemanticKittiSequencesWhenPresent) {
  const std::string dir = std::string(UD_SHARED_DATA) + "/semantic_kitti";
  if (!fs::is_directory(dir + "/sequences/00/velodyne")) {
    GTEST_SKIP() << "no SemanticKITTI in " << dir;
  }
  ud::TrackingEvalParams p;
  p.params.classifier.enabled = false;
  p.max_frames = 5;
  ud::SemanticKittiTrackingEvalResult r;
  std::string error;
  ASSERT_TRUE(ud::evaluateSemanticKittiTracking(p, dir + "/sequences/00", &r, &error)) << error;
  EXPECT_EQ(r.frames, 5u);
  ASSERT_EQ(r.per_sequence.size(), 1u);
  EXPECT_EQ(r.per_sequence[0].first, "00");
  EXPECT_EQ(r.per_sequence[0].second.gt, r.tracker.gt);
  EXPECT_EQ(r.tracker.frames, 5u);
}

TEST(SegmentationEval, CellClassesAroundTheSensor) {
  // A flat road 1.8 m below the sensor and a 1.5 m high block 3 m ahead: ground dots, the
  // sensor in the middle, the block's cells short or tall, one row per grid row.
  urban_detection::CloudXYZIRT cloud;
  for (float x = -6.0f; x <= 6.0f; x += 0.1f) {
    for (float y = -6.0f; y <= 6.0f; y += 0.1f) {
      urban_detection::PointXYZIRT p{};
      p.x = x;
      p.y = y;
      p.z = -1.8f;
      cloud.push_back(p);
      if (x > 2.9f && x < 3.6f && y > -0.3f && y < 0.3f) {
        for (float z = -1.7f; z < -0.3f; z += 0.1f) {
          p.z = z;
          cloud.push_back(p);
        }
      }
    }
  }
  ud::SegmentationEvaluator ev{ud::GridSegmenterParams()};
  std::vector<ud::SegGroup> groups(cloud.size(), ud::SegGroup::kGround);
  ev.frame(cloud, groups, "");
  const std::string text = ud::cellClassesAscii(ev.segmenterOn(), 4.0);
  EXPECT_EQ(text.rfind("cells of the last scan, +x right, +y up, hough on\n", 0), 0u) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), 'S'), 1);
  EXPECT_GT(std::count(text.begin(), text.end(), '.'), 100);
  EXPECT_GT(std::count(text.begin(), text.end(), 's') + std::count(text.begin(), text.end(), 'T'),
            0);
  const std::size_t rows = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  EXPECT_EQ(rows,
            1u + 2u * static_cast<std::size_t>(4.0 / ud::GridSegmenterParams().cell_size_m) + 1u);
  EXPECT_EQ(ev.on().frames, 1);
  EXPECT_GT(ud::groundRecall(ev.on()), 0.5);
}
