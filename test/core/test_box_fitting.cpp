// Whole-object boxes (box_fitting.h), the track class evidence (class_evidence.h) and the box
// quality scores (box_quality.h).
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/evaluation/box_quality.h"
#include "urban_detection/core/tracking/class_evidence.h"
#include "urban_detection/core/tracking/tracker.h"

namespace core = urban_detection::core;
using urban_detection::LabeledCloud;
using urban_detection::LabeledPoint;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Difference of two box yaws modulo 180 deg, in [0, 90] deg.
double headingErrorDeg(double a, double b) {
  double d = std::fmod(std::fabs(a - b), kPi);
  if (d > 0.5 * kPi) d = kPi - d;
  return d * 180.0 / kPi;
}

// The points a sensor at the origin sees of a rectangle (centre c, length l along yaw, width
// w): the faces whose outward normal points towards it, sampled at the spacing of a 0.17 deg
// azimuth step at that range, with `noise_m` of Gaussian noise.
std::vector<Eigen::Vector2f> visibleFaces(const Eigen::Vector2d& c, double l, double w, double yaw,
                                          double noise_m, std::mt19937* rng,
                                          int* faces_seen = nullptr) {
  std::normal_distribution<double> noise(0.0, noise_m);
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw)), ay(-ax.y(), ax.x());
  const Eigen::Vector2d corner[4] = {
      c + 0.5 * l * ax + 0.5 * w * ay, c - 0.5 * l * ax + 0.5 * w * ay,
      c - 0.5 * l * ax - 0.5 * w * ay, c + 0.5 * l * ax - 0.5 * w * ay};
  const double spacing = std::max(0.02, c.norm() * 0.17 * kPi / 180.0);
  std::vector<Eigen::Vector2f> pts;
  int faces = 0;
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d a = corner[e], b = corner[(e + 1) % 4];
    const Eigen::Vector2d mid = 0.5 * (a + b);
    if ((mid - c).dot(mid) >= -1e-9) continue;  // faces away (or edge-on)
    ++faces;
    const int steps = std::max(1, static_cast<int>((b - a).norm() / spacing));
    for (int k = 0; k <= steps; ++k) {
      const Eigen::Vector2d q = a + (b - a) * (static_cast<double>(k) / steps);
      pts.emplace_back(static_cast<float>(q.x() + noise(*rng)),
                       static_cast<float>(q.y() + noise(*rng)));
    }
  }
  if (faces_seen) *faces_seen = faces;
  return pts;
}

// The plain reference of the heading search: every point, the whole quarter turn in 0.1 deg
// steps, the best closeness score.
double referenceHeading(const std::vector<Eigen::Vector2f>& pts, double d0) {
  double best = 0.0, best_score = -1.0;
  for (int k = 0; k < 900; ++k) {
    const double t = k * 0.1 * kPi / 180.0;
    const double s = core::closenessScore(pts.data(), pts.size(), t, d0);
    if (s > best_score) {
      best_score = s;
      best = t;
    }
  }
  return best;
}

}  // namespace

