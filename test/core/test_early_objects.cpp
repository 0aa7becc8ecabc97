// Early objects (Pipeline::addSector / finishRevolution, core/pipeline/early_objects.h): as
// sectors of a revolution complete, objects that are final are given at once; the rest when
// the seam closes. The objects given early plus those given at the seam must be exactly the
// objects of the classic mode (same points, class and box; ids aside), on synthetic scenes
// (an object across the seam, an object that grows into a later sector), on the simulated
// drive and on real SemanticKITTI scans (skipped when ../shared/data is absent); an object
// is never given before it is complete.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "segmentation_scene.h"
#include "simulated_drive.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace urban_detection {
namespace core {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The pipeline of the shipped configuration (classifier on when its model is there).
PipelineParams shippedParams() {
  PipelineParams p;
  const std::string model = std::string(UD_SOURCE_DIR) + "/config/object_classifier.yml.gz";
  if (std::filesystem::exists(model)) {
    std::string error;
    EXPECT_TRUE(loadPipelineConfigsYaml(
        {std::string(UD_SOURCE_DIR) + "/config/classification.yaml"}, &p, &error))
        << error;
  }
  return p;
}

// The points of `cloud` in the order a sensor spinning in `sense` (+1: counter-clockwise)
// from azimuth `seam` would give them, with times over a 0.1 s revolution.
CloudXYZIRT sweepOrder(const CloudXYZIRT& cloud, double seam, double sense) {
  std::vector<double> u(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    double a = sense * (std::atan2(cloud[i].y, cloud[i].x) - seam);
    a = std::fmod(a, 2.0 * kPi);
    if (a < 0.0) a += 2.0 * kPi;
    u[i] = std::isfinite(a) ? a : 0.0;
  }
  std::vector<std::size_t> order(cloud.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return u[a] < u[b]; });
  CloudXYZIRT out;
  out.header = cloud.header;
  for (const std::size_t i : order) {
    PointXYZIRT p = cloud[i];
    p.time = static_cast<float>(0.1 * u[i] / (2.0 * kPi));
    out.push_back(p);
  }
  return out;
}

// What identifies an object across the two modes (ids aside).
using ObjectKey =
    std::tuple<std::vector<std::uint32_t>, int, float, float, float, float, float, float, float>;
ObjectKey keyOf(const DetectedObject& o) {
  std::vector<std::uint32_t> idx(o.indices.begin(), o.indices.end());
  std::sort(idx.begin(), idx.end());
  return ObjectKey(idx, static_cast<int>(o.category), o.class_confidence, o.obb_center.x(),
                   o.obb_center.y(), o.obb_center.z(), o.obb_size.x(), o.obb_size.y(),
                   o.obb_yaw_rad);
}

struct EarlyRun {
  std::vector<std::vector<DetectedObject>> per_sector;  // objects given at each sector
  std::vector<DetectedObject> at_seam;                  // objects given at the seam
  std::size_t mismatches = 0;
  std::size_t pending = 0, pending_hough = 0;  // summed over the sectors
};

// Feeds `cloud` to `pipeline` in `sectors` equal parts, then closes the seam.
EarlyRun runEarly(Pipeline* pipeline, const CloudXYZIRT& cloud, int sectors,
                  std::uint32_t revolution) {
  EarlyRun run;
  const std::size_t n = cloud.size();
  for (int s = 0; s < sectors; ++s) {
    const std::size_t a = n * s / sectors, b = n * (s + 1) / sectors;
    const EarlySectorResult& r = pipeline->addSector(revolution, &cloud[a], b - a);
    EXPECT_EQ(r.objects.size(), r.last_point_time_s.size());
    for (std::size_t k = 0; k < r.objects.size(); ++k) {
      // Its last point is among the points given so far.
      EXPECT_LE(r.last_point_time_s[k], cloud[b - 1].time);
    }
    run.per_sector.push_back(r.objects);
    run.pending += r.pending;
    run.pending_hough += r.pending_hough;
    if (std::getenv("UD_EARLY_DEBUG")) {
      std::cout << "sector " << s << ": given " << r.objects.size() << " pending " << r.pending
                << " (hough " << r.pending_hough << ") swept " << r.swept_deg << " deg\n";
    }
  }
  CloudXYZIRT whole = cloud;
  whole.header.seq = revolution;
  const PipelineResult& r = pipeline->finishRevolution(whole);
  EXPECT_EQ(r.given_early.size(), r.objects.size());
  for (std::size_t k = 0; k < r.objects.size(); ++k) {
    if (!r.given_early[k]) run.at_seam.push_back(r.objects[k]);
  }
  run.mismatches = r.early_mismatches;
  return run;
}

