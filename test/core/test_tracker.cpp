// Tracker: constant-velocity targets, crossing targets, birth and death, ego-motion
// compensation, the Hungarian solver against brute force, parameter validation and hostile
// input. Synthetic detections only; no ROS.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "urban_detection/core/tracking/hungarian.h"
#include "urban_detection/core/tracking/tracker.h"

namespace core = urban_detection::core;

namespace {

constexpr double kDt = 0.1;  // [s] one revolution at 600 rpm

core::DetectedObject box(double x, double y, double yaw = 0.0, double l = 4.2, double w = 1.8,
                         core::ObjectCategory c = core::ObjectCategory::kVehicle) {
  core::DetectedObject o;
  o.obb_center = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), 0.8f);
  o.obb_size = Eigen::Vector3f(static_cast<float>(l), static_cast<float>(w), 1.5f);
  o.obb_yaw_rad = static_cast<float>(yaw);
  o.centroid = o.obb_center;
  o.category = c;
  o.class_confidence = 0.9f;
  return o;
}

const core::Track* trackNear(const core::Tracker& t, double x, double y, double within = 1.5) {
  for (const core::Track& tr : t.tracks()) {
    if (std::hypot(tr.center.x() - x, tr.center.y() - y) < within) return &tr;
  }
  return nullptr;
}

core::TrackerParams fast() {
  core::TrackerParams p;
  p.birth_hits = 3;
  p.death_misses = 4;
  p.tentative_max_misses = 2;
  return p;
}

}  // namespace

TEST(Tracker, ConstantVelocityTargetKeepsOneIdAndItsVelocityConverges) {
  core::Tracker tracker(fast());
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  const Eigen::Vector2d v(8.0, -1.5);
  std::uint32_t id = 0;
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector2d p = Eigen::Vector2d(-20, 5) + v * (k * kDt);
    tracker.update({box(p.x() + noise(rng), p.y() + noise(rng), std::atan2(v.y(), v.x()))},
                   Eigen::Isometry3d::Identity(), 100.0 + k * kDt);
    ASSERT_EQ(tracker.tracks().size(), 1u) << "revolution " << k;
    if (k == 0) id = tracker.tracks()[0].id;
    EXPECT_EQ(tracker.tracks()[0].id, id);
  }
  const core::Track& t = tracker.tracks()[0];
  EXPECT_EQ(t.state, core::TrackState::kConfirmed);
  EXPECT_EQ(t.hits, 40u);
  EXPECT_NEAR(t.velocity.x(), v.x(), 0.4);
  EXPECT_NEAR(t.velocity.y(), v.y(), 0.4);
  EXPECT_LT(t.velocity_covariance.trace(), 1.0);
  // Heading along the velocity, not the opposite way.
  EXPECT_NEAR(std::cos(t.yaw_rad - std::atan2(v.y(), v.x())), 1.0, 0.05);
  EXPECT_EQ(t.category, core::ObjectCategory::kVehicle);
}

TEST(Tracker, TwoCrossingTargetsKeepTheirIds) {
  core::Tracker tracker(fast());
  // Two cars on crossing diagonals, meeting at the origin at k = 20: they pass 1.2 m apart.
  std::uint32_t id_a = 0, id_b = 0;
  for (int k = 0; k <= 40; ++k) {
    const double s = (k - 20) * kDt;
    const Eigen::Vector2d a(6.0 * s - 0.6, 6.0 * s), b(6.0 * s + 0.6, -6.0 * s);
    tracker.update({box(a.x(), a.y(), M_PI / 4, 1.0, 0.8), box(b.x(), b.y(), -M_PI / 4, 1.0, 0.8)},
                   Eigen::Isometry3d::Identity(), k * kDt);
    ASSERT_EQ(tracker.tracks().size(), 2u) << "revolution " << k;
    const core::Track* ta = trackNear(tracker, a.x(), a.y(), 0.5);
    const core::Track* tb = trackNear(tracker, b.x(), b.y(), 0.5);
    ASSERT_TRUE(ta && tb) << "revolution " << k;
    if (k == 0) {
      id_a = ta->id;
      id_b = tb->id;
    }
    EXPECT_EQ(ta->id, id_a) << "revolution " << k;
    EXPECT_EQ(tb->id, id_b) << "revolution " << k;
  }
}

