// CLEAR-MOT scoring (clear_mot.h) on tiny hand-computed sequences, and the KITTI tracking
// label and calibration readers (kitti_tracking.h) on files written here.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "urban_detection/core/tracking/clear_mot.h"
#include "urban_detection/core/tracking/kitti_tracking.h"

namespace core = urban_detection::core;

namespace {

core::MotGroundTruth gt(std::uint32_t id, double x, double y, bool ignored = false) {
  core::MotGroundTruth g;
  g.id = id;
  g.position = Eigen::Vector2d(x, y);
  g.ignored = ignored;
  return g;
}

core::MotHypothesis hyp(std::uint32_t id, double x, double y, bool dont_care = false) {
  core::MotHypothesis h;
  h.id = id;
  h.position = Eigen::Vector2d(x, y);
  h.dont_care = dont_care;
  return h;
}

std::string tempPath(const std::string& name) {
  return testing::TempDir() + "/ud_kitti_tracking_" + name;
}

}  // namespace

TEST(ClearMot, PerfectTrackingScoresOne) {
  core::ClearMot mot;
  for (int k = 0; k < 5; ++k) {
    mot.addFrame({gt(1, k, 0), gt(2, k, 5)}, {hyp(10, k + 0.1, 0), hyp(11, k, 5.2)});
  }
  const core::ClearMotResult r = mot.result();
  EXPECT_EQ(r.gt, 10u);
  EXPECT_EQ(r.matches, 10u);
  EXPECT_DOUBLE_EQ(r.mota(), 1.0);
  EXPECT_NEAR(r.motp_m(), 0.15, 1e-12);
  EXPECT_EQ(r.id_switches, 0u);
  EXPECT_EQ(r.gt_tracks, 2u);
  EXPECT_EQ(r.mostly_tracked, 2u);
}

TEST(ClearMot, HandComputedSequence) {
  // GT 1 walks along y = 0; GT 2 stands at (0, 10).
  //  f0: h7 on GT1, h8 on GT2                       -> 2 matches
  //  f1: h7 on GT1, nothing on GT2, h9 far away     -> 1 match, 1 miss, 1 FP
  //  f2: h9 on GT1 (switch 7 -> 9), h8 on GT2       -> 2 matches, 1 IDSW, 1 fragmentation (GT2)
  //  f3: h9 on GT1, h8 on GT2                       -> 2 matches
  // GT = 8, misses 1, FP 1, IDSW 1: MOTA = 1 - 3/8.
  core::ClearMot mot;
  mot.addFrame({gt(1, 0, 0), gt(2, 0, 10)}, {hyp(7, 0, 0), hyp(8, 0, 10)});
  mot.addFrame({gt(1, 1, 0), gt(2, 0, 10)}, {hyp(7, 1, 0), hyp(9, 30, 30)});
  mot.addFrame({gt(1, 2, 0), gt(2, 0, 10)}, {hyp(9, 2, 0.5), hyp(8, 0, 10)});
  mot.addFrame({gt(1, 3, 0), gt(2, 0, 10)}, {hyp(9, 3, 0), hyp(8, 0, 10)});
  const core::ClearMotResult r = mot.result();
  EXPECT_EQ(r.frames, 4u);
  EXPECT_EQ(r.gt, 8u);
  EXPECT_EQ(r.matches, 7u);
  EXPECT_EQ(r.misses, 1u);
  EXPECT_EQ(r.false_positives, 1u);
  EXPECT_EQ(r.id_switches, 1u);
  EXPECT_EQ(r.fragmentations, 1u);
  EXPECT_NEAR(r.mota(), 1.0 - 3.0 / 8.0, 1e-12);
  EXPECT_NEAR(r.motp_m(), 0.5 / 7.0, 1e-12);
  EXPECT_EQ(r.gt_tracks, 2u);
  EXPECT_EQ(r.mostly_tracked, 1u);     // GT1 4/4
  EXPECT_EQ(r.partially_tracked, 1u);  // GT2 3/4 < 0.8
  EXPECT_NEAR(r.idSwitchesPer100GtTracks(), 50.0, 1e-12);
}

