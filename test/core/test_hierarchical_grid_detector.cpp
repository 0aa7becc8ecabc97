// Hierarchical grid detector (paper Sec. 3.2): the three separation cases of Fig. 4 as ASCII
// art, LiDAR-like cars near and far, the distance weight, agreement with the kd-tree baseline,
// and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

#include "detection_test_utils.h"
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"

namespace urban_detection {
namespace {

using core::DetectedObject;
using core::HierarchicalGridDetector;
using core::HierarchicalGridDetectorParams;
using test::fromAsciiArt;
using test::Partition;
using test::partitionOf;
using test::truthPartition;

// The ASCII tests run close to the sensor with the weight switched off, so "dense" means
// exactly >= dense_min_weighted_points (6) raw points and the art alone decides the result.
HierarchicalGridDetectorParams asciiParams(bool refine = true) {
  HierarchicalGridDetectorParams p;
  p.weight.enabled = false;
  p.dense_refinement = refine;
  p.min_points = 1;
  p.min_weighted_points = 0.0;
  return p;
}

std::vector<DetectedObject> run(const LabeledCloud& cloud, const HierarchicalGridDetectorParams& p,
                                core::HierarchicalGridStats* stats = nullptr) {
  HierarchicalGridDetector det(p);
  std::vector<DetectedObject> objects;
  det.detect(cloud, &objects);
  if (stats) *stats = det.stats();
  return objects;
}

// The Fig. 4 scenes lie across the line of sight: columns run along x, rows along y, and the
// art starts at (-1.8, 4.8), so the sensor looks along +y (rows) through it and a gap between
// columns is a gap across the line of sight. Both corners are on super-cell borders.
constexpr float kAcrossX0 = -1.8f, kAcrossY0 = 4.8f;

LabeledCloud acrossArt(const std::vector<std::string>& art, const std::map<char, float>& heights) {
  return fromAsciiArt(art, heights, kAcrossX0, kAcrossY0);
}

// Fig. 4a: two cars whose super-cells touch and have similar Zmax (psi = 0.1 m): one coarse
// blob. Columns 8 and 9, the facing border lines of super-cells 2 and 3, are empty, so the
// dense level splits the blob.
//                        super-cells: |0 ||1 ||2 ||3 ||4 ||5 |
const std::vector<std::string> kTwoCars = {"AAAAAAAA..BBBBBBBB", "AAAAAAAA..BBBBBBBB",
                                           "AAAAAAAA..BBBBBBBB", "AAAAAAAA..BBBBBBBB",
                                           "AAAAAAAA..BBBBBBBB", "AAAAAAAA..BBBBBBBB"};

TEST(HierarchicalGridFig4, TwoCarsTouchingAtCoarseLevelAreSplitOnTheSuperCellBorder) {
  const LabeledCloud cloud = acrossArt(kTwoCars, {{'A', 1.5f}, {'B', 1.4f}});
  core::HierarchicalGridStats coarse_stats, stats;
  const auto coarse = run(cloud, asciiParams(false), &coarse_stats);
  EXPECT_EQ(coarse_stats.coarse_blobs, 1u);
  EXPECT_EQ(coarse.size(), 1u) << "the coarse level alone merges the two cars";
  const auto objects = run(cloud, asciiParams(true), &stats);
  EXPECT_EQ(partitionOf(objects), truthPartition(cloud));
  EXPECT_EQ(objects.size(), 2u);
}

TEST(HierarchicalGridFig4, OneEmptySubCellAcrossTheLineOfSightSeparatesADenseOneJoins) {
  // B reaches column 9: a single near-empty column across the line of sight still separates.
  std::vector<std::string> art = kTwoCars;
  for (std::string& row : art) row[9] = 'B';
  EXPECT_EQ(partitionOf(run(acrossArt(art, {{'A', 1.5f}, {'B', 1.4f}}), asciiParams(true))),
            truthPartition(acrossArt(art, {{'A', 1.5f}, {'B', 1.4f}})));
  // One dense sub-cell in that column (row 3) touches both: the line is broken, one object.
  art[3][8] = 'A';
  EXPECT_EQ(run(acrossArt(art, {{'A', 1.5f}, {'B', 1.4f}}), asciiParams(true)).size(), 1u);
  // Two near-empty points in the strip do not connect them, and join the nearer car.
  art = kTwoCars;
  art[2][8] = 'a';
  art[2][9] = 'b';
  const LabeledCloud cloud = acrossArt(art, {{'A', 1.5f}, {'B', 1.4f}});
  EXPECT_EQ(partitionOf(run(cloud, asciiParams(true))), truthPartition(cloud));
}

TEST(HierarchicalGridFig4, PedestrianBesideACarIsSplitOnTheSuperCellBorder) {
  // Fig. 4b: car C (1.5 m) in super-cells 0-2, pedestrian P (1.8 m, psi = 0.3 m: linked) in
  // super-cell 3. Columns 8 and 9 are near-empty: one stray return of the car (lower-case
  // 'c'), which joins the car's object.
  const std::vector<std::string> art = {"CCCCCCCCc.....", "CCCCCCCC......", "CCCCCCCC..PP..",
                                        "CCCCCCCC..PP..", "CCCCCCCC......", "CCCCCCCC......"};
  const LabeledCloud cloud = acrossArt(art, {{'C', 1.5f}, {'P', 1.8f}});
  core::HierarchicalGridStats stats;
  EXPECT_EQ(run(cloud, asciiParams(false), &stats).size(), 1u);
  const auto objects = run(cloud, asciiParams(true));
  EXPECT_EQ(partitionOf(objects), truthPartition(cloud));
  EXPECT_EQ(objects.size(), 2u);
}

TEST(HierarchicalGridFig4, SuperCellStraddlingTwoObjectsIsSplitWhereverTheLineRuns) {
  // Fig. 4c: one near-empty column of sub-cells between A and B runs through a super-cell
  // (its centre column, or either border column); the super-cell's sub-cells go to the
  // object on their side.
  for (int gap = 1; gap <= 7; ++gap) {
    std::string row(9, 'B');
    for (int c = 0; c < gap; ++c) row[c] = 'A';
    row[gap] = '.';
    const std::vector<std::string> art(6, row);
    const LabeledCloud cloud = acrossArt(art, {{'A', 1.2f}, {'B', 1.3f}});
    core::HierarchicalGridStats stats;
    EXPECT_EQ(run(cloud, asciiParams(false), &stats).size(), 1u) << row;
    EXPECT_EQ(stats.coarse_blobs, 1u);
    EXPECT_EQ(partitionOf(run(cloud, asciiParams(true))), truthPartition(cloud)) << row;
  }
}

// ------------------------------------------------------------------------------------------
// Radial bridges (step 3): holes along the line of sight are sampling holes.

// Art with rows along the line of sight: the sensor looks along +x through it (columns), so
// a gap between columns is a gap along the line of sight; y0 centres the rows on the x axis.
LabeledCloud alongArt(const std::vector<std::string>& art, float x0) {
  return fromAsciiArt(art, {{'A', 1.0f}, {'B', 1.1f}}, x0, -0.6f);
}

TEST(HierarchicalGridBridges, HolesAlongTheLineOfSightAreBridgedUpToTheReach) {
  core::HierarchicalGridStats stats;
  // Near (x from 6 m): one near-empty sub-cell is bridged, two are not.
  const std::vector<std::string> one(6, "AAA.BBB"), two(6, "AAA..BBB"), four(6, "AAA....BBB");
  auto near_one = run(alongArt(one, 6.0f), asciiParams(true), &stats);
  EXPECT_EQ(near_one.size(), 1u);
  EXPECT_GT(stats.bridges, 0u);
  EXPECT_EQ(partitionOf(run(alongArt(two, 6.0f), asciiParams(true))),
            truthPartition(alongArt(two, 6.0f)));
  // Without bridges the one-sub-cell hole separates, as it does across the line of sight.
  HierarchicalGridDetectorParams no_bridge = asciiParams(true);
  no_bridge.radial_bridge_subcells = 0;
  EXPECT_EQ(run(alongArt(one, 6.0f), no_bridge).size(), 2u);
  // Far (x from 30 m, beyond bridge_range_m): up to three are bridged, four are not.
  const std::vector<std::string> three(6, "AAA...BBB");
  EXPECT_EQ(run(alongArt(three, 30.0f), asciiParams(true)).size(), 1u);
  EXPECT_EQ(run(alongArt(three, 6.0f), asciiParams(true)).size(), 2u) << "near: too wide";
  HierarchicalGridDetectorParams no_far_merge = asciiParams(true);
  no_far_merge.far_merge.max_gap_m = 0.0;
  EXPECT_EQ(partitionOf(run(alongArt(four, 30.0f), no_far_merge)),
            truthPartition(alongArt(four, 30.0f)));
  // (Step 6 then joins these two far pieces, one behind the other, 0.8 m apart.)
  EXPECT_EQ(run(alongArt(four, 30.0f), asciiParams(true)).size(), 1u);
  // The coarse level still decides: a bridge never joins super-cells psi apart.
  const LabeledCloud high = fromAsciiArt(one, {{'A', 1.0f}, {'B', 2.5f}}, 6.0f, -0.6f);
  EXPECT_EQ(run(high, asciiParams(true)).size(), 2u);
}

TEST(HierarchicalGridBridges, ObjectsOneSubCellApartAcrossTheLineOfSightStaySeparateFarAway) {
  // At 30 m, where three sub-cells are bridged along the line of sight, a single near-empty
  // column across it still separates two objects; beyond gap_bridge_range_m (35 m) it is a
  // sampling hole and is bridged, two columns are not.
  const std::vector<std::string> art(6, "AAAA.BBBB"), two(6, "AAAA..BBBB");
  const std::map<char, float> h = {{'A', 1.0f}, {'B', 1.1f}};
  const LabeledCloud at30 = fromAsciiArt(art, h, -0.6f, 30.0f);
  EXPECT_EQ(partitionOf(run(at30, asciiParams(true))), truthPartition(at30));
  EXPECT_EQ(run(fromAsciiArt(art, h, -0.6f, 40.2f), asciiParams(true)).size(), 1u);
  const LabeledCloud two40 = fromAsciiArt(two, h, -0.6f, 40.2f);
  EXPECT_EQ(partitionOf(run(two40, asciiParams(true))), truthPartition(two40));
}

TEST(HierarchicalGridBridges, FarSparseCarsStayOneObjectOnlyThanksToTheBridges) {
  // LiDAR-like cars at 25-55 m, yaws in steps of 0.3 rad keeping every visible side at least
  // 0.4 rad from grazing (as ASingleCarStaysOneObjectAtAnyYawAndRange): with the shipped
  // bridges each car is one object; without them (no radial bridge, no far gap bridge) the
  // scan-line holes of oblique faces shred at least a quarter of them.
  HierarchicalGridDetectorParams none;
  none.radial_bridge_subcells = 0;
  none.far_radial_bridge_subcells = 0;
  none.gap_bridge_range_m = 1000.0;
  none.far_merge.max_gap_m = 0.0;  // step 6 would join far pieces after the fact
  int cases = 0, shredded_without = 0;
  for (const float range : {25.0f, 32.0f, 45.0f, 55.0f}) {
    for (float yaw = 0.0f; yaw < 3.1f; yaw += 0.3f) {
      const float rel = yaw + 0.3f;  // relative to the line of sight (azimuth -0.3 rad)
      if (std::min(std::fabs(std::sin(rel)), std::fabs(std::cos(rel))) < std::sin(0.4f)) continue;
      LabeledCloud cloud;
      test::addLidarCar(&cloud, range * std::cos(-0.3f), range * std::sin(-0.3f), yaw, 1);
      const auto with = run(cloud, HierarchicalGridDetectorParams());
      ++cases;
      ASSERT_FALSE(with.empty()) << "range " << range << " yaw " << yaw;
      std::size_t largest = 0;
      for (const auto& o : with) largest = std::max(largest, o.indices.size());
      EXPECT_GE(largest, cloud.size() * 9 / 10) << "range " << range << " yaw " << yaw;
      std::size_t largest_without = 0;
      for (const auto& o : run(cloud, none)) {
        largest_without = std::max(largest_without, o.indices.size());
      }
      shredded_without += largest_without < cloud.size() * 9 / 10;
    }
  }
  EXPECT_GE(shredded_without * 4, cases) << shredded_without << " of " << cases;
}

TEST(HierarchicalGridCoarse, NeighboursWithDifferentZmaxAreNotMerged) {
  // No gap at all, but the super-cells of L (0.4 m) and T (1.8 m) differ by psi = 1.4 m > 1.2.
  const std::vector<std::string> art = {"LLLTTT", "LLLTTT", "LLLTTT"};
  const LabeledCloud cloud = fromAsciiArt(art, {{'L', 0.4f}, {'T', 1.8f}});
  core::HierarchicalGridStats stats;
  const auto objects = run(cloud, asciiParams(false), &stats);
  EXPECT_EQ(stats.coarse_blobs, 2u);
  EXPECT_EQ(partitionOf(objects), truthPartition(cloud));
  // With psi_max_m = 1.5 they merge, and nothing separates them at the dense level.
  HierarchicalGridDetectorParams p = asciiParams(true);
  p.psi_max_m = 1.5;
  EXPECT_EQ(run(cloud, p).size(), 1u);
}

TEST(HierarchicalGridCoarse, PsiThresholdIsExactForFloatHeights) {
  // psi_max_m = 0.3 is not a float: 0.3f is 0.30000001 > 0.3. Zmax values 0 and 0.3f differ
  // by more than psi_max_m (not linked: two objects), 0 and the next float below 0.3f by less
  // (linked: one object), at both levels. Rounding the threshold to the nearest float instead
  // of down would link the first pair.
  const float below = std::nextafter(0.3f, 0.0f);
  ASSERT_GT(static_cast<double>(0.3f), 0.3);
  ASSERT_LT(static_cast<double>(below), 0.3);
  const std::vector<std::string> art = {"LLLTTT", "LLLTTT", "LLLTTT"};
  for (const bool refine : {false, true}) {
    HierarchicalGridDetectorParams p = asciiParams(refine);
    p.psi_max_m = 0.3;
    EXPECT_EQ(run(fromAsciiArt(art, {{'L', 0.0f}, {'T', 0.3f}}), p).size(), 2u) << refine;
    EXPECT_EQ(run(fromAsciiArt(art, {{'L', 0.0f}, {'T', below}}), p).size(), 1u) << refine;
    // The same pairs the other way round (T lower than L).
    EXPECT_EQ(run(fromAsciiArt(art, {{'L', 0.3f}, {'T', 0.0f}}), p).size(), 2u) << refine;
    EXPECT_EQ(run(fromAsciiArt(art, {{'L', below}, {'T', 0.0f}}), p).size(), 1u) << refine;
  }
}

TEST(HierarchicalGridDense, IsolatedNearEmptySubCellsAreNoise) {
  const std::vector<std::string> art = {"AAA....", "AAA...x", "AAA...."};
  const LabeledCloud cloud = fromAsciiArt(art, {{'A', 1.0f}, {'X', 1.0f}});
  core::HierarchicalGridStats stats;
  const auto objects = run(cloud, asciiParams(true), &stats);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].indices.size(), 9u * 12u);
  EXPECT_EQ(stats.noise_points, 1u);
}

