// Segmenting a revolution as it arrives: the points binned batch by batch with
// GridSegmenter::addPoints (as PacketSource hands on each sector) and the rest at segment()
// must give exactly the labels, statistics, cell classes and grid of segment() on the whole
// cloud, for any split of the revolution (runs of points in one cell cut between two
// batches, one-point and empty batches), on synthetic streets with invalid points, on the
// simulated drive and on the real scans of ../shared/data (skipped when absent); a lost or
// foreign batch makes segment() bin the whole cloud afresh, with the same result.
#include "urban_detection/core/common/point_types.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "segmentation_scene.h"
#include "simulated_drive.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace urban_detection {
namespace {

std::vector<CloudXYZIRT> realScans(std::size_t per_drive) {
  std::vector<CloudXYZIRT> frames;
  const std::string root = UD_SHARED_DATA;
  const auto semantic = core::listFiles(root + "/semantic_kitti/sequences/00/velodyne", ".bin");
  for (std::size_t i = 0; i < semantic.size() && i < per_drive; ++i) {
    CloudXYZIRT c;
    if (core::readKittiBin(semantic[i], &c)) frames.push_back(std::move(c));
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

// A street with invalid points (NaN, inf, far, absurdly high) sprinkled in.
CloudXYZIRT syntheticStreet(unsigned seed) {
  std::vector<test::Box> boxes = {
      {-30.f, 6.0f, 0.0f, 30.f, 7.0f, 12.0f, 1}, {-30.f, -8.0f, 0.0f, 30.f, -7.0f, 1.3f, 2},
      {4.f, 2.5f, 0.0f, 8.5f, 4.3f, 1.5f, 3},    {-9.f, -4.f, 0.0f, -5.f, -2.2f, 1.6f, 4},
      {-30.f, 4.0f, 0.0f, 30.f, 6.0f, 0.15f, 5},
  };
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(1.73f, boxes, &tags, 64, 1200);
  std::mt19937 rng(seed);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < cloud.size(); i += 97 + rng() % 50) {
    const float bad[4] = {nan, inf, 1e6f, 0.0f};
    const int k = static_cast<int>(rng() % 4);
    cloud[i].x = bad[k];
    if (k == 3) cloud[i].z = 500.0f;
  }
  return cloud;
}

// Random batch sizes: mostly a sector's worth, sometimes 0 or 1 point, sometimes a cut in the
// middle of a run; the last `keep` points are left for segment().
std::vector<std::size_t> randomSplit(std::size_t n, std::size_t keep, std::mt19937* rng) {
  std::vector<std::size_t> sizes;
  std::size_t done = 0;
  const std::size_t target = n > keep ? n - keep : 0;
  while (done < target) {
    std::size_t s;
    switch ((*rng)() % 5) {
      case 0:
        s = (*rng)() % 3;  // 0, 1 or 2 points
        break;
      case 1:
        s = 1 + (*rng)() % 37;
        break;
      default:
        s = 1 + (*rng)() % (n / 8 + 1);
        break;
    }
    s = std::min(s, target - done);
    sizes.push_back(s);
    done += s;
  }
  return sizes;
}

void expectSameSegmentation(const core::GridSegmenter& a, const std::vector<core::SegmentClass>& la,
                            const core::GridSegmenter& b, const std::vector<core::SegmentClass>& lb,
                            const std::string& what) {
  ASSERT_EQ(la, lb) << what;
  const core::SegmentationStats& sa = a.stats();
  const core::SegmentationStats& sb = b.stats();
  EXPECT_EQ(sa.points_unknown, sb.points_unknown) << what;
  EXPECT_EQ(sa.points_non_finite, sb.points_non_finite) << what;
  EXPECT_EQ(sa.points_clutter, sb.points_clutter) << what;
  EXPECT_EQ(sa.points_ground, sb.points_ground) << what;
  EXPECT_EQ(sa.points_tall, sb.points_tall) << what;
  EXPECT_EQ(sa.points_short, sb.points_short) << what;
  EXPECT_EQ(sa.cells_occupied, sb.cells_occupied) << what;
  EXPECT_EQ(sa.cells_ground_reached, sb.cells_ground_reached) << what;
  ASSERT_EQ(a.grid().occupiedCells().toVector(), b.grid().occupiedCells().toVector()) << what;
  const auto ca = a.grid().occupiedStats(), cb = b.grid().occupiedStats();
  for (std::size_t s = 0; s < ca.size(); ++s) {
    ASSERT_EQ(ca[s].count, cb[s].count) << what << " slot " << s;
    ASSERT_EQ(std::memcmp(&ca[s].z_min, &cb[s].z_min, 3 * sizeof(float)), 0)
        << what << " slot " << s;
  }
  ASSERT_EQ(a.grid().pointSlots(), b.grid().pointSlots()) << what;
  ASSERT_EQ(std::memcmp(a.grid().pointHeights().data(), b.grid().pointHeights().data(),
                        a.grid().pointHeights().size() * sizeof(float)),
            0)
      << what;
  for (const std::int32_t c : a.grid().occupiedCells()) {
    ASSERT_EQ(a.cellClasses()[c], b.cellClasses()[c]) << what << " cell " << c;
  }
}

// Streams every frame (random splits) through one segmenter and segments it whole with another,
// frames back to back, so stale state of the previous frame would show as a mismatch.
void checkStreamedEqualsWhole(std::vector<CloudXYZIRT> frames, unsigned seed,
                              const core::GridSegmenterParams& params = {}) {
  core::GridSegmenter streamed(params), whole(params);
  std::vector<core::SegmentClass> ls, lw;
  std::mt19937 rng(seed);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    CloudXYZIRT& cloud = frames[f];
    cloud.header.seq = static_cast<std::uint32_t>(f + 1);
    const std::size_t keep = rng() % 3 == 0 ? 0 : rng() % 2000;
    std::size_t at = 0;
    for (const std::size_t s : randomSplit(cloud.size(), keep, &rng)) {
      streamed.addPoints(cloud.header.seq, cloud.points.data() + at, s);
      at += s;
    }
    streamed.segment(cloud, &ls);
    EXPECT_EQ(streamed.lastUsedStream(), at > 0) << "frame " << f;
    whole.segment(cloud, &lw);
    EXPECT_FALSE(whole.lastUsedStream());
    expectSameSegmentation(streamed, ls, whole, lw, "frame " + std::to_string(f));
  }
}

// The early-objects chain's use: segmentSoFar() after every batch (the stream stays open)
// equals segment() of the points so far, and segment() of the whole cloud at the end equals
// it too, frames back to back.
void checkSoFarEqualsPrefix(std::vector<CloudXYZIRT> frames, unsigned seed) {
  core::GridSegmenter streamed, whole;
  std::vector<core::SegmentClass> ls, lw;
  std::mt19937 rng(seed);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    CloudXYZIRT& cloud = frames[f];
    cloud.header.seq = static_cast<std::uint32_t>(f + 1);
    std::size_t at = 0, batch = 0;
    for (const std::size_t s : randomSplit(cloud.size(), rng() % 2000, &rng)) {
      streamed.addPoints(cloud.header.seq, cloud.points.data() + at, s);
      at += s;
      if (s == 0 || ++batch % 3 != 0) continue;
      CloudXYZIRT prefix;
      prefix.header = cloud.header;
      prefix.points.assign(cloud.points.begin(), cloud.points.begin() + at);
      streamed.segmentSoFar(prefix, &ls);
      EXPECT_TRUE(streamed.lastUsedStream()) << "frame " << f << " batch " << batch;
      whole.segment(prefix, &lw);
      expectSameSegmentation(streamed, ls, whole, lw,
                             "frame " + std::to_string(f) + " after " + std::to_string(at));
    }
    streamed.segment(cloud, &ls);
    EXPECT_EQ(streamed.lastUsedStream(), at > 0) << "frame " << f;
    whole.segment(cloud, &lw);
    expectSameSegmentation(streamed, ls, whole, lw, "frame " + std::to_string(f));
  }
}

