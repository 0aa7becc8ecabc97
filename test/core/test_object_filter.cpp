// ObjectFilter (vegetation rejection after either detector) on synthetic scans: rays of a
// 64-beam-like sensor (rows of constant elevation, fixed azimuth step) cast against a car-like
// box, a pedestrian-like cylinder, a pole and a porous bush (returns at random depths inside a
// sphere), plus degenerate inputs.
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "synthetic_scans.h"
#include "test_files.h"
#include "urban_detection/core/classification/object_filter.h"
#include "urban_detection/core/params/params_yaml.h"

namespace core = urban_detection::core;
using urban_detection::LabeledCloud;
using urban_detection::LabeledPoint;

using namespace urban_detection::test;  // NOLINT: scan helpers

namespace {

struct Scene {
  LabeledCloud fg;
  std::vector<core::DetectedObject> objects;
};

// The stage is off by default (config/classification.yaml explains why); these tests switch it on.
core::ObjectFilterParams on() {
  core::ObjectFilterParams p;
  p.enabled = true;
  return p;
}

}  // namespace

TEST(ObjectFilter, RejectsPorousBushKeepsCarPedestrianPole) {
  std::mt19937 rng(42);
  Scene s;
  // Car: 4.2 x 1.8 x 1.2 m box, front face 8 m ahead and 2 m to the left (L-shaped view).
  s.objects.push_back(scan(box({8.0, 1.2, -1.6}, {12.2, 3.0, -0.3}), 0, 25, -14, 0, &s.fg));
  // Pedestrian: 0.25 m radius cylinder 7 m away, 1.75 m tall.
  s.objects.push_back(scan(cylinder(7.0, -2.0, 0.25, -1.73, 0.0), -25, -10, -15, 0, &s.fg));
  // Pole: 0.08 m radius cylinder 6 m away.
  s.objects.push_back(scan(cylinder(6.0, 3.0, 0.08, -1.73, 0.3), 20, 32, -16, 3, &s.fg));
  // Bush: porous sphere, radius 1 m, 9 m away.
  s.objects.push_back(scan(bush({9.0, -6.0, -1.0}, 1.0, &rng), -45, -22, -14, 2, &s.fg));
  for (std::size_t k = 0; k < s.objects.size(); ++k) {
    s.objects[k].id = static_cast<std::uint32_t>(k + 1);
    ASSERT_GE(s.objects[k].indices.size(), 60u) << "object " << k;
  }

  core::ObjectFilter filter(on());
  filter.indexForeground(s.fg);
  const core::ObjectFeatures car = filter.features(s.fg, s.objects[0]);
  const core::ObjectFeatures ped = filter.features(s.fg, s.objects[1]);
  const core::ObjectFeatures bush_f = filter.features(s.fg, s.objects[3]);
  EXPECT_EQ(car.points, s.objects[0].indices.size());
  EXPECT_GT(car.triplets, 100u);
  EXPECT_LT(car.jump_fraction, 0.05);
  EXPECT_LT(ped.jump_fraction, 0.05);
  EXPECT_GT(bush_f.jump_fraction, 0.4);
  EXPECT_NEAR(car.height_m, 1.3, 0.15);

  const std::vector<std::uint32_t> car_idx = s.objects[0].indices;
  const std::vector<std::uint32_t> bush_idx = s.objects[3].indices;
  std::vector<core::DetectedObject> rejected;
  const core::ObjectFilterStats st = filter.apply(s.fg, &s.objects, &rejected);
  EXPECT_EQ(st.input, 4u);
  EXPECT_EQ(st.vegetation, 1u);
  EXPECT_EQ(st.kept, 3u);
  ASSERT_EQ(s.objects.size(), 3u);
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_EQ(rejected[0].indices, bush_idx);
  EXPECT_EQ(rejected[0].id, 4u);
  EXPECT_EQ(s.objects[0].indices, car_idx);  // order kept
  for (std::size_t k = 0; k < s.objects.size(); ++k) EXPECT_EQ(s.objects[k].id, k + 1);
}