TEST(HierarchicalGridFilters, MinPointsAndMaxExtent) {
  // A: 2 dense sub-cells (24 points); B: a 21 x 0.2 m wall-like strip (4.2 m).
  const std::vector<std::string> art = {"AA..BBBBBBBBBBBBBBBBBBBBB"};
  const LabeledCloud cloud = fromAsciiArt(art, {{'A', 1.0f}, {'B', 1.0f}});
  HierarchicalGridDetectorParams p = asciiParams(true);
  p.min_points = 25;
  core::HierarchicalGridStats stats;
  auto objects = run(cloud, p, &stats);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].indices.size(), 21u * 12u);
  EXPECT_EQ(stats.dropped_small, 1u);
  p.min_points = 1;
  p.max_extent_m = 4.0;
  objects = run(cloud, p, &stats);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].indices.size(), 24u);
  EXPECT_EQ(stats.dropped_large, 1u);
}

TEST(HierarchicalGridFilters, WeightedPointCountDropsNearFragmentsKeepsSparseFarObjects) {
  // Shipped weights: w = 1 near the sensor, > 3 at 40 m. A 40-point fragment at 5 m weighs 40
  // (< 60: dropped); a 24-point object at 40 m weighs > 72 (kept). min_points (10) passes both.
  const HierarchicalGridDetectorParams shipped;
  const core::DistanceWeight w(shipped.weight);
  ASSERT_NEAR(w(5.0f), 1.0f, 1e-6f);
  ASSERT_GT(w(40.0f), 3.0f);
  ASSERT_DOUBLE_EQ(shipped.min_weighted_points, 60.0);
  LabeledCloud cloud;
  for (int i = 0; i < 40; ++i) {  // 2 x 2 sub-cells around (5.1, 0.1), 10 points each
    test::addPoint(&cloud, 5.05f + 0.1f * (i % 4), 0.05f + 0.1f * ((i / 4) % 4), -1.0f + 0.01f * i,
                   1);
  }
  for (int i = 0; i < 24; ++i) {  // 2 x 1 sub-cells around (40.1, 0.1), 12 points each
    test::addPoint(&cloud, 40.05f + 0.1f * (i % 4), 0.05f + 0.05f * ((i / 4) % 3),
                   -1.0f + 0.02f * i, 2);
  }
  core::HierarchicalGridStats stats;
  auto objects = run(cloud, shipped, &stats);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].indices.size(), 24u);
  EXPECT_GT(objects[0].centroid.x(), 39.0f);
  EXPECT_EQ(stats.dropped_small, 1u);
  HierarchicalGridDetectorParams off = shipped;
  off.min_weighted_points = 0.0;
  objects = run(cloud, off, &stats);
  EXPECT_EQ(objects.size(), 2u);
  EXPECT_EQ(stats.dropped_small, 0u);
  off.min_weighted_points = -1.0;
  EXPECT_NE(core::validate(off).find("min_weighted_points"), std::string::npos);
}