// Early + seam objects == the classic objects of a separate pipeline; returns the number of
// objects given early.
std::size_t expectSameAsClassic(const PipelineParams& p, const CloudXYZIRT& cloud,
                                const EarlyRun& run, const std::string& what) {
  Pipeline classic(p);
  const PipelineResult& c = classic.process(cloud);
  std::vector<ObjectKey> expected, got;
  for (const DetectedObject& o : c.objects) expected.push_back(keyOf(o));
  std::size_t early = 0;
  for (const auto& sector : run.per_sector) {
    for (const DetectedObject& o : sector) got.push_back(keyOf(o)), ++early;
  }
  for (const DetectedObject& o : run.at_seam) got.push_back(keyOf(o));
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(run.mismatches, 0u) << what;
  EXPECT_EQ(got.size(), expected.size()) << what;
  EXPECT_TRUE(got == expected) << what << ": early + seam objects differ from the classic ones";
  return early;
}

// Index of the object of `objects` holding point `i`, or -1.
int objectWith(const std::vector<DetectedObject>& objects, std::uint32_t i) {
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const auto& idx = objects[k].indices;
    if (std::find(idx.begin(), idx.end(), i) != idx.end()) return static_cast<int>(k);
  }
  return -1;
}

// Far enough that the Hough window (20 m) does not hold them.
std::vector<test::Box> seamScene() {
  return {
      {28.0f, -1.0f, 0.0f, 32.0f, 1.0f, 1.5f, 1},    // a car across the seam (azimuth 0)
      {-32.0f, -1.0f, 0.0f, -28.0f, 1.0f, 1.5f, 2},  // a car opposite (azimuth 180 deg)
      {1.0f, 28.0f, 0.0f, 3.0f, 32.0f, 1.5f, 3},     // a car at azimuth ~90 deg
      {12.0f, 24.0f, 0.0f, 18.0f, 25.2f, 1.4f, 4},   // a van-long object at 60-65 deg
  };
}

TEST(EarlyObjects, ObjectAcrossTheSeamWaitsForTheSeam) {
  std::vector<int> tags;
  const CloudXYZIRT raw = test::rayCast(1.73f, seamScene(), &tags, 64, 1800, 2.0f, -24.8f, 50.0f);
  const CloudXYZIRT cloud = sweepOrder(raw, 0.0, 1.0);
  const PipelineParams p;  // no classifier: boxes are no street objects it knows
  Pipeline pipeline(p);
  const EarlyRun run = runEarly(&pipeline, cloud, 16, 7);
  const std::size_t early = expectSameAsClassic(p, cloud, run, "seam scene");
  EXPECT_GT(early, 0u) << "no object given before the seam";

  // The car across the seam: the classic object with points on both sides of azimuth 0.
  Pipeline classic(p);
  const PipelineResult& c = classic.process(cloud);
  std::uint32_t seam_point = 0;
  bool found = false;
  for (const DetectedObject& o : c.objects) {
    bool left = false, right = false;
    for (const std::uint32_t i : o.indices) {
      left = left || (cloud[i].x > 25.0f && cloud[i].y > 0.2f);
      right = right || (cloud[i].x > 25.0f && cloud[i].y < -0.2f);
    }
    if (left && right) seam_point = o.indices.front(), found = true;
  }
  ASSERT_TRUE(found) << "no object across the seam";
  for (std::size_t s = 0; s < run.per_sector.size(); ++s) {
    EXPECT_EQ(objectWith(run.per_sector[s], seam_point), -1)
        << "the car across the seam was given at sector " << s;
  }
  EXPECT_GE(objectWith(run.at_seam, seam_point), 0) << "the car across the seam is not given";

  // The car opposite the seam is given before the revolution ends, in the sector after the
  // one that completed it (not earlier than its last point).
  bool opposite_early = false;
  for (std::size_t s = 0; s + 1 < run.per_sector.size(); ++s) {
    for (const DetectedObject& o : run.per_sector[s]) {
      opposite_early = opposite_early || o.centroid.x() < -25.0f;
    }
  }
  EXPECT_TRUE(opposite_early) << "the car opposite the seam waited for the seam";
}