TEST(ObjectFilter, RenumbersIdsAndKeepsOrderWhenTheFirstObjectIsRejected) {
  std::mt19937 rng(7);
  Scene s;
  s.objects.push_back(scan(bush({9.0, 0.0, -1.0}, 1.0, &rng), -10, 10, -14, 2, &s.fg));
  s.objects.push_back(scan(box({8.0, 4.0, -1.6}, {12.2, 5.8, -0.3}), 15, 40, -14, 0, &s.fg));
  s.objects[0].id = 1;
  s.objects[1].id = 2;
  core::ObjectFilter filter(on());
  filter.apply(s.fg, &s.objects);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].id, 1u);
  EXPECT_GT(s.objects[0].centroid.y(), 3.0f);  // the car
}

TEST(ObjectFilter, CarBehindTheSensorAcrossTheAzimuthWrapIsKept) {
  Scene s;
  // Box straddling azimuth +-180 deg.
  s.objects.push_back(scan(box({-12.2, -1.0, -1.6}, {-8.0, 1.0, -0.3}), 170, 190, -14, 0, &s.fg));
  core::ObjectFilter filter(on());
  filter.indexForeground(s.fg);
  const core::ObjectFeatures f = filter.features(s.fg, s.objects[0]);
  EXPECT_GT(f.triplets, 100u);
  EXPECT_LT(f.jump_fraction, 0.05);
  filter.apply(s.fg, &s.objects);
  EXPECT_EQ(s.objects.size(), 1u);
}

TEST(ObjectFilter, SmallAndUnmeasurableObjectsAreKept) {
  std::mt19937 rng(3);
  Scene s;
  // A porous but tiny object (few points): not judged.
  s.objects.push_back(scan(bush({12.0, 0.0, -1.0}, 0.1, &rng), -2, 2, -8, -2, &s.fg));
  ASSERT_LT(s.objects[0].indices.size(), 30u);
  ASSERT_GT(s.objects[0].indices.size(), 3u);
  core::ObjectFilter filter(on());
  const core::ObjectFilterStats st = filter.apply(s.fg, &s.objects);
  EXPECT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(st.not_judged, 1u);
  EXPECT_EQ(st.vegetation, 0u);
}

TEST(ObjectFilter, DegenerateInputs) {
  core::ObjectFilter filter(on());
  LabeledCloud fg;
  std::vector<core::DetectedObject> objects;
  EXPECT_EQ(filter.apply(fg, &objects).kept, 0u);  // nothing at all

  // One point; an object whose indices are not in the foreground; NaN points only.
  LabeledPoint p;
  p.x = 5.0f;
  p.y = 1.0f;
  p.z = -1.0f;
  p.intensity = 10.0f;
  p.index = 0;
  fg.push_back(p);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::uint32_t k = 1; k <= 50; ++k) {
    LabeledPoint q = p;
    q.x = nan;
    q.index = k;
    fg.push_back(q);
  }
  core::DetectedObject one, missing, nans, empty;
  one.indices = {0};
  missing.indices = {1000, 1001, 4000000000u};
  for (std::uint32_t k = 1; k <= 50; ++k) nans.indices.push_back(k);
  objects = {one, missing, nans, empty};
  filter.indexForeground(fg);
  EXPECT_EQ(filter.features(fg, one).points, 1u);
  EXPECT_EQ(filter.features(fg, missing).points, 0u);
  EXPECT_EQ(filter.features(fg, nans).points, 0u);
  EXPECT_EQ(filter.features(fg, nans).jump_fraction, 0.0);
  const core::ObjectFilterStats st = filter.apply(fg, &objects);
  EXPECT_EQ(objects.size(), 4u);
  EXPECT_EQ(st.not_judged, 4u);

  // A second foreground reusing the filter: stale index entries of the first one are gone.
  LabeledCloud fg2;
  fg2.push_back(p);
  fg2[0].index = 3;
  filter.indexForeground(fg2);
  EXPECT_EQ(filter.features(fg2, one).points, 0u);  // index 0 no longer present
}