// ------------------------------------------------------------------------------------------
// LiDAR-like cars.

TEST(HierarchicalGridCars, ASingleCarStaysOneObjectAtAnyYawAndRange) {
  // The car's body (every point below the roof) must be one object, whatever the view. Its
  // roof is 0.23 m below the sensor, so from a few metres on the roof gets single scan lines
  // up to metres behind the body; those may stay apart (the kd-tree splits them too) but must
  // not cut the body, and at least 90 % of all points are in the body's object. Yaw is
  // relative to the line of sight (0.7 rad) and keeps every visible side at >= 0.4 rad from
  // grazing: a side seen edge-on returns scan lines metres apart, which no 2-D or 3-D
  // proximity rule joins (the kd-tree neither).
  const HierarchicalGridDetectorParams p;  // shipped defaults
  for (const float range : {6.0f, 12.0f, 25.0f, 40.0f}) {
    for (const float rel_yaw : {0.4f, 0.8f, 1.17f, 1.97f, 2.35f, 2.74f}) {
      const float yaw = 0.7f + rel_yaw;
      LabeledCloud cloud;
      test::addLidarCar(&cloud, range * std::cos(0.7f), range * std::sin(0.7f), yaw, 1);
      ASSERT_GT(cloud.size(), 20u);
      const auto objects = run(cloud, p);
      const float roof_z = 1.5f - 1.73f - 0.02f;
      std::set<std::uint32_t> body;
      for (const LabeledPoint& q : cloud.points) {
        if (q.z < roof_z) body.insert(q.index);
      }
      std::size_t holding = 0;
      for (const auto& o : objects) {
        const std::set<std::uint32_t> mine(o.indices.begin(), o.indices.end());
        std::size_t n = 0;
        for (const std::uint32_t i : body) n += mine.count(i);
        if (n == 0) continue;
        ++holding;
        EXPECT_EQ(n, body.size()) << "range " << range << " yaw " << yaw;
        EXPECT_GE(o.indices.size(), cloud.size() * 9 / 10) << "range " << range << " yaw " << yaw;
      }
      EXPECT_EQ(holding, 1u) << "range " << range << " yaw " << yaw;
    }
  }
}