TEST(Tracker, BirthAfterNHitsDeathAfterMMisses) {
  core::TrackerParams p = fast();
  core::Tracker tracker(p);
  double t = 0.0;
  for (int k = 0; k < p.birth_hits; ++k, t += kDt) {
    tracker.update({box(10, 0)}, Eigen::Isometry3d::Identity(), t);
    ASSERT_EQ(tracker.tracks().size(), 1u);
    EXPECT_EQ(tracker.tracks()[0].state,
              k + 1 < p.birth_hits ? core::TrackState::kTentative : core::TrackState::kConfirmed)
        << "hit " << k + 1;
  }
  const std::uint32_t id = tracker.tracks()[0].id;
  for (int k = 1; k <= p.death_misses; ++k, t += kDt) {
    tracker.update({}, Eigen::Isometry3d::Identity(), t);
    if (k < p.death_misses) {
      ASSERT_EQ(tracker.tracks().size(), 1u) << "miss " << k;
      EXPECT_EQ(tracker.tracks()[0].state, core::TrackState::kLost);
      EXPECT_TRUE(tracker.died().empty());
    } else {
      EXPECT_TRUE(tracker.tracks().empty());
      ASSERT_EQ(tracker.died().size(), 1u);
      EXPECT_EQ(tracker.died()[0], id);
    }
  }
  // A new object gets a new id; a tentative one dies after tentative_max_misses misses.
  tracker.update({box(-10, 0)}, Eigen::Isometry3d::Identity(), t += kDt);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_GT(tracker.tracks()[0].id, id);
  EXPECT_EQ(tracker.tracks()[0].state, core::TrackState::kTentative);
  for (int k = 0; k < p.tentative_max_misses; ++k) {
    tracker.update({}, Eigen::Isometry3d::Identity(), t += kDt);
  }
  EXPECT_TRUE(tracker.tracks().empty());
}

TEST(Tracker, LostTrackRecoveredKeepsItsId) {
  core::Tracker tracker(fast());
  double t = 0.0;
  for (int k = 0; k < 5; ++k, t += kDt)
    tracker.update({box(10, 0)}, Eigen::Isometry3d::Identity(), t);
  const std::uint32_t id = tracker.tracks()[0].id;
  tracker.update({}, Eigen::Isometry3d::Identity(), t += kDt);
  EXPECT_EQ(tracker.tracks()[0].state, core::TrackState::kLost);
  tracker.update({box(10, 0)}, Eigen::Isometry3d::Identity(), t += kDt);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].id, id);
  EXPECT_EQ(tracker.tracks()[0].state, core::TrackState::kConfirmed);
}

TEST(Tracker, StaticObjectFromMovingSensorHasNoVelocity) {
  // The sensor drives along x at 10 m/s and turns slowly; a parked car at (30, 4) in odom is
  // seen in the sensor frame moving backwards. With the poses it must stand still.
  core::Tracker tracker(fast());
  const Eigen::Vector3d parked(30.0, 4.0, 0.8);
  for (int k = 0; k < 30; ++k) {
    Eigen::Isometry3d odom_T_sensor = Eigen::Isometry3d::Identity();
    odom_T_sensor.translation() = Eigen::Vector3d(10.0 * k * kDt, 0.2 * k * kDt, 1.7);
    odom_T_sensor.linear() = Eigen::AngleAxisd(0.02 * k, Eigen::Vector3d::UnitZ()).matrix();
    const Eigen::Vector3d in_sensor = odom_T_sensor.inverse() * parked;
    const double yaw_in_sensor = 0.3 - 0.02 * k;
    core::DetectedObject o = box(in_sensor.x(), in_sensor.y(), yaw_in_sensor);
    o.obb_center.z() = static_cast<float>(in_sensor.z());
    tracker.update({o}, odom_T_sensor, k * kDt);
    ASSERT_EQ(tracker.tracks().size(), 1u);
  }
  const core::Track& t = tracker.tracks()[0];
  EXPECT_LT(t.speed(), 0.05);
  EXPECT_NEAR(t.center.x(), parked.x(), 0.05);
  EXPECT_NEAR(t.center.y(), parked.y(), 0.05);
  EXPECT_NEAR(t.center.z(), parked.z(), 0.05);
  EXPECT_NEAR(std::cos(t.yaw_rad - 0.3), 1.0, 1e-3);
  // The same drive without poses sees it move at the sensor's speed.
  core::Tracker blind(fast());
  for (int k = 0; k < 30; ++k) {
    const Eigen::Vector3d in_sensor(30.0 - 10.0 * k * kDt, 4.0, 0.8);
    blind.update({box(in_sensor.x(), in_sensor.y())}, Eigen::Isometry3d::Identity(), k * kDt);
  }
  ASSERT_EQ(blind.tracks().size(), 1u);
  EXPECT_NEAR(blind.tracks()[0].speed(), 10.0, 0.5);
}