TEST(ObjectFilter, DisabledKeepsEverythingAndBadParamsThrow) {
  std::mt19937 rng(11);
  Scene s;
  s.objects.push_back(scan(bush({9.0, 0.0, -1.0}, 1.0, &rng), -10, 10, -14, 2, &s.fg));
  core::ObjectFilterParams p;
  p.enabled = false;
  core::ObjectFilter off(p);
  off.apply(s.fg, &s.objects);
  EXPECT_EQ(s.objects.size(), 1u);
  core::ObjectFilter enabled(on());
  enabled.apply(s.fg, &s.objects);
  EXPECT_EQ(s.objects.size(), 0u);

  core::ObjectFilterParams bad;
  bad.max_jump_fraction = 1.5;
  EXPECT_NE(core::validate(bad).find("max_jump_fraction"), std::string::npos);
  EXPECT_THROW(core::ObjectFilter{bad}, std::invalid_argument);
  bad = core::ObjectFilterParams();
  bad.jump_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(core::ObjectFilter{bad}, std::invalid_argument);
  EXPECT_TRUE(core::validate(core::ObjectFilterParams()).empty());
}

TEST(ObjectFilter, FarObjectsAreNotJudged) {
  std::mt19937 rng(21);
  Scene s;
  // The same porous bush, 12 m and 40 m away.
  s.objects.push_back(scan(bush({12.0, 0.0, -1.0}, 1.2, &rng), -10, 10, -10, 2, &s.fg));
  s.objects.push_back(scan(bush({0.0, 40.0, -1.0}, 1.2, &rng), 80, 100, -4, 1, &s.fg, 0.05));
  core::ObjectFilter filter(on());
  filter.indexForeground(s.fg);
  ASSERT_GT(filter.features(s.fg, s.objects[1]).jump_fraction, 0.3);
  ASSERT_GT(filter.features(s.fg, s.objects[1]).triplets, 20u);
  const core::ObjectFilterStats st = filter.apply(s.fg, &s.objects);
  EXPECT_EQ(st.porous, 1u);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_GT(s.objects[0].centroid.y(), 30.0f) << "the far bush (beyond max_range_m) is kept";
}

TEST(ObjectFilter, BrightHedgeRuleIsOffByDefaultAndSparesPeople) {
  Scene s;
  // A trimmed hedge: smooth, 4 m long, 0.6 m thick, bright; a bright pedestrian; a dark car.
  s.objects.push_back(
      scan(box({8.0, -6.0, -1.73}, {8.6, -2.0, -0.5}), -40, -10, -14, 0, &s.fg, 0.09, 0.4, 97.0f));
  s.objects.push_back(
      scan(cylinder(7.0, 2.0, 0.25, -1.73, 0.0), 10, 22, -15, 0, &s.fg, 0.09, 0.4, 94.0f));
  s.objects.push_back(
      scan(box({8.0, 5.0, -1.6}, {12.2, 6.8, -0.3}), 25, 45, -14, 0, &s.fg, 0.09, 0.4, 40.0f));
  const std::vector<core::DetectedObject> all = s.objects;
  core::ObjectFilter off(on());
  off.apply(s.fg, &s.objects);
  EXPECT_EQ(s.objects.size(), 3u) << "hedge_min_intensity 0: rule off";

  core::ObjectFilterParams p = on();
  p.hedge_min_intensity = 85.0;
  core::ObjectFilter bright(p);
  s.objects = all;
  std::vector<core::DetectedObject> rejected;
  const core::ObjectFilterStats st = bright.apply(s.fg, &s.objects, &rejected);
  EXPECT_EQ(st.bright_hedge, 1u);
  EXPECT_EQ(st.porous, 0u);
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_EQ(rejected[0].indices, all[0].indices) << "the hedge";
  EXPECT_EQ(s.objects.size(), 2u) << "the bright pedestrian is shorter than hedge_min_length_m";
}