// Object holding each ground-truth label's body points (below the roof), or -1 when they are
// not all in one object; -2 when an object mixes bodies of different labels.
std::map<std::uint32_t, int> bodyObjects(const LabeledCloud& cloud,
                                         const std::vector<DetectedObject>& objects) {
  std::map<std::uint32_t, int> obj_of_index;
  for (std::size_t k = 0; k < objects.size(); ++k) {
    for (const std::uint32_t i : objects[k].indices) obj_of_index[i] = static_cast<int>(k);
  }
  std::map<std::uint32_t, int> result;
  std::map<int, std::uint32_t> label_of_object;
  for (const LabeledPoint& q : cloud.points) {
    if (q.z >= 1.5f - 1.73f - 0.02f) continue;  // roof scan lines may stay apart
    const auto it = obj_of_index.find(q.index);
    const int obj = it == obj_of_index.end() ? -1 : it->second;
    auto r = result.emplace(q.label, obj);
    if (r.first->second != obj) r.first->second = -1;
    if (obj >= 0) {
      auto l = label_of_object.emplace(obj, q.label);
      if (l.first->second != q.label) result[q.label] = -2;
    }
  }
  return result;
}

TEST(HierarchicalGridCars, TwoParkedCarsAreTwoObjectsWhateverTheGridAlignment) {
  // Parked in a row along x at y = 6 m (a kerb-side scene), 0.8 m bumper to bumper: wide
  // enough for a 0.4 m strip of empty sub-cells wherever the gap falls on the grid, which the
  // shifts sweep over one super-cell. Their sides are equally high, so wherever no whole
  // empty super-cell fits in the gap, the coarse level alone merges the two bodies.
  int coarse_merged = 0;
  for (float shift = 0.0f; shift < 0.6f; shift += 0.05f) {
    LabeledCloud cloud;
    test::addLidarCar(&cloud, 4.0f + shift, 6.0f, 0.0f, 1);
    test::addLidarCar(&cloud, 4.0f + shift + 4.5f + 0.8f, 6.0f, 0.0f, 2);
    HierarchicalGridDetectorParams p;
    p.dense_refinement = false;
    auto bodies = bodyObjects(cloud, run(cloud, p));
    coarse_merged += bodies[2] == -2;
    bodies = bodyObjects(cloud, run(cloud, HierarchicalGridDetectorParams()));
    EXPECT_GE(bodies[1], 0) << "shift " << shift;
    EXPECT_GE(bodies[2], 0) << "shift " << shift;
    EXPECT_NE(bodies[1], bodies[2]) << "shift " << shift;
  }
  EXPECT_GE(coarse_merged, 3);
}