TEST(Tracker, ManyObjectsKeepTheirIds) {
  core::Tracker tracker(fast());
  std::vector<core::DetectedObject> objects;
  for (int k = 0; k < 100; ++k)
    objects.push_back(box(6.0 * (k % 10), 4.0 * (k / 10), 0.0, 4.0, 1.8));
  for (int r = 0; r < 10; ++r) tracker.update(objects, Eigen::Isometry3d::Identity(), r * kDt);
  ASSERT_EQ(tracker.tracks().size(), 100u);
  for (const core::Track& t : tracker.tracks()) {
    EXPECT_EQ(t.state, core::TrackState::kConfirmed);
    EXPECT_LE(t.id, 100u);
    EXPECT_EQ(t.detection, static_cast<int>(t.id) - 1);  // each kept its own detection
  }
}

TEST(Tracker, HostileInputIsSkippedNotFatal) {
  core::Tracker tracker(fast());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<core::DetectedObject> objects = {box(1, 1), box(5, 5), box(9, 9), box(13, 13)};
  objects[0].obb_center.x() = nan;
  objects[1].obb_size.y() = inf;
  objects[2].obb_yaw_rad = nan;
  const core::TrackerStats& s = tracker.update(objects, Eigen::Isometry3d::Identity(), 0.0);
  EXPECT_EQ(s.invalid_detections, 3u);
  EXPECT_EQ(tracker.tracks().size(), 1u);
  // Empty input, a NaN stamp and a NaN pose do not crash either.
  tracker.update({}, Eigen::Isometry3d::Identity(), std::nan(""));
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = std::nan("");
  EXPECT_EQ(tracker.update({box(1, 1)}, bad, 0.2).invalid_detections, 1u);
  // Time going back restarts the tracker; ids keep rising.
  const std::uint32_t before = tracker.tracks().empty() ? 0 : tracker.tracks().back().id;
  EXPECT_TRUE(tracker.update({box(2, 2)}, Eigen::Isometry3d::Identity(), -5.0).restarted);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_GT(tracker.tracks()[0].id, before);
}

TEST(TrackerParams, ValidateRefusesOutOfRangeAndNaN) {
  EXPECT_EQ(core::validate(core::TrackerParams()), "");
  core::TrackerParams p;
  p.gate_distance_m = -1.0;
  EXPECT_NE(core::validate(p).find("gate_distance_m"), std::string::npos) << core::validate(p);
  EXPECT_NE(core::validate(p).find("accepted [0.1, 20] m"), std::string::npos) << core::validate(p);
  p = core::TrackerParams();
  p.measurement_std_m = std::nan("");
  EXPECT_NE(core::validate(p).find("measurement_std_m"), std::string::npos);
  p = core::TrackerParams();
  p.birth_hits = 0;
  EXPECT_NE(core::validate(p).find("birth_hits"), std::string::npos);
  p = core::TrackerParams();
  p.death_misses = 100000;
  EXPECT_NE(core::validate(p).find("death_misses"), std::string::npos);
  p = core::TrackerParams();
  p.smoothing = 1.5;
  EXPECT_NE(core::validate(p).find("smoothing"), std::string::npos);
  p = core::TrackerParams();
  p.max_dt_s = 0.01;
  p.default_dt_s = 0.1;
  EXPECT_NE(core::validate(p).find("max_dt_s"), std::string::npos);
  p.gate_distance_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(core::Tracker{p}, std::invalid_argument);
}