TEST(StreamingSegmentation, SegmentingSoFarThenAppendingEqualsThePrefixes) {
  checkSoFarEqualsPrefix({syntheticStreet(11), syntheticStreet(12)}, 5);
  checkSoFarEqualsPrefix(ud_test::simulatedRevolutions(2), 6);
}

TEST(StreamingSegmentation, SyntheticStreetsWithInvalidPointsEqualTheWholeCloud) {
  std::vector<CloudXYZIRT> frames;
  for (unsigned s = 0; s < 6; ++s) frames.push_back(syntheticStreet(s));
  checkStreamedEqualsWhole(frames, 1);
  core::GridSegmenterParams variant;  // the optional branches on
  variant.overhang_min_gap_m = 0.6;
  variant.thin_max_width_m = 0.3;
  variant.curb_cells_ground = true;
  checkStreamedEqualsWhole(frames, 2, variant);
}

TEST(StreamingSegmentation, SimulatedDriveEqualsTheWholeCloud) {
  checkStreamedEqualsWhole(ud_test::simulatedRevolutions(4), 3);
}

TEST(StreamingSegmentation, RealScansEqualTheWholeCloud) {
  const std::vector<CloudXYZIRT> frames = realScans(4);
  if (frames.empty()) GTEST_SKIP() << "no SemanticKITTI / KITTI raw scans in " << UD_SHARED_DATA;
  checkStreamedEqualsWhole(frames, 4);
}