TEST(HierarchicalGridWeights, FarSparseCarSurvivesOnlyThanksToTheDistanceWeight) {
  // A car at 55 m seen with the KITTI HDL-64E's angular steps: 1-4 points per sub-cell.
  LabeledCloud cloud;
  test::addLidarCar(&cloud, 55.0f * std::cos(-0.3f), 55.0f * std::sin(-0.3f), 0.5f, 1);
  ASSERT_GT(cloud.size(), 15u);
  HierarchicalGridDetectorParams p;  // shipped defaults, weight on
  core::HierarchicalGridStats with_stats, without_stats;
  const auto with = run(cloud, p, &with_stats);
  ASSERT_EQ(with.size(), 1u);
  EXPECT_EQ(with[0].indices.size(), cloud.size());
  p.weight.enabled = false;
  const auto without = run(cloud, p, &without_stats);
  // Unweighted, the sub-cells are near-empty: the car is dropped as noise or shredded.
  EXPECT_TRUE(without.empty() || without.size() > 1 || without[0].indices.size() < cloud.size() / 2)
      << without.size() << " objects";
  EXPECT_LT(without_stats.dense_occupied, with_stats.dense_occupied / 2);
}

// ------------------------------------------------------------------------------------------
// Agreement with the kd-tree baseline, and bad input.

LabeledCloud wellSeparatedScene() {
  LabeledCloud cloud;
  std::uint32_t id = 1;
  // Vans (2.2 m: taller than the sensor, so no sparse roof lines) and pedestrians at least
  // 3 m apart, at 5..35 m around the sensor, no side seen edge-on: objects both detectors
  // must find exactly.
  const float vans[][3] = {{8, 3, 1.2f}, {-10, 6, 1.0f}, {15, -9, 2.0f}, {-20, -14, 0.0f}};
  for (const auto& c : vans) test::addLidarCar(&cloud, c[0], c[1], c[2], id++, 5.0f, 2.0f, 2.2f);
  const float peds[][2] = {{4, -6}, {-6, -3}, {12, 12}};
  for (const auto& pd : peds) {
    test::addLidarCar(&cloud, pd[0], pd[1], 0.3f, id++, 0.5f, 0.5f, 1.8f);
  }
  return cloud;
}