TEST(ObjectFilter, DetectionYamlMirrorsTheParamsAndTyposAreErrors) {
  core::ObjectFilterParams p;
  p.enabled = true;  // the shipped value is false: loading must overwrite this
  p.jump_m = 9.0;
  std::string error;
  ASSERT_TRUE(core::loadObjectFilterParamsYaml(
      std::string(UD_SOURCE_DIR) + "/config/classification.yaml", &p, &error))
      << error;
  const core::ObjectFilterParams d;
  EXPECT_EQ(p.enabled, d.enabled);
  EXPECT_EQ(p.min_points, d.min_points);
  EXPECT_DOUBLE_EQ(p.row_gap_deg, d.row_gap_deg);
  EXPECT_DOUBLE_EQ(p.max_azimuth_gap_deg, d.max_azimuth_gap_deg);
  EXPECT_DOUBLE_EQ(p.jump_m, d.jump_m);
  EXPECT_EQ(p.min_triplets, d.min_triplets);
  EXPECT_DOUBLE_EQ(p.max_jump_fraction, d.max_jump_fraction);
  EXPECT_DOUBLE_EQ(p.max_range_m, d.max_range_m);
  EXPECT_DOUBLE_EQ(p.hedge_min_intensity, d.hedge_min_intensity);
  EXPECT_DOUBLE_EQ(p.hedge_min_length_m, d.hedge_min_length_m);
  EXPECT_DOUBLE_EQ(p.uniform_max_intensity_std, d.uniform_max_intensity_std);
  EXPECT_EQ(p.uniform_min_points, d.uniform_min_points);

  const ud_test::TempFile typo(".yaml", "detection:\n  object_filter:\n    jump_mm: 0.3\n");
  EXPECT_FALSE(core::loadObjectFilterParamsYaml(typo.path(), &p, &error));
  EXPECT_NE(error.find("object_filter/jump_mm: unknown parameter"), std::string::npos) << error;
}

TEST(ObjectFilter, UniformMaterialRuleIsOffByDefaultAndKeepsMixedObjects) {
  Scene s;
  // A hedge 9 m away (one material: intensity 90 +- 10), a car (dark paint 20 with bright lamps
  // and plate 120) and, 40 m away beyond the porosity rule's max_range_m, a second hedge.
  s.objects.push_back(
      scan(box({8.0, -6.0, -1.73}, {8.6, -2.0, -0.5}), -40, -10, -14, 0, &s.fg, 0.09, 0.4, 90.0f));
  s.objects.push_back(
      scan(box({8.0, 5.0, -1.6}, {12.2, 6.8, -0.3}), 25, 45, -14, 0, &s.fg, 0.09, 0.4, 20.0f));
  s.objects.push_back(
      scan(box({40.0, -1.0, -1.73}, {40.6, 1.0, -0.5}), -2, 2, -8, 0, &s.fg, 0.09, 0.4, 90.0f));
  for (std::size_t k = 0; k < s.fg.size(); ++k) {
    s.fg.points[k].intensity += (k % 2 ? 10.0f : -10.0f);
  }
  for (std::size_t k = 0; k < s.objects[1].indices.size(); k += 3) {
    for (LabeledPoint& p : s.fg.points) {
      if (p.index == s.objects[1].indices[k]) p.intensity = 120.0f;
    }
  }
  ASSERT_GE(s.objects[2].indices.size(), 10u);
  const std::vector<core::DetectedObject> all = s.objects;
  core::ObjectFilter off(on());
  off.indexForeground(s.fg);
  EXPECT_NEAR(off.features(s.fg, all[0]).std_intensity, 10.0, 0.5);
  EXPECT_GT(off.features(s.fg, all[1]).std_intensity, 40.0);
  off.apply(s.fg, &s.objects);
  EXPECT_EQ(s.objects.size(), 3u) << "uniform_max_intensity_std 0: rule off";

  core::ObjectFilterParams p = on();
  p.uniform_max_intensity_std = 30.0;
  core::ObjectFilter uniform(p);
  s.objects = all;
  std::vector<core::DetectedObject> rejected;
  const core::ObjectFilterStats st = uniform.apply(s.fg, &s.objects, &rejected);
  EXPECT_EQ(st.uniform, 2u);
  EXPECT_EQ(st.porous + st.bright_hedge, 0u);
  ASSERT_EQ(rejected.size(), 2u);
  EXPECT_EQ(rejected[0].indices, all[0].indices) << "the near hedge";
  EXPECT_EQ(rejected[1].indices, all[2].indices) << "the far hedge: any range";
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].indices, all[1].indices) << "the car";

  // Too few points to judge a spread: kept.
  p.uniform_min_points = static_cast<int>(all[2].indices.size()) + 1;
  core::ObjectFilter few(p);
  s.objects = {all[2]};
  EXPECT_EQ(few.apply(s.fg, &s.objects).uniform, 0u);
  EXPECT_EQ(s.objects.size(), 1u);

  p.uniform_max_intensity_std = -1.0;
  EXPECT_NE(core::validate(p).find("uniform_max_intensity_std"), std::string::npos);
}