// A lost batch, a batch of another revolution, points that are not the cloud's, a parameter
// change while streaming: segment() bins the whole cloud afresh and the result is unchanged.
TEST(StreamingSegmentation, MismatchedBatchesFallBackToTheWholeCloud) {
  std::vector<CloudXYZIRT> frames = {syntheticStreet(7), syntheticStreet(8), syntheticStreet(9)};
  core::GridSegmenter streamed, whole;
  std::vector<core::SegmentClass> ls, lw;
  for (std::size_t f = 0; f < frames.size(); ++f) frames[f].header.seq = 10 + f;
  const std::size_t third = frames[0].size() / 3;
  auto check = [&](const CloudXYZIRT& cloud, bool used, const std::string& what) {
    streamed.segment(cloud, &ls);
    EXPECT_EQ(streamed.lastUsedStream(), used) << what;
    whole.segment(cloud, &lw);
    expectSameSegmentation(streamed, ls, whole, lw, what);
  };
  // The middle batch lost: the count still fits, the third batch's first point does not.
  streamed.addPoints(10, frames[0].points.data(), third);
  streamed.addPoints(10, frames[0].points.data() + 2 * third, third);
  check(frames[0], false, "lost batch");
  // Batches of revolution 11 for the cloud of revolution 12.
  streamed.addPoints(11, frames[1].points.data(), third);
  check(frames[2], false, "other revolution");
  // The right seq, other points.
  streamed.addPoints(12, frames[1].points.data(), third);
  check(frames[2], false, "other points");
  // More points than the cloud has.
  streamed.addPoints(12, frames[2].points.data(), frames[2].size());
  streamed.addPoints(12, frames[2].points.data(), 5);
  check(frames[2], false, "too many points");
  // New parameters while streaming: binned with the old sensor height.
  core::GridSegmenterParams p = streamed.params();
  streamed.addPoints(10, frames[0].points.data(), third);
  p.sensor_height_m = 1.9;
  streamed.setParams(p);
  whole.setParams(p);
  check(frames[0], false, "new parameters");
  // A dropped partial revolution whose seq the next one gets again: its batches lie later in
  // the sweep, so the next revolution's first batch goes back in time and starts over.
  CloudXYZIRT timed = frames[1];
  for (std::size_t i = 0; i < timed.size(); ++i) timed[i].time = 1e-6f * static_cast<float>(i);
  timed.header.seq = 13;
  streamed.addPoints(13, timed.points.data() + 2 * third, third);
  streamed.addPoints(13, timed.points.data(), third);
  streamed.addPoints(13, timed.points.data() + third, third);
  check(timed, true, "partial revolution dropped");
  // Receipt-time jitter: each batch starts before the previous one ended (points of a burst of
  // packets), but after it started: one stream.
  for (std::size_t i = 0; i < timed.size(); ++i) {
    timed[i].time = 1e-6f * static_cast<float>(i % third) + 1e-4f * static_cast<float>(i / third);
  }
  timed.header.seq = 14;
  streamed.addPoints(14, timed.points.data(), third);
  streamed.addPoints(14, timed.points.data() + third, third);
  ASSERT_LT(timed[third].time, timed[third - 1].time);
  check(timed, true, "jittered times");
  // And streaming works again afterwards, on the same segmenter.
  streamed.addPoints(11, frames[1].points.data(), third);
  check(frames[1], true, "after the fallbacks");
  // An empty cloud and a stream of nothing.
  CloudXYZIRT empty;
  empty.header.seq = 99;
  streamed.addPoints(99, nullptr, 0);
  check(empty, true, "empty");
}

}  // namespace
}  // namespace urban_detection