TEST(EarlyObjects, ObjectGrowingIntoALaterSectorIsGivenWhole) {
  // Sectors of 1/16 revolution (22.5 deg): the long object at azimuth 55-70 deg and the car
  // at 82-87 deg are cut by sector borders (45, 67.5, 90 deg); the sweep turns clockwise.
  std::vector<test::Box> boxes = seamScene();
  boxes.push_back({13.0f, 22.5f, 0.0f, 14.2f, 28.0f, 1.6f, 5});  // along the line of sight
  std::vector<int> tags;
  const CloudXYZIRT raw = test::rayCast(1.73f, boxes, &tags, 64, 1800, 2.0f, -24.8f, 50.0f);
  for (const double sense : {1.0, -1.0}) {
    const CloudXYZIRT cloud = sweepOrder(raw, kPi / 2.0 + 0.3, sense);
    const PipelineParams p;
    Pipeline pipeline(p);
    const EarlyRun run = runEarly(&pipeline, cloud, 16, 3);
    expectSameAsClassic(p, cloud, run, sense > 0 ? "counter-clockwise" : "clockwise");
    // Every object given at sector s is complete: its points are all of one classic object and
    // none of that object's points comes later than sector s.
    Pipeline classic(p);
    const PipelineResult& c = classic.process(cloud);
    const std::size_t n = cloud.size();
    std::size_t given = 0;
    for (std::size_t s = 0; s < run.per_sector.size(); ++s) {
      const std::size_t end = n * (s + 1) / run.per_sector.size();
      for (const DetectedObject& o : run.per_sector[s]) {
        ++given;
        const int k = objectWith(c.objects, o.indices.front());
        ASSERT_GE(k, 0);
        EXPECT_EQ(c.objects[k].indices.size(), o.indices.size()) << "given before complete";
        for (const std::uint32_t i : c.objects[k].indices) EXPECT_LT(i, end);
      }
    }
    EXPECT_GT(given, 0u);
    // The objects that span a sector border exist and were not given at the first of them.
    std::size_t spanning = 0;
    for (const DetectedObject& o : c.objects) {
      const auto [lo, hi] = std::minmax_element(o.indices.begin(), o.indices.end());
      if (*lo * 16 / n != *hi * 16 / n) ++spanning;
    }
    EXPECT_GT(spanning, 0u) << "the scene has no object across a sector border";
  }
}

// The sector at which the object holding point `i` was given, or -1 (at the seam).
int sectorGiven(const EarlyRun& run, std::uint32_t i) {
  for (std::size_t s = 0; s < run.per_sector.size(); ++s) {
    if (objectWith(run.per_sector[s], i) >= 0) return static_cast<int>(s);
  }
  return -1;
}

// A point of `cloud` inside the box.
std::uint32_t pointIn(const CloudXYZIRT& cloud, const test::Box& b) {
  for (std::uint32_t i = 0; i < cloud.size(); ++i) {
    const PointXYZIRT& q = cloud[i];
    const float z = q.z + 1.73f;  // the scenes' sensor height
    if (q.x >= b.x0 && q.x <= b.x1 && q.y >= b.y0 && q.y <= b.y1 && z >= b.z0 + 0.3f && z <= b.z1) {
      return i;
    }
  }
  ADD_FAILURE() << "no point in the box";
  return 0;
}