TEST(ClearMot, KeepsThePreviousCorrespondenceWhileItHolds) {
  // Two hypotheses near GT 1; h5 was its match and is still within the threshold, so h6 being
  // closer does not make a switch (step 1 of the CLEAR-MOT procedure). h6 is then an FP.
  core::ClearMot mot;
  mot.addFrame({gt(1, 0, 0)}, {hyp(5, 0, 0)});
  std::vector<int> matched;
  mot.addFrame({gt(1, 0, 0)}, {hyp(5, 1.5, 0), hyp(6, 0.1, 0)}, &matched);
  ASSERT_EQ(matched.size(), 1u);
  EXPECT_EQ(matched[0], 0);
  const core::ClearMotResult r = mot.result();
  EXPECT_EQ(r.id_switches, 0u);
  EXPECT_EQ(r.false_positives, 1u);
}

TEST(ClearMot, IgnoredObjectsAndDontCareHypotheses) {
  // An ignored GT object takes the hypothesis on it out of the count; a don't-care hypothesis
  // that matches nothing is not an FP; an ordinary unmatched one is.
  core::ClearMot mot;
  mot.addFrame({gt(1, 0, 0), gt(2, 10, 0, true)},
               {hyp(1, 0, 0), hyp(2, 10.5, 0), hyp(3, 50, 0, true), hyp(4, -50, 0)});
  const core::ClearMotResult r = mot.result();
  EXPECT_EQ(r.gt, 1u);
  EXPECT_EQ(r.matches, 1u);
  EXPECT_EQ(r.false_positives, 1u);
  EXPECT_NEAR(r.mota(), 0.0, 1e-12);
  EXPECT_EQ(r.gt_tracks, 1u);
}

TEST(ClearMot, MostlyLostAndEmptyFrames) {
  core::ClearMot mot;
  mot.addFrame({}, {});
  for (int k = 0; k < 10; ++k) {
    std::vector<core::MotHypothesis> h;
    if (k == 0) h.push_back(hyp(1, 0, 0));
    mot.addFrame({gt(3, 0, 0)}, h);
  }
  const core::ClearMotResult r = mot.result();
  EXPECT_EQ(r.mostly_lost, 1u);  // 1/10 < 0.2
  EXPECT_EQ(r.misses, 9u);
  EXPECT_NEAR(r.mota(), 0.1, 1e-12);
  EXPECT_NEAR(r.recall(), 0.1, 1e-12);
}

TEST(KittiTracking, ReadsLabelsWithDontCareAndScores) {
  const std::string path = tempPath("labels.txt");
  {
    std::ofstream out(path);
    out << "0 -1 DontCare -1 -1 -10.000000 219.310000 188.490000 245.500000 218.560000 "
           "-1000.000000 -1000.000000 -1000.000000 -10.000000 -1.000000 -1.000000 -1.000000\n"
        << "0 0 Van 0 0 -1.793451 296.744956 161.752147 455.226042 292.372804 2.000000 "
           "1.823255 4.433886 -4.552284 1.858523 13.410495 -2.115488\n"
        << "\n"
        << "1 0 Van 0 0 -1.796862 294.898777 156.024256 452.199718 284.621269 2.000000 "
           "1.823255 4.433886 -4.650955 1.766774 13.581085 -2.121565\n"
        << "1 2 Pedestrian 0 0 -2.523309 1106.137292 166.576807 1204.470628 323.876144 "
           "1.714062 0.767881 0.972283 6.301919 1.652419 8.455685 -1.900245 0.87\n";
  }
  std::map<int, std::vector<core::KittiTrackingLabel>> labels;
  std::string error;
  ASSERT_TRUE(core::readKittiTrackingLabels(path, &labels, &error)) << error;
  ASSERT_EQ(labels.size(), 2u);
  ASSERT_EQ(labels[0].size(), 2u);
  ASSERT_EQ(labels[1].size(), 2u);
  EXPECT_TRUE(labels[0][0].dontCare());
  EXPECT_EQ(labels[0][0].track_id, -1);
  EXPECT_EQ(labels[0][1].type, "Van");
  EXPECT_EQ(labels[0][1].track_id, 0);
  EXPECT_DOUBLE_EQ(labels[0][1].height_m, 2.0);
  EXPECT_DOUBLE_EQ(labels[0][1].length_m, 4.433886);
  EXPECT_DOUBLE_EQ(labels[0][1].location.z(), 13.410495);
  EXPECT_DOUBLE_EQ(labels[0][1].rotation_y, -2.115488);
  EXPECT_DOUBLE_EQ(labels[0][1].score, 1.0);
  EXPECT_EQ(labels[1][1].track_id, 2);
  EXPECT_DOUBLE_EQ(labels[1][1].score, 0.87);
  EXPECT_DOUBLE_EQ(labels[1][1].bbox[2], 1204.470628);
  std::remove(path.c_str());
}