TEST(HierarchicalGridVsKdTree, SamePartitionAndBoxesOnWellSeparatedObjects) {
  const LabeledCloud cloud = wellSeparatedScene();
  const auto grid = run(cloud, HierarchicalGridDetectorParams());
  core::KdTreeDetector kd;
  std::vector<DetectedObject> kobj;
  kd.detect(cloud, &kobj);
  EXPECT_EQ(partitionOf(grid), truthPartition(cloud));
  EXPECT_EQ(partitionOf(kobj), truthPartition(cloud));
  // Both order objects by their first point, and share the geometry code: identical boxes.
  ASSERT_EQ(grid.size(), kobj.size());
  for (std::size_t i = 0; i < grid.size(); ++i) {
    EXPECT_EQ(grid[i].id, kobj[i].id);
    EXPECT_EQ(grid[i].indices, kobj[i].indices);
    EXPECT_TRUE(grid[i].obb_center.isApprox(kobj[i].obb_center));
    EXPECT_TRUE(grid[i].obb_size.isApprox(kobj[i].obb_size));
    EXPECT_FLOAT_EQ(grid[i].obb_yaw_rad, kobj[i].obb_yaw_rad);
  }
}

// The kd-tree's neighbour order is not used by the clustering: sorted and unsorted radius
// searches give the same objects, point order within them included (both order objects and
// their points by position in the input).
TEST(KdTreeDetector, SortedAndUnsortedSearchGiveTheSameObjects) {
  LabeledCloud cloud = wellSeparatedScene();
  // Two cars touching (one cluster) and a sparse pole: clusters grown across many searches.
  std::uint32_t id = 100;
  test::addLidarCar(&cloud, 25.0f, 20.0f, 0.0f, id++, 4.5f, 1.8f, 1.5f);
  test::addLidarCar(&cloud, 25.0f, 22.0f, 0.0f, id++, 4.5f, 1.8f, 1.5f);
  for (int k = 0; k < 12; ++k) test::addPoint(&cloud, -3.0f, 9.0f, -1.6f + 0.25f * k, id);
  core::KdTreeDetectorParams sorted_p, unsorted_p;
  sorted_p.sorted_search = true;
  unsorted_p.sorted_search = false;
  core::KdTreeDetector sorted(sorted_p), unsorted(unsorted_p);
  std::vector<DetectedObject> a, b;
  sorted.detect(cloud, &a);
  unsorted.detect(cloud, &b);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GE(a.size(), 8u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].indices, b[i].indices);
    EXPECT_EQ(a[i].centroid, b[i].centroid);
    EXPECT_EQ(a[i].obb_center, b[i].obb_center);
    EXPECT_EQ(a[i].obb_size, b[i].obb_size);
    EXPECT_EQ(a[i].obb_yaw_rad, b[i].obb_yaw_rad);
  }
}

TEST(HierarchicalGridInput, EmptyAndOnePoint) {
  HierarchicalGridDetector det;
  std::vector<DetectedObject> objects(3);  // stale content must be cleared
  det.detect(LabeledCloud(), &objects);
  EXPECT_TRUE(objects.empty());
  LabeledCloud one;
  test::addPoint(&one, 5.0f, 5.0f, -1.0f, 1);
  det.detect(one, &objects);
  EXPECT_TRUE(objects.empty());  // min_points = 10
  HierarchicalGridDetectorParams p;
  p.min_points = 1;
  p.min_weighted_points = 0.0;
  p.dense_min_weighted_points = 1.0;
  HierarchicalGridDetector det1(p);
  det1.detect(one, &objects);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].id, 1u);
  EXPECT_EQ(objects[0].indices, std::vector<std::uint32_t>{0});
  EXPECT_TRUE(objects[0].centroid.isApprox(Eigen::Vector3f(5.0f, 5.0f, -1.0f)));
  EXPECT_EQ(objects[0].obb_size, Eigen::Vector3f::Zero());
}

TEST(HierarchicalGridInput, NonFiniteAndHugePointsAreIgnored) {
  const LabeledCloud clean = wellSeparatedScene();
  LabeledCloud dirty;
  const float bad[] = {std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity(),
                       -std::numeric_limits<float>::infinity(),
                       1e30f,
                       -1e30f,
                       3e38f};
  std::size_t k = 0;
  for (const LabeledPoint& p : clean.points) {
    dirty.push_back(p);  // keeps its index
    if (p.index % 7 == 0) {
      LabeledPoint q = p;
      q.index = 1000000 + static_cast<std::uint32_t>(k);
      const float b = bad[k++ % 6];
      (k % 3 == 0 ? q.x : k % 3 == 1 ? q.y : q.z) = b;
      dirty.push_back(q);
    }
  }
  HierarchicalGridDetector det;
  std::vector<DetectedObject> a, b;
  det.detect(clean, &a);
  det.detect(dirty, &b);
  EXPECT_EQ(partitionOf(a), partitionOf(b));
  EXPECT_EQ(det.stats().invalid_points + det.stats().outside_points, dirty.size() - clean.size());
  core::KdTreeDetector kd;
  kd.detect(clean, &a);
  kd.detect(dirty, &b);
  EXPECT_EQ(partitionOf(a), partitionOf(b));
}

