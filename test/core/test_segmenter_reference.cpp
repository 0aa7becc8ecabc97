// The optimised GridSegmenter (reused scratch buffers, occupied-cell lists, branch-free
// per-point passes) must give exactly the labels and statistics of the plain re-statement of
// the algorithm in reference_segmenter.h: on the real scans of ../shared/data (SemanticKITTI
// and both KITTI raw drives, skipped when absent), on synthetic scenes with invalid points,
// and under parameter variants that switch the optional branches on and off. Frames run
// back to back through one segmenter, so stale scratch state from the previous frame would
// show up as a mismatch.
#include "urban_detection/core/common/point_types.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "reference_segmenter.h"
#include "segmentation_scene.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace {

using core::SegmentClass;

std::vector<CloudXYZIRT> sharedFrames(std::size_t per_drive) {
  std::vector<CloudXYZIRT> frames;
  const std::string root = UD_SHARED_DATA;
  for (const auto& f : core::listFiles(root + "/semantic_kitti/sequences/00/velodyne", ".bin")) {
    CloudXYZIRT c;
    if (core::readKittiBin(f, &c)) frames.push_back(std::move(c));
  }
  for (const char* drive : {"drive_0048", "drive_0005"}) {
    const auto files = core::listFiles(root + "/kitti_raw/" + drive, ".pcd");
    for (std::size_t i = 0; i < files.size() && i < per_drive; ++i) {
      CloudXYZIRT c;
      if (core::readPcdXyzi(files[i], &c)) frames.push_back(std::move(c));
    }
  }
  return frames;
}

// A street: road, curb, facades on both sides, parked cars, plus invalid points sprinkled in
// (NaN, +-inf, far away, absurdly high) at fixed positions from point `invalid_from` on.
CloudXYZIRT syntheticStreet(unsigned seed, std::size_t invalid_from = 0) {
  std::vector<test::Box> boxes = {
      {-30.f, 6.0f, 0.0f, 30.f, 7.0f, 12.0f, 1},   // facade left
      {-30.f, -8.0f, 0.0f, 30.f, -7.0f, 1.3f, 2},  // low wall right (Hough territory)
      {4.f, 2.5f, 0.0f, 8.5f, 4.3f, 1.5f, 3},      // parked car
      {-9.f, -4.f, 0.0f, -5.f, -2.2f, 1.6f, 4},    // parked car
      {-30.f, 4.0f, 0.0f, 30.f, 6.0f, 0.15f, 5},   // sidewalk behind a curb
  };
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(1.73f, boxes, &tags, 64, 1200);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> noise(-0.02f, 0.02f);
  for (auto& p : cloud.points) p.z += noise(rng);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < cloud.size(); i += 97) {
    if (i < invalid_from) continue;
    switch ((i / 97) % 6) {
      case 0:
        cloud[i].x = nan;
        break;
      case 1:
        cloud[i].z = inf;
        break;
      case 2:
        cloud[i].z = -inf;
        break;
      case 3:
        cloud[i].z = nan;
        break;
      case 4:
        cloud[i].y = 500.0f;
        break;
      default:
        cloud[i].z = 80.0f;
        break;
    }
  }
  return cloud;
}

void expectSameAsReference(core::GridSegmenter* seg, const CloudXYZIRT& cloud,
                           const std::string& what) {
  std::vector<SegmentClass> labels;
  seg->segment(cloud, &labels);
  const reference::RefOutput ref = reference::segment(cloud, seg->params());
  ASSERT_EQ(labels.size(), ref.labels.size()) << what;
  std::size_t differ = 0, first = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] != ref.labels[i] && differ++ == 0) first = i;
  }
  EXPECT_EQ(differ, 0u) << what << ": first differing point " << first << " ("
                        << static_cast<int>(labels[first]) << " vs reference "
                        << static_cast<int>(ref.labels[first]) << ")";
  const core::SegmentationStats& s = seg->stats();
  EXPECT_EQ(s.points_unknown, ref.stats.points_unknown) << what;
  EXPECT_EQ(s.points_non_finite, ref.stats.points_non_finite) << what;
  EXPECT_EQ(s.points_clutter, ref.stats.points_clutter) << what;
  EXPECT_EQ(s.points_ground, ref.stats.points_ground) << what;
  EXPECT_EQ(s.points_tall, ref.stats.points_tall) << what;
  EXPECT_EQ(s.points_short, ref.stats.points_short) << what;
  EXPECT_EQ(s.cells_occupied, ref.stats.cells_occupied) << what;
  EXPECT_EQ(s.cells_ground_reached, ref.stats.cells_ground_reached) << what;
  EXPECT_EQ(s.hough.lines_found, ref.stats.hough.lines_found) << what;
  EXPECT_EQ(s.hough.cells_relabeled, ref.stats.hough.cells_relabeled) << what;
}