TEST(EarlyObjects, ObjectBesideAGroupLongerThanAVehicleIsGivenEarly) {
  // A hedge 2.4 m high (its cells are tall but low enough to be a vehicle's) runs 60 m across
  // the seam, outside the Hough window; a pedestrian stands 1.8 m in front of it early in the
  // sweep. The hedge's vehicle group reaches the seam, so it is open until the revolution
  // ends, but its swept part is already longer than any vehicle: the group is never made
  // short, whatever comes, and the pedestrian is final once that part is swept.
  const test::Box pedestrian{22.6f, 11.7f, 0.0f, 23.2f, 12.3f, 1.8f, 2};
  const std::vector<test::Box> boxes = {{25.0f, -30.0f, 0.0f, 25.6f, 30.0f, 2.4f, 1}, pedestrian};
  std::vector<int> tags;
  const CloudXYZIRT raw = test::rayCast(1.73f, boxes, &tags, 64, 1800, 2.0f, -24.8f, 50.0f);
  const CloudXYZIRT cloud = sweepOrder(raw, 0.0, 1.0);
  const PipelineParams p;
  Pipeline pipeline(p);
  const EarlyRun run = runEarly(&pipeline, cloud, 16, 11);
  expectSameAsClassic(p, cloud, run, "hedge scene");
  const int s = sectorGiven(run, pointIn(cloud, pedestrian));
  EXPECT_GE(s, 0) << "the pedestrian beside the hedge waited for the seam";
  EXPECT_LE(s, 4) << "the pedestrian was given late";
  // The hedge itself crosses the seam: at the seam only.
  EXPECT_EQ(sectorGiven(run, pointIn(cloud, boxes[0])), -1);
}

TEST(EarlyObjects, ObjectBesideARowOfParkedCarsInTheHoughWindowIsGivenEarly) {
  // Inside the Hough window a pedestrian stands 2 m beside a row of parked cars (short cells
  // below the sensor: no wall support). Their component is longer than a Hough run, but no
  // run over it can reach min_tall_fraction of wall support, so the pedestrian is final once
  // the row is swept, long before the seam.
  const test::Box pedestrian{7.4f, -10.3f, 0.0f, 8.0f, -9.7f, 1.8f, 9};
  std::vector<test::Box> boxes = {pedestrian};
  for (int k = 0; k < 7; ++k) {
    const float y0 = -18.0f + 5.5f * static_cast<float>(k);
    boxes.push_back({10.0f, y0, 0.0f, 11.8f, y0 + 4.5f, 1.5f, 10 + k});
  }
  std::vector<int> tags;
  const CloudXYZIRT raw = test::rayCast(1.73f, boxes, &tags, 64, 1800, 2.0f, -24.8f, 50.0f);
  const CloudXYZIRT cloud = sweepOrder(raw, -kPi / 2.0, 1.0);
  const PipelineParams p;
  Pipeline pipeline(p);
  const EarlyRun run = runEarly(&pipeline, cloud, 16, 12);
  expectSameAsClassic(p, cloud, run, "parked cars scene");
  const int s = sectorGiven(run, pointIn(cloud, pedestrian));
  EXPECT_GE(s, 0) << "the pedestrian beside the parked cars waited for the seam";
  EXPECT_LE(s, 12) << "the pedestrian was given late";
}

TEST(EarlyObjects, ObjectBesideAFacadeInTheHoughWindowWaitsForTheSeam) {
  // The same pedestrian beside a facade (tall cells along 30 m): a Hough run may relabel its
  // cells, and which lines are found depends on the whole revolution.
  const test::Box pedestrian{7.4f, -10.3f, 0.0f, 8.0f, -9.7f, 1.8f, 9};
  const std::vector<test::Box> boxes = {pedestrian, {10.0f, -18.0f, 0.0f, 10.6f, 18.0f, 8.0f, 1}};
  std::vector<int> tags;
  const CloudXYZIRT raw = test::rayCast(1.73f, boxes, &tags, 64, 1800, 2.0f, -24.8f, 50.0f);
  const CloudXYZIRT cloud = sweepOrder(raw, -kPi / 2.0, 1.0);
  const PipelineParams p;
  Pipeline pipeline(p);
  const EarlyRun run = runEarly(&pipeline, cloud, 16, 13);
  expectSameAsClassic(p, cloud, run, "facade scene");
  EXPECT_EQ(sectorGiven(run, pointIn(cloud, pedestrian)), -1)
      << "the pedestrian beside a facade was given before the seam";
}