// The binning takes four points at a time and the remainder one by one: the same points, on
// the grid border and off it, at every position modulo four give the same objects, boxes and
// counts.
TEST(HierarchicalGridInput, PointsBinAlikeInBlocksOfFourAndInTheRemainder) {
  HierarchicalGridDetector det;
  const float lo = -80.4f;  // the grid's lower corner with the defaults: -ceil(80 / 0.6) * 0.6
  ASSERT_EQ(static_cast<float>(-std::ceil(80.0 / 0.6) * 0.6), lo);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // x, y, z; inside: on the lower corner, just inside the upper one, just inside the z limit;
  // outside: just below the lower corner, on the upper one, beyond the z limit; invalid: NaN.
  const float inside[][3] = {{lo, lo, 0.0f}, {-lo - 0.001f, 3.0f, 0.0f}, {2.0f, 2.0f, 49.99f}};
  const float outside[][3] = {
      {std::nextafter(lo, -100.0f), 0.0f, 0.0f}, {-lo, 0.0f, 0.0f}, {0.0f, 2.0f, -50.01f}};
  LabeledCloud base = wellSeparatedScene();
  for (const auto& q : inside) test::addPoint(&base, q[0], q[1], q[2], 0);
  for (const auto& q : outside) test::addPoint(&base, q[0], q[1], q[2], 0);
  test::addPoint(&base, nan, 1.0f, 0.0f, 0);
  std::vector<DetectedObject> expected;
  det.detect(base, &expected);
  const core::HierarchicalGridStats expected_stats = det.stats();
  EXPECT_EQ(expected_stats.outside_points, 3u);
  EXPECT_EQ(expected_stats.invalid_points, 1u);
  ASSERT_GE(expected.size(), 7u);
  for (int shift = 1; shift < 8; ++shift) {
    LabeledCloud shifted;
    for (int k = 0; k < shift; ++k) test::addPoint(&shifted, nan, nan, nan, 0);
    for (const LabeledPoint& p : base.points) shifted.push_back(p);
    if (shift % 2) std::reverse(shifted.points.begin(), shifted.points.end());
    std::vector<DetectedObject> out;
    det.detect(shifted, &out);
    EXPECT_EQ(det.stats().invalid_points, 1u + shift) << shift;
    EXPECT_EQ(det.stats().outside_points, 3u) << shift;
    EXPECT_EQ(det.stats().dense_cells, expected_stats.dense_cells) << shift;
    EXPECT_EQ(partitionOf(out), partitionOf(expected)) << shift;
    if (shift % 2) continue;  // reversed: the same objects, sums in another order
    ASSERT_EQ(out.size(), expected.size());
    for (std::size_t k = 0; k < out.size(); ++k) {
      EXPECT_EQ(out[k].indices, expected[k].indices) << shift;
      EXPECT_EQ(out[k].centroid, expected[k].centroid) << shift;
      EXPECT_EQ(out[k].obb_center, expected[k].obb_center) << shift;
      EXPECT_EQ(out[k].obb_size, expected[k].obb_size) << shift;
    }
  }
}

TEST(HierarchicalGridInput, BuffersAreReusedAcrossFramesWithoutStaleState) {
  const LabeledCloud first = wellSeparatedScene();
  LabeledCloud second;
  test::addLidarCar(&second, 30.0f, -5.0f, 0.9f, 1);
  HierarchicalGridDetector reused;
  std::vector<DetectedObject> out;
  reused.detect(first, &out);
  reused.detect(second, &out);
  HierarchicalGridDetector fresh;
  std::vector<DetectedObject> expected;
  fresh.detect(second, &expected);
  EXPECT_EQ(partitionOf(out), partitionOf(expected));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(reused.stats().dense_cells, fresh.stats().dense_cells);
}

TEST(HierarchicalGridInput, TwoMillionRandomPoints) {
  LabeledCloud cloud;
  cloud.resize(2000000);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-100.0f, 100.0f);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = u(rng);
    cloud[i].y = u(rng);
    cloud[i].z = u(rng) * 0.02f;
    cloud[i].index = static_cast<std::uint32_t>(i);
  }
  HierarchicalGridDetector det;
  std::vector<DetectedObject> objects;
  det.detect(cloud, &objects);
  const auto& s = det.stats();
  EXPECT_EQ(s.input_points, cloud.size());
  // Points with |x| or |y| >= 80.4 (the grid rounded to whole super-cells) are outside.
  const double inside = (160.8 / 200.0) * (160.8 / 200.0);
  EXPECT_NEAR(static_cast<double>(s.outside_points) / cloud.size(), 1.0 - inside, 0.01);
  std::set<std::uint32_t> seen;
  std::size_t assigned = 0;
  for (const auto& o : objects) {
    assigned += o.indices.size();
    seen.insert(o.indices.begin(), o.indices.end());
    EXPECT_LE(o.max_pt.x() - o.min_pt.x(), 20.0f);
    EXPECT_LE(o.max_pt.y() - o.min_pt.y(), 20.0f);
  }
  EXPECT_EQ(seen.size(), assigned) << "a point in two objects";
  EXPECT_LE(assigned + s.noise_points, cloud.size() - s.outside_points);
  // Poisson occupancy: 50 points per m^2, 2 per 0.2 m sub-cell on average, P(empty) = e^-2.
  EXPECT_NEAR(static_cast<double>(s.dense_cells) / (804.0 * 804.0), 1.0 - std::exp(-2.0), 0.01);
}