std::vector<core::GridSegmenterParams> variants() {
  std::vector<core::GridSegmenterParams> v(12);
  // Step 5b (shipped off): overhangs and thin uprights, and the long-vehicle rule's test left to
  // the Hough refinement near the sensor; then everywhere, over any object height.
  v[10].overhang_min_gap_m = 0.6;
  v[10].thin_max_width_m = 0.3;
  v[10].vehicle_fov_test_near = false;
  v[11].overhang_min_gap_m = 0.3;
  v[11].overhang_min_height_m = 0.0;
  v[11].overhang_max_range_m = 80.0;
  v[11].thin_max_width_m = 1.0;
  v[9].curb_cells_ground = true;
  v[1].hough.enabled = false;
  v[2].ground_in_sparse_cells = false;
  v[2].min_points_per_cell = 6;
  v[3].cell_size_m = 0.4;
  v[3].max_range_m = 50.0;
  v[3].terrain_fill_iterations = 3;
  v[4].terrain_fill_iterations = 30;  // beyond the terrain bit windows: plain ring scan
  // The smallest and largest bit windows (fillTerrain ORs the terrain rows in blocks of
  // 2 * terrain_fill_iterations + 1 rows; 3 and 57 do not divide the padded row count).
  v[5].terrain_fill_iterations = 1;
  v[6].terrain_fill_iterations = 28;
  v[7].vehicle_max_height_m = 0.0;  // the long-vehicle rule off, and loosened (more groups)
  v[8].vehicle_max_length_m = 40.0;
  v[8].vehicle_max_width_m = 40.0;
  return v;
}

TEST(SegmenterReference, SyntheticStreetsWithInvalidPointsMatchTheReference) {
  for (const auto& params : variants()) {
    core::GridSegmenter seg(params);
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const CloudXYZIRT cloud = syntheticStreet(seed);
      // Not vacuous: the scene must exercise every class.
      const auto ref = reference::segment(cloud, params);
      EXPECT_GT(ref.stats.points_ground, 1000u);
      EXPECT_GT(ref.stats.points_tall, 100u);
      EXPECT_GT(ref.stats.points_short, 100u);
      EXPECT_GT(ref.stats.points_unknown, 100u);
      expectSameAsReference(&seg, cloud, "synthetic seed " + std::to_string(seed));
    }
  }
}

// SimpleGrid::build takes a run-by-run path for chunks of points without invalid points and a
// point-by-point one otherwise; runs cross chunk boundaries and both paths. Streets without
// invalid points (long runs near the sensor, 1-point runs far away), and with invalid points
// only in the second half, so that chunks of both kinds follow each other.
TEST(SegmenterReference, StreetsWithAndWithoutInvalidChunksMatchTheReference) {
  for (const auto& params : variants()) {
    core::GridSegmenter seg(params);
    for (unsigned seed = 4; seed <= 5; ++seed) {
      const CloudXYZIRT clean = syntheticStreet(seed, std::numeric_limits<std::size_t>::max());
      const auto ref = reference::segment(clean, params);
      // Not vacuous: many 1024-point chunks (SimpleGrid's) hold no point without a cell.
      std::size_t clean_chunks = 0;
      for (std::size_t b = 0; b + 1024 <= clean.size(); b += 1024) {
        bool any_unknown = false;
        for (std::size_t i = b; i < b + 1024; ++i) {
          any_unknown = any_unknown || ref.labels[i] == SegmentClass::kUnknown;
        }
        clean_chunks += any_unknown ? 0 : 1;
      }
      EXPECT_GT(clean_chunks, 20u);
      EXPECT_GT(ref.stats.points_short, 100u);
      expectSameAsReference(&seg, clean, "clean street seed " + std::to_string(seed));
      const CloudXYZIRT half = syntheticStreet(seed, clean.size() / 2);
      expectSameAsReference(&seg, half, "street invalid from half, seed " + std::to_string(seed));
    }
  }
}

TEST(SegmenterReference, EmptyOnePointAndAllInvalidCloudsMatchTheReference) {
  core::GridSegmenter seg;
  CloudXYZIRT empty;
  expectSameAsReference(&seg, empty, "empty");
  CloudXYZIRT one;
  PointXYZIRT p;
  p.x = 3.0f;
  p.y = -2.0f;
  p.z = -1.7f;
  one.push_back(p);
  expectSameAsReference(&seg, one, "one point");
  CloudXYZIRT bad;
  for (int i = 0; i < 100; ++i) {
    p.x = i % 2 ? std::numeric_limits<float>::quiet_NaN() : 1e30f;
    bad.push_back(p);
  }
  expectSameAsReference(&seg, bad, "all invalid");
  expectSameAsReference(&seg, syntheticStreet(7), "street after invalid clouds");
}