TEST(KittiTracking, RefusesMalformedLines) {
  core::KittiTrackingLabel l;
  EXPECT_FALSE(core::parseKittiTrackingLine("0 1 Car 0 0", &l));
  EXPECT_FALSE(core::parseKittiTrackingLine("x 1 Car 0 0 0 1 2 3 4 1.5 1.6 3.9 1 2 3 0.1", &l));
  EXPECT_FALSE(core::parseKittiTrackingLine("0 1 Car 0 0 0 1 2 3 4 1.5 nan 3.9 1 2 3 0.1", &l));
  EXPECT_FALSE(core::parseKittiTrackingLine("0 -2 Car 0 0 0 1 2 3 4 1.5 1.6 3.9 1 2 3 0.1", &l));
  EXPECT_TRUE(core::parseKittiTrackingLine("3 1 Car 0 0 0 1 2 3 4 1.5 1.6 3.9 1 2 3 0.1", &l));
  EXPECT_EQ(l.frame, 3);
  const std::string path = tempPath("bad.txt");
  {
    std::ofstream out(path);
    out << "0 1 Car 0 0 0 1 2 3 4 1.5 1.6 3.9 1 2 3 0.1\n0 2 Car 0 0\n";
  }
  std::map<int, std::vector<core::KittiTrackingLabel>> labels;
  std::string error;
  EXPECT_FALSE(core::readKittiTrackingLabels(path, &labels, &error));
  EXPECT_NE(error.find(":2:"), std::string::npos) << error;
  EXPECT_FALSE(core::readKittiTrackingLabels(tempPath("missing.txt"), &labels, &error));
  std::remove(path.c_str());
}

TEST(KittiTracking, CalibrationAndBoxGeometry) {
  // A tracking calib file (R_rect / Tr_velo_cam without colons) with the usual KITTI axes:
  // camera x = -velo y, camera y = -velo z, camera z = velo x.
  const std::string path = tempPath("calib.txt");
  {
    std::ofstream out(path);
    out << "P0: 721.5 0 609.5 0 0 721.5 172.8 0 0 0 1 0\n"
        << "P2: 721.5 0 609.5 44.8 0 721.5 172.8 0.2 0 0 1 0.003\n"
        << "R_rect 1 0 0 0 1 0 0 0 1\n"
        << "Tr_velo_cam 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n"
        << "Tr_imu_velo 1 0 0 0 0 1 0 0 0 0 1 0\n";
  }
  core::KittiTrackingCalibration calib;
  std::string error;
  ASSERT_TRUE(core::readKittiTrackingCalibration(path, &calib, &error)) << error;
  const Eigen::Vector3d p(10.0, 2.0, -0.5);
  EXPECT_LT((calib.rectToVelo(calib.veloToRect(p)) - p).norm(), 1e-9);
  double u, v;
  EXPECT_TRUE(calib.project(Eigen::Vector3d(10, 0, 0), &u, &v));
  EXPECT_NEAR(u, 609.5 + 44.8 / 10.0, 1.0);
  EXPECT_FALSE(calib.project(Eigen::Vector3d(-10, 0, 0), &u, &v));  // behind the camera

  // A car 10 m ahead (camera z), 4 m long along the camera x axis (rotation_y 0).
  core::KittiTrackingLabel car;
  ASSERT_TRUE(core::parseKittiTrackingLine("0 1 Car 0 0 0 0 0 10 10 1.5 1.8 4.0 0 1.0 10 0", &car));
  const Eigen::Vector3d centre = core::kittiTrackingBoxCenterVelo(car, calib);
  EXPECT_TRUE(core::insideKittiTrackingBox(car, calib, centre));
  // Along the length: camera x = -velo y; 1.9 m inside, 2.1 m outside.
  EXPECT_TRUE(core::insideKittiTrackingBox(car, calib, centre + Eigen::Vector3d(0, 1.9, 0)));
  EXPECT_FALSE(core::insideKittiTrackingBox(car, calib, centre + Eigen::Vector3d(0, 2.1, 0)));
  EXPECT_FALSE(core::insideKittiTrackingBox(car, calib, centre + Eigen::Vector3d(1.0, 0, 0)));
  EXPECT_TRUE(core::insideKittiTrackingBox(car, calib, centre + Eigen::Vector3d(1.0, 0, 0), 0.2));

  std::ofstream(path) << "P2: 1 2 3\n";
  EXPECT_FALSE(core::readKittiTrackingCalibration(path, &calib, &error));
  EXPECT_NE(error.find("P2"), std::string::npos);
  std::remove(path.c_str());
}