// Sub-cells near the grid border probe their neighbours and bridges with bounds checks, the
// others through flat offsets: objects touching the border of a 10 m grid come out exactly as
// from a 20 m grid (same cell borders, multiples of 0.6 m), where they are inside.
TEST(HierarchicalGridInput, ObjectsAtTheGridBorderAreFoundAsInALargerGrid) {
  LabeledCloud cloud;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // The 10 m grid covers [-10.2, 10.2)^2. Blobs on its edges and corners (and one inside),
  // 0.5 m x 1.4 m, with gaps along the line of sight that need bridges.
  const float centres[][2] = {{9.9f, 0.3f}, {-9.95f, -2.0f}, {3.0f, 9.95f}, {-1.0f, -9.9f},
                              {9.9f, 9.9f}, {-9.9f, 9.9f},   {5.0f, 2.0f},  {9.9f, -4.0f}};
  std::uint32_t truth = 1;
  for (const auto& c : centres) {
    for (int i = 0; i < 150; ++i) {
      const float a = u(rng), b = u(rng);
      if (a > 0.45f && a < 0.6f) continue;  // a hole across the blob
      test::addPoint(&cloud, std::clamp(c[0] - 0.25f + 0.5f * a, -10.19f, 10.19f),
                     std::clamp(c[1] - 0.7f + 1.4f * b, -10.19f, 10.19f), 1.5f * u(rng), truth);
    }
    ++truth;
  }
  HierarchicalGridDetectorParams small, large;
  small.grid_half_extent_m = 10.0;
  large.grid_half_extent_m = 20.0;
  const auto a = run(cloud, small), b = run(cloud, large);
  ASSERT_EQ(a.size(), 8u);  // one object per blob (a few isolated points may be noise)
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_GT(a[i].indices.size(), 100u);
    for (const std::uint32_t k : a[i].indices) ASSERT_EQ(cloud[k].label, i + 1);
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].indices, b[i].indices);
    EXPECT_EQ(a[i].obb_center, b[i].obb_center);
    EXPECT_EQ(a[i].obb_size, b[i].obb_size);
    EXPECT_EQ(a[i].obb_yaw_rad, b[i].obb_yaw_rad);
  }
}

// The same with the far and farthest bridge tables (step 3) in use inside the 10 m grid and
// the longest bridges: interior sub-cells probe one padded row per table and direction bin,
// border ones probe the neighbours and bridges one by one; both make the same links in the
// same order (same objects, same number of bridges).
TEST(HierarchicalGridInput, FarBridgeTablesAtTheGridBorderGiveTheSameLinksAsInside) {
  LabeledCloud cloud;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float centres[][2] = {{9.8f, 0.3f}, {-9.8f, -2.0f}, {3.0f, 9.8f}, {-1.0f, -9.8f},
                              {9.8f, 9.8f}, {-9.8f, 9.8f},  {5.0f, 2.0f}, {2.5f, -1.0f}};
  for (const auto& c : centres) {
    for (int i = 0; i < 120; ++i) {
      const float a = u(rng), b = u(rng);
      if ((a > 0.3f && a < 0.5f) || (b > 0.4f && b < 0.55f)) continue;  // holes both ways
      test::addPoint(&cloud, std::clamp(c[0] - 0.4f + 0.8f * a, -10.19f, 10.19f),
                     std::clamp(c[1] - 0.8f + 1.6f * b, -10.19f, 10.19f), 1.5f * u(rng), 1);
    }
  }
  for (const double gap_range : {4.0, 100.0}) {
    HierarchicalGridDetectorParams small;
    small.grid_half_extent_m = 10.0;
    small.bridge_range_m = 2.0;
    small.gap_bridge_range_m = gap_range;
    small.far_radial_bridge_subcells = 8;
    small.dense_min_weighted_points = 2.0;
    small.min_weighted_points = 0.0;
    HierarchicalGridDetectorParams large = small;
    large.grid_half_extent_m = 20.0;
    HierarchicalGridDetector det_small(small), det_large(large);
    std::vector<DetectedObject> a, b;
    det_small.detect(cloud, &a);
    det_large.detect(cloud, &b);
    EXPECT_GT(det_small.stats().bridges, 0u);
    EXPECT_EQ(det_small.stats().bridges, det_large.stats().bridges);
    EXPECT_EQ(det_small.stats().components, det_large.stats().components);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_GE(a.size(), 4u);
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].indices, b[i].indices);
  }
}

TEST(HierarchicalGridParams, ValidateNamesTheBadField) {
  HierarchicalGridDetectorParams p;
  EXPECT_EQ(core::validate(p), "");
  p.xi = 0;
  EXPECT_NE(core::validate(p).find("xi"), std::string::npos);
  EXPECT_THROW(HierarchicalGridDetector{p}, std::invalid_argument);
  p = HierarchicalGridDetectorParams();
  p.coarse_cell_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(core::validate(p).find("coarse_cell_m"), std::string::npos);
  p = HierarchicalGridDetectorParams();
  p.grid_half_extent_m = 500.0;
  p.coarse_cell_m = 0.05;
  EXPECT_NE(core::validate(p).find("sub-cells"), std::string::npos);
  core::KdTreeDetectorParams k;
  EXPECT_EQ(core::validate(k), "");
  k.cluster_tolerance_m = 0.0;
  EXPECT_NE(core::validate(k).find("cluster_tolerance_m"), std::string::npos);
}

}  // namespace
}  // namespace urban_detection