TEST(BevIoU, KnownOverlaps) {
  const Eigen::Vector2d o(0, 0);
  EXPECT_NEAR(core::bevIoU(o, 2, 2, 0, o, 2, 2, 0), 1.0, 1e-9);
  EXPECT_NEAR(core::bevIoU(o, 2, 2, 0, Eigen::Vector2d(1, 0), 2, 2, 0), 1.0 / 3.0, 1e-9);
  EXPECT_NEAR(core::bevIoU(o, 2, 2, 0, Eigen::Vector2d(5, 0), 2, 2, 0), 0.0, 1e-12);
  EXPECT_NEAR(core::bevIoU(o, 2, 2, 0, o, 2, 2, M_PI / 2), 1.0, 1e-9);
  // A square and the same square turned 45 degrees: intersection is the regular octagon.
  const double oct = 8.0 * (std::sqrt(2.0) - 1.0);  // area of the octagon in a 2x2 square
  EXPECT_NEAR(core::bevIoU(o, 2, 2, 0, o, 2, 2, M_PI / 4), oct / (8.0 - oct), 1e-9);
  EXPECT_EQ(core::bevIoU(o, 0, 2, 0, o, 2, 2, 0), 0.0);
}

namespace {

double bruteForce(const std::vector<double>& c, int rows, int cols) {
  // Every injective map of the smaller side into the larger one.
  const bool by_rows = rows <= cols;
  const int n = by_rows ? rows : cols, m = by_rows ? cols : rows;
  std::vector<int> perm(m);
  std::iota(perm.begin(), perm.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += by_rows ? c[i * cols + perm[i]] : c[perm[i] * cols + i];
    best = std::min(best, s);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

}  // namespace

TEST(Hungarian, OptimalOnSmallMatricesAgainstBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  std::uniform_int_distribution<int> size(1, 6);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = size(rng), cols = size(rng);
    std::vector<double> c(rows * cols);
    for (double& x : c) x = trial % 3 == 0 ? std::round(u(rng)) : u(rng);  // ties too
    std::vector<int> a;
    const double total = core::solveAssignment(c, rows, cols, &a);
    ASSERT_EQ(a.size(), static_cast<std::size_t>(rows));
    // A valid one-to-one assignment of min(rows, cols) pairs whose cost is what it reports.
    std::vector<int> used(cols, 0);
    int pairs = 0;
    double check = 0.0;
    for (int r = 0; r < rows; ++r) {
      if (a[r] < 0) continue;
      ASSERT_LT(a[r], cols);
      ASSERT_EQ(used[a[r]]++, 0);
      ++pairs;
      check += c[r * cols + a[r]];
    }
    EXPECT_EQ(pairs, std::min(rows, cols));
    EXPECT_NEAR(total, check, 1e-9);
    EXPECT_NEAR(total, bruteForce(c, rows, cols), 1e-9)
        << rows << "x" << cols << " trial " << trial;
  }
  std::vector<int> a;
  EXPECT_EQ(core::solveAssignment({}, 0, 3, &a), 0.0);
  EXPECT_TRUE(a.empty());
}

TEST(Tracker, ResetReportsTheDroppedTracks) {
  core::Tracker tracker(fast());
  tracker.update({box(1, 1), box(9, 9)}, Eigen::Isometry3d::Identity(), 0.0);
  tracker.reset();
  tracker.update({}, Eigen::Isometry3d::Identity(), 0.1);
  EXPECT_EQ(tracker.died().size(), 2u);
  EXPECT_TRUE(tracker.tracks().empty());
}