TEST(EarlyObjects, SimulatedDriveGivesTheClassicObjects) {
  const PipelineParams p = shippedParams();
  Pipeline pipeline(p);
  std::size_t early = 0, total = 0;
  std::uint32_t seq = 100;
  for (const CloudXYZIRT& cloud : ud_test::simulatedRevolutions(12)) {
    const EarlyRun run = runEarly(&pipeline, cloud, 10, seq);
    early += expectSameAsClassic(p, cloud, run, "revolution " + std::to_string(seq));
    for (const auto& s : run.per_sector) total += s.size();
    total += run.at_seam.size();
    ++seq;
  }
  ASSERT_GT(total, 0u);
  EXPECT_GT(early, 0u);
  std::cout << "[ early    ] simulated drive: " << early << " of " << total
            << " objects given before the seam\n";
}

TEST(EarlyObjects, ARevolutionJoinedLateGivesEverythingAtTheSeam) {
  std::vector<int> tags;
  const CloudXYZIRT raw = test::rayCast(1.73f, seamScene(), &tags, 64, 1800, 2.0f, -24.8f, 50.0f);
  const CloudXYZIRT cloud = sweepOrder(raw, 0.0, 1.0);
  const PipelineParams p;
  Pipeline pipeline(p);
  // The first 4 of 16 sectors never arrive.
  const std::size_t n = cloud.size();
  for (int s = 4; s < 16; ++s) {
    const std::size_t a = n * s / 16, b = n * (s + 1) / 16;
    EXPECT_TRUE(pipeline.addSector(5, &cloud[a], b - a).objects.empty()) << "sector " << s;
  }
  CloudXYZIRT whole = cloud;
  whole.header.seq = 5;
  const PipelineResult& r = pipeline.finishRevolution(whole);
  EXPECT_GT(r.objects.size(), 0u);
  EXPECT_EQ(r.early_mismatches, 0u);
  for (const std::uint8_t g : r.given_early) EXPECT_EQ(g, 0u);
  // The next revolution, whole, gives early again.
  EarlyRun run = runEarly(&pipeline, cloud, 16, 6);
  EXPECT_GT(expectSameAsClassic(p, cloud, run, "after a late join"), 0u);
}

TEST(EarlyObjects, RealScansGiveTheClassicObjects) {
  const std::string root = UD_SHARED_DATA;
  const auto files = listFiles(root + "/semantic_kitti/sequences/00/velodyne", ".bin");
  if (files.empty()) GTEST_SKIP() << "no SemanticKITTI scans in " << root;
  const PipelineParams p = shippedParams();
  Pipeline pipeline(p);
  std::size_t early = 0, total = 0;
  std::uint32_t seq = 0;
  for (std::size_t f = 0; f < files.size() && f < 400; f += 100) {
    CloudXYZIRT raw;
    ASSERT_TRUE(readKittiBin(files[f], &raw)) << files[f];
    // KITTI's HDL-64E starts its revolution behind the car.
    const CloudXYZIRT cloud = sweepOrder(raw, kPi, 1.0);
    const EarlyRun run = runEarly(&pipeline, cloud, 10, seq++);
    early += expectSameAsClassic(p, cloud, run, files[f]);
    for (const auto& s : run.per_sector) total += s.size();
    total += run.at_seam.size();
  }
  ASSERT_GT(total, 0u);
  EXPECT_GT(early, 0u);
  std::cout << "[ early    ] SemanticKITTI 00: " << early << " of " << total
            << " objects given before the seam\n";
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