// L-shaped and I-shaped cars of the prior's size at many headings, ranges and bearings: the
// whole-object box's centre and heading are those of the car.
TEST(BoxFitting, CarsAtHeadingsAndRangesGiveTheirCentreAndHeading) {
  std::mt19937 rng(39);
  core::BoxFitter fitter;
  const double l = fitter.params().vehicle_length_m, w = fitter.params().vehicle_width_m;
  int cases = 0, one_face = 0;
  for (const double range : {6.0, 12.0, 20.0, 35.0}) {
    for (const double bearing_deg : {0.0, 30.0, 90.0, 145.0, -60.0}) {
      for (const double heading_deg : {0.0, 15.0, 40.0, 90.0, 125.0, 170.0}) {
        const double b = bearing_deg * kPi / 180.0, yaw = heading_deg * kPi / 180.0;
        const Eigen::Vector2d c(range * std::cos(b), range * std::sin(b));
        int faces = 0;
        const auto pts = visibleFaces(c, l, w, yaw, 0.02, &rng, &faces);
        one_face += faces == 1;
        const core::BevBox box =
            fitter.fitPoints(pts.data(), pts.size(), core::ObjectCategory::kVehicle);
        SCOPED_TRACE(::testing::Message() << "range " << range << " bearing " << bearing_deg
                                          << " heading " << heading_deg << " faces " << faces);
        EXPECT_LT((box.center.cast<double>() - c).norm(), 0.25);
        EXPECT_LT(headingErrorDeg(box.yaw_rad, yaw), 3.0);
        EXPECT_NEAR(box.size.x(), l, 0.15);
        EXPECT_NEAR(box.size.y(), w, 0.15);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 120);
  EXPECT_GT(one_face, 10);  // I-shapes (one face) are among them
}

// Only the back of a car straight ahead: the box grows away from the sensor, the back face
// stays where it was seen.
TEST(BoxFitting, BackFaceOnlyGrowsAwayFromTheSensor) {
  std::mt19937 rng(1);
  core::BoxFitter fitter;
  const double l = fitter.params().vehicle_length_m;
  const Eigen::Vector2d c(15.0 + 0.5 * l, 0.0);
  int faces = 0;
  const auto pts = visibleFaces(c, l, fitter.params().vehicle_width_m, 0.0, 0.01, &rng, &faces);
  ASSERT_EQ(faces, 1);
  const core::BevBox box = fitter.fitPoints(pts.data(), pts.size(), core::ObjectCategory::kVehicle);
  EXPECT_NEAR(box.center.x(), c.x(), 0.1);
  EXPECT_NEAR(box.center.y(), 0.0, 0.1);
  EXPECT_LT(headingErrorDeg(box.yaw_rad, 0.0), 2.0);
  EXPECT_NEAR(box.center.x() - 0.5 * box.size.x(), 15.0, 0.05);  // the seen face stays
}

// A larger object than the prior (a van) keeps its seen extent; a partly seen side is
// lengthened to the prior length away from the sensor; other classes get no prior.
TEST(BoxFitting, PriorsOnlyLengthen) {
  std::mt19937 rng(2);
  core::BoxFitter fitter;
  // A 6 m van side on, beside the sensor.
  auto van = visibleFaces(Eigen::Vector2d(0.0, 6.0), 6.0, 2.1, 0.0, 0.01, &rng);
  core::BevBox box = fitter.fitPoints(van.data(), van.size(), core::ObjectCategory::kVehicle);
  EXPECT_NEAR(box.size.x(), 6.0, 0.1);
  EXPECT_NEAR(box.size.y(), fitter.params().vehicle_width_m, 0.05);
  // Width grows away from the sensor: the seen side at y = 4.95 stays.
  EXPECT_NEAR(box.center.y() - 0.5 * box.size.y(), 6.0 - 1.05, 0.05);
  // The same points as "other object": the points' own rectangle.
  box = fitter.fitPoints(van.data(), van.size(), core::ObjectCategory::kOtherObject);
  EXPECT_NEAR(box.size.x(), 6.0, 0.1);
  EXPECT_LT(box.size.y(), 0.1);
  // A pedestrian's few points: the prior's footprint around them, pushed away.
  std::vector<Eigen::Vector2f> ped = {{10.0f, 0.1f}, {10.0f, -0.1f}, {10.02f, 0.0f}};
  box = fitter.fitPoints(ped.data(), ped.size(), core::ObjectCategory::kPedestrian);
  EXPECT_NEAR(box.size.x(), 0.8, 1e-3);
  EXPECT_NEAR(box.size.y(), 0.6, 1e-3);
  EXPECT_GT(box.center.x(), 10.2);
}

// The coarse-to-fine search on a stride sample finds the heading of the plain reference (all
// points, 0.1 deg steps) on random L-shapes of random objects.
TEST(BoxFitting, SearchAgreesWithTheExhaustiveReference) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  core::BoxFitter fitter;
  int close = 0;
  const int n = 200;
  for (int k = 0; k < n; ++k) {
    const double range = 5.0 + 30.0 * u(rng), bearing = 2.0 * kPi * u(rng);
    const double yaw = kPi * u(rng), l = 2.0 + 4.0 * u(rng), w = 1.0 + 1.0 * u(rng);
    const auto pts =
        visibleFaces(Eigen::Vector2d(range * std::cos(bearing), range * std::sin(bearing)), l, w,
                     yaw, 0.03, &rng);
    const double fast = fitter.searchHeading(pts.data(), pts.size());
    const double ref = referenceHeading(pts, fitter.params().closeness_min_distance_m);
    // Both modulo 90 deg.
    double d = std::fmod(std::fabs(fast - ref), 0.5 * kPi);
    d = std::min(d, 0.5 * kPi - d) * 180.0 / kPi;
    close += d <= 2.0;
    // And both near the truth.
    double t = std::fmod(std::fabs(fast - yaw), 0.5 * kPi);
    t = std::min(t, 0.5 * kPi - t) * 180.0 / kPi;
    EXPECT_LT(t, 6.0) << "case " << k;
  }
  // The stride sample and the coarse sweep may settle in another basin of nearly equal score.
  EXPECT_GE(close, n * 9 / 10);
}

// fit() on a cloud: objects find their points by index; points not in the foreground and NaN
// points are skipped; an object without points keeps its box; disabled does nothing.
TEST(BoxFitting, FitOnCloudAndEdgeCases) {
  std::mt19937 rng(3);
  LabeledCloud fg;
  const auto pts = visibleFaces(Eigen::Vector2d(10.0, 5.0), 3.9, 1.6, 0.3, 0.01, &rng);
  core::DetectedObject car;
  for (const auto& p : pts) {
    LabeledPoint q;
    q.x = p.x();
    q.y = p.y();
    q.z = 0.5f;
    q.index = static_cast<std::uint32_t>(1000 + fg.size());
    car.indices.push_back(q.index);
    fg.push_back(q);
  }
  LabeledPoint nan_point;
  nan_point.x = std::nanf("");
  nan_point.index = 5000;
  fg.push_back(nan_point);
  car.indices.push_back(5000);
  car.indices.push_back(777777);  // not in the foreground
  car.category = core::ObjectCategory::kVehicle;
  car.obb_center = Eigen::Vector3f(9.0f, 4.0f, 0.7f);
  car.obb_size = Eigen::Vector3f(2.0f, 1.0f, 1.4f);
  core::DetectedObject empty;
  empty.indices = {123456};
  empty.obb_center = Eigen::Vector3f(1, 2, 3);
  std::vector<core::DetectedObject> objects = {car, empty};

  core::BoxFittingParams off;
  off.enabled = false;
  core::BoxFitter(off).fit(fg, &objects);
  EXPECT_EQ(objects[0].obb_center, car.obb_center);

  core::BoxFitter fitter;
  fitter.fit(fg, &objects);
  EXPECT_NEAR(objects[0].obb_center.x(), 10.0f, 0.2f);
  EXPECT_NEAR(objects[0].obb_center.y(), 5.0f, 0.2f);
  EXPECT_FLOAT_EQ(objects[0].obb_center.z(), 0.7f);  // height kept
  EXPECT_FLOAT_EQ(objects[0].obb_size.z(), 1.4f);
  EXPECT_LT(headingErrorDeg(objects[0].obb_yaw_rad, 0.3), 3.0);
  EXPECT_EQ(objects[1].obb_center, Eigen::Vector3f(1, 2, 3));

  // One and two points: no heading search, the fallback yaw; finite boxes.
  const Eigen::Vector2f one[2] = {{5.0f, 0.0f}, {5.0f, 1.0f}};
  core::BevBox b =
      fitter.fitPoints(one, 1, core::ObjectCategory::kVehicle, Eigen::Vector2f::Zero(), 0.25f);
  EXPECT_TRUE(b.center.allFinite());
  EXPECT_NEAR(b.size.x(), 3.9f, 1e-4);
  b = fitter.fitPoints(one, 2, core::ObjectCategory::kUnknown, Eigen::Vector2f::Zero(), 0.0f);
  EXPECT_NEAR(b.size.x(), 1.0f, 1e-5);
  EXPECT_NEAR(b.size.y(), 0.0f, 1e-5);
}

TEST(BoxFitting, ValidateRefusesBadParameters) {
  core::BoxFittingParams p;
  EXPECT_EQ(core::validate(p), "");
  p.vehicle_width_m = 5.0;
  EXPECT_NE(core::validate(p).find("vehicle_width_m"), std::string::npos);
  p = core::BoxFittingParams();
  p.coarse_step_deg = std::nan("");
  EXPECT_NE(core::validate(p).find("coarse_step_deg"), std::string::npos);
  EXPECT_THROW(core::BoxFitter{p}, std::invalid_argument);
}

// A parked car seen from a passing sensor: its detections show different faces; the track's
// whole-object box stays put (centre, size and heading steady).
TEST(BoxFitting, ParkedCarTrackBoxDoesNotBreathe) {
  std::mt19937 rng(5);
  core::BoxFitter fitter;
  core::Tracker tracker;
  const Eigen::Vector2d car(20.0, 4.0);
  std::vector<double> length, cx;
  for (int r = 0; r < 40; ++r) {
    const double t = 0.1 * r;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(8.0 * t, 0.0, 0.0);  // drives past the car
    const Eigen::Vector2d rel = car - pose.translation().head<2>();
    const auto pts = visibleFaces(rel, 3.9, 1.6, 0.1, 0.02, &rng);
    core::DetectedObject o;
    const core::BevBox b = fitter.fitPoints(pts.data(), pts.size(), core::ObjectCategory::kVehicle);
    o.obb_center = Eigen::Vector3f(b.center.x(), b.center.y(), 0.8f);
    o.obb_size = Eigen::Vector3f(b.size.x(), b.size.y(), 1.5f);
    o.obb_yaw_rad = b.yaw_rad;
    o.category = core::ObjectCategory::kVehicle;
    o.class_confidence = 0.7f;
    tracker.update({o}, pose, t);
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const core::Track& tr = tracker.tracks()[0];
    if (r >= 5) {
      length.push_back(tr.size.x());
      cx.push_back(tr.center.x());
      EXPECT_LT((tr.center.head<2>() - car).norm(), 0.2) << "revolution " << r;
      EXPECT_LT(headingErrorDeg(tr.yaw_rad, 0.1), 3.0);
    }
  }
  const auto [lo, hi] = std::minmax_element(length.begin(), length.end());
  EXPECT_LT(*hi - *lo, 0.15);
  const auto [xlo, xhi] = std::minmax_element(cx.begin(), cx.end());
  EXPECT_LT(*xhi - *xlo, 0.25);
}

TEST(ClassEvidence, AccumulatesAndComesRound) {
  core::ClassEvidence e;
  EXPECT_EQ(e.category(), core::ObjectCategory::kUnknown);
  EXPECT_EQ(e.probability(), 0.0f);
  e.add(core::ObjectCategory::kUnknown, 0.9f);  // unclassified: no evidence
  EXPECT_EQ(e.count(), 0u);
  for (int k = 0; k < 3; ++k) e.add(core::ObjectCategory::kVehicle, 0.6f);
  EXPECT_EQ(e.category(), core::ObjectCategory::kVehicle);
  const float p3 = e.probability();
  e.add(core::ObjectCategory::kVehicle, 0.6f);
  EXPECT_GT(e.probability(), p3);  // more agreeing evidence, more belief
  // One confident other class does not overturn four agreeing detections...
  e.add(core::ObjectCategory::kOtherObject, 0.95f);
  EXPECT_EQ(e.category(), core::ObjectCategory::kVehicle);
  // ...but a run of them does, within a few revolutions even after a long history.
  for (int k = 0; k < 200; ++k) e.add(core::ObjectCategory::kVehicle, 0.99f);
  int needed = 0;
  while (e.category() != core::ObjectCategory::kPedestrian && needed < 50) {
    e.add(core::ObjectCategory::kPedestrian, 0.9f);
    ++needed;
  }
  EXPECT_EQ(e.category(), core::ObjectCategory::kPedestrian);
  EXPECT_LE(needed, 6);
  e.add(core::ObjectCategory::kCyclist, std::nanf(""));  // NaN: weakest evidence, no harm
  EXPECT_EQ(e.category(), core::ObjectCategory::kPedestrian);
  EXPECT_GT(e.probability(), 0.0f);
  EXPECT_LE(e.probability(), 1.0f);
}

TEST(BoxQuality, ScoresAndSummaries) {
  core::GroundBox gt;
  gt.center = Eigen::Vector2d(10.0, 0.0);
  gt.length_m = 4.0;
  gt.width_m = 2.0;
  gt.yaw_rad = 0.1;
  core::GroundBox det = gt;
  det.yaw_rad = 0.1 + kPi;  // turned half way round: the same box
  core::BoxQualitySample s = core::scoreBox(core::ObjectCategory::kVehicle, gt, &det);
  EXPECT_NEAR(s.heading_error_deg, 0.0, 1e-9);
  EXPECT_NEAR(s.iou, 1.0, 1e-9);
  EXPECT_NEAR(s.range_m, 10.0, 1e-12);
  det = gt;
  det.center += Eigen::Vector2d(std::cos(0.1), std::sin(0.1));  // 1 m along: IoU 6/10
  det.yaw_rad = 0.1 + 100.0 * kPi / 180.0;
  s = core::scoreBox(core::ObjectCategory::kVehicle, gt, &det);
  EXPECT_NEAR(s.center_error_m, 1.0, 1e-12);
  EXPECT_NEAR(s.heading_error_deg, 80.0, 1e-9);
  det.yaw_rad = gt.yaw_rad;
  s = core::scoreBox(core::ObjectCategory::kVehicle, gt, &det);
  EXPECT_NEAR(s.iou, 6.0 / 10.0, 1e-9);
  std::vector<core::BoxQualitySample> all = {
      s, core::scoreBox(core::ObjectCategory::kVehicle, gt, &gt),
      core::scoreBox(core::ObjectCategory::kVehicle, gt, nullptr),
      core::scoreBox(core::ObjectCategory::kPedestrian, gt, &gt)};
  const core::BoxQualitySummary v =
      core::summarize(all, core::ObjectCategory::kVehicle, 0.0, 40.0, 0.7);
  EXPECT_EQ(v.labelled, 3u);
  EXPECT_EQ(v.matched, 2u);
  EXPECT_NEAR(v.median_center_error_m, 0.5, 1e-12);
  EXPECT_NEAR(v.share_iou_at_least, 0.5, 1e-12);
  const core::BoxQualitySummary far =
      core::summarize(all, core::ObjectCategory::kVehicle, 40.0, 80.0, 0.5);
  EXPECT_EQ(far.labelled, 0u);
  EXPECT_TRUE(std::isnan(far.median_iou));
}