TEST(SegmenterReference, RealScansMatchTheReference) {
  const std::vector<CloudXYZIRT> frames = sharedFrames(6);
  if (frames.empty()) GTEST_SKIP() << "no SemanticKITTI / KITTI raw scans in " << UD_SHARED_DATA;
  for (const auto& params : variants()) {
    core::GridSegmenter seg(params);
    for (std::size_t f = 0; f < frames.size(); ++f) {
      expectSameAsReference(&seg, frames[f], "real frame " + std::to_string(f));
      if (HasFailure()) return;
    }
  }
}

}  // namespace
}  // namespace urban_detection

namespace urban_detection {
namespace {

// SimpleGrid::rowOf / colOf take the quotient from a floating-point reciprocal: they must equal
// integer division for every index, checked at each row boundary (where rounding would show)
// for small, default and large grids (2000 x 2000 cells).
TEST(SimpleGridIndex, RowAndColumnEqualIntegerDivisionAtEveryRowBoundary) {
  for (const auto& geometry : {std::pair<double, double>{1.0, 3.0},
                               {0.5, 80.0},
                               {0.4, 50.0},
                               {0.25, 250.0},
                               {0.05, 20.0},
                               {0.3, 97.3}}) {
    core::SimpleGridParams p;
    p.cell_size_m = geometry.first;
    p.max_range_m = geometry.second;
    const core::SimpleGrid grid(p);
    const std::int64_t side = grid.cols(), cells = side * side;
    std::size_t wrong = 0;
    for (std::int64_t row = 0; row < side; ++row) {
      for (std::int64_t d = -2; d <= 2; ++d) {
        const std::int64_t i = row * side + d;
        if (i < 0 || i >= cells) continue;
        const auto idx = static_cast<std::int32_t>(i);
        wrong += grid.rowOf(idx) != i / side || grid.colOf(idx) != i % side;
      }
    }
    EXPECT_EQ(wrong, 0u) << "side " << side;
  }
}

}  // namespace
}  // namespace urban_detection

namespace urban_detection {
namespace {

// SimpleGrid::build's AVX2 cell pass (eight points at a time, chosen at run time) must give
// bit for bit the SSE2 path's per-point slots and heights and per-cell statistics: synthetic
// streets with invalid points, a clean one, odd lengths (tails of fewer than eight points) and
// the real scans of ../shared/data.
TEST(SimpleGridAvx2, SameGridAsTheSse2Path) {
  core::SimpleGrid avx2, sse2;
  sse2.setAllowAvx2(false);
  EXPECT_FALSE(sse2.avx2Active());
  if (!avx2.avx2Active()) GTEST_SKIP() << "this CPU has no AVX2";
  std::vector<CloudXYZIRT> clouds = sharedFrames(3);
  for (unsigned seed = 1; seed <= 3; ++seed) clouds.push_back(syntheticStreet(seed));
  clouds.push_back(syntheticStreet(4, std::numeric_limits<std::size_t>::max()));
  CloudXYZIRT odd = syntheticStreet(5);
  odd.points.resize(3 * 1024 + 13);
  clouds.push_back(odd);
  std::size_t valid_points = 0, invalid_points = 0;
  for (std::size_t f = 0; f < clouds.size(); ++f) {
    const CloudXYZIRT& cloud = clouds[f];
    avx2.build(cloud, 1.73f, 50.0f);
    sse2.build(cloud, 1.73f, 50.0f);
    ASSERT_EQ(avx2.pointSlots(), sse2.pointSlots()) << "cloud " << f;
    ASSERT_EQ(avx2.pointHeights().size(), sse2.pointHeights().size());
    EXPECT_EQ(std::memcmp(avx2.pointHeights().data(), sse2.pointHeights().data(),
                          sizeof(float) * cloud.size()),
              0)
        << "cloud " << f;
    ASSERT_EQ(avx2.occupiedCells().toVector(), sse2.occupiedCells().toVector()) << "cloud " << f;
    const auto a = avx2.occupiedStats();
    const auto b = sse2.occupiedStats();
    ASSERT_EQ(a.size(), b.size());
    std::size_t differ = 0;
    for (std::size_t s = 0; s < a.size(); ++s) {
      differ += a[s].count != b[s].count ||
                std::memcmp(&a[s].z_min, &b[s].z_min, sizeof(float)) != 0 ||
                std::memcmp(&a[s].z_max, &b[s].z_max, sizeof(float)) != 0 ||
                std::memcmp(&a[s].z_sum, &b[s].z_sum, sizeof(float)) != 0;
    }
    EXPECT_EQ(differ, 0u) << "cloud " << f;
    for (const std::int32_t s : avx2.pointSlots()) (s == 0 ? invalid_points : valid_points)++;
  }
  EXPECT_GT(valid_points, 100000u);
  EXPECT_GT(invalid_points, 100u);
}

}  // namespace
}  // namespace urban_detection
