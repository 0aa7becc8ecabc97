// A deterministic 2-million-point revolution through segmentation and both detectors,
// with non-finite, huge and out-of-grid points interleaved and
// 3000 points in a single grid cell. Expected labels and objects come from how the scene was
// built, not from running the code: the lattice is ground, the car box and the post are the
// only short objects, every hostile point is unknown and in no object.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace {

enum Tag : std::uint8_t { kTagGround, kTagCar, kTagPost, kTagHostile };

constexpr std::size_t kTotalPoints = 2000000;
constexpr float kGroundZ = -1.73f;  // sensor 1.73 m above a flat road

struct Scene {
  CloudXYZIRT cloud;
  std::vector<Tag> tags;
};

void add(Scene* s, float x, float y, float z, Tag tag) {
  s->cloud.push_back(makePoint(x, y, z, 10.0f));
  s->tags.push_back(tag);
}

Scene buildScene() {
  Scene s;
  s.cloud.reserve(kTotalPoints);
  // Car: 4 m x 1.8 m box from 0.3 m to 1.5 m above the road, centred at (10, 6); its four
  // sides and roof sampled every 4 cm.
  const float x0 = 8.0f, x1 = 12.0f, y0 = 5.1f, y1 = 6.9f, z0 = kGroundZ + 0.3f,
              z1 = kGroundZ + 1.5f;
  for (float z = z0; z <= z1 + 1e-4f; z += 0.04f) {
    for (float x = x0; x <= x1 + 1e-4f; x += 0.04f) {
      add(&s, x, y0, z, kTagCar);
      add(&s, x, y1, z, kTagCar);
    }
    for (float y = y0 + 0.04f; y < y1 - 1e-4f; y += 0.04f) {
      add(&s, x0, y, z, kTagCar);
      add(&s, x1, y, z, kTagCar);
    }
  }
  for (float x = x0 + 0.04f; x < x1 - 1e-4f; x += 0.04f) {
    for (float y = y0 + 0.04f; y < y1 - 1e-4f; y += 0.04f) add(&s, x, y, z1, kTagCar);
  }
  // Post: 3000 points in a 10 cm column 0.3-1.0 m above the road, all in one 0.5 m grid cell.
  for (int k = 0; k < 3000; ++k) {
    add(&s, -8.2f + 0.001f * static_cast<float>(k % 100),
        -8.2f + 0.01f * static_cast<float>(k % 10),
        kGroundZ + 0.3f + 0.7f * static_cast<float>(k) / 3000.0f, kTagPost);
  }
  // Hostile points: NaN, +-inf, 1e30 and far outside the grid, 10000 of each kind.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 10000; ++k) {
    const float f = static_cast<float>(k % 100) * 0.1f;
    add(&s, nan, f, kGroundZ, kTagHostile);
    add(&s, f, -inf, kGroundZ + 0.5f, kTagHostile);
    add(&s, 1e30f, f, kGroundZ + 0.5f, kTagHostile);
    add(&s, f, f, -1e30f, kTagHostile);
    add(&s, 1e5f, -f, kGroundZ + 0.5f, kTagHostile);
  }
  // Road: the rest, a flat 8 cm lattice of 1400 points per row starting at (-56, -56).
  const std::size_t ground = kTotalPoints - s.cloud.size();
  for (std::size_t i = 0; i < ground; ++i) {
    add(&s, -56.0f + 0.08f * static_cast<float>(i % 1400),
        -56.0f + 0.08f * static_cast<float>(i / 1400), kGroundZ, kTagGround);
  }
  // A fixed shuffle, so hostile points sit between valid ones as dropouts would.
  std::vector<std::size_t> order(s.cloud.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(8));
  Scene out;
  out.cloud.reserve(order.size());
  for (const std::size_t i : order) {
    out.cloud.push_back(s.cloud[i]);
    out.tags.push_back(s.tags[i]);
  }
  return out;
}

std::vector<std::uint32_t> indicesTagged(const Scene& s, Tag tag) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < s.tags.size(); ++i) {
    if (s.tags[i] == tag) out.push_back(static_cast<std::uint32_t>(i));
  }
  return out;
}

// Objects sorted by their first index, each with sorted indices.
std::vector<std::vector<std::uint32_t>> partition(const std::vector<core::DetectedObject>& objs) {
  std::vector<std::vector<std::uint32_t>> out;
  for (const core::DetectedObject& o : objs) {
    out.push_back(o.indices);
    std::sort(out.back().begin(), out.back().end());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(LargeHostileCloud, TwoMillionPointsSegmentAndDetectExactly) {
  const Scene scene = buildScene();
  ASSERT_EQ(scene.cloud.size(), kTotalPoints);

  core::GridSegmenter segmenter;
  std::vector<core::SegmentClass> labels;
  segmenter.segment(scene.cloud, &labels);
  ASSERT_EQ(labels.size(), kTotalPoints);
  std::size_t wrong[4] = {0, 0, 0, 0};
  const core::SegmentClass expected[4] = {core::SegmentClass::kGround, core::SegmentClass::kShort,
                                          core::SegmentClass::kShort, core::SegmentClass::kUnknown};
  for (std::size_t i = 0; i < kTotalPoints; ++i) {
    if (labels[i] != expected[scene.tags[i]]) ++wrong[scene.tags[i]];
  }
  EXPECT_EQ(wrong[kTagGround], 0u) << "road points not labelled ground";
  EXPECT_EQ(wrong[kTagCar], 0u) << "car points not labelled short";
  EXPECT_EQ(wrong[kTagPost], 0u) << "post points not labelled short";
  EXPECT_EQ(wrong[kTagHostile], 0u) << "non-finite / out-of-grid points not unknown";

  LabeledCloud foreground;
  core::extractForeground(scene.cloud, labels, &foreground);
  const std::vector<std::uint32_t> car = indicesTagged(scene, kTagCar);
  const std::vector<std::uint32_t> post = indicesTagged(scene, kTagPost);
  EXPECT_EQ(foreground.size(), car.size() + post.size());
  std::vector<std::vector<std::uint32_t>> expected_objects{car, post};
  std::sort(expected_objects.begin(), expected_objects.end());

  std::vector<core::DetectedObject> objects;
  core::HierarchicalGridDetector grid;
  grid.detect(foreground, &objects);
  EXPECT_EQ(partition(objects), expected_objects)
      << "hierarchical grid: " << objects.size() << " objects";
  core::KdTreeDetector kdtree;
  kdtree.detect(foreground, &objects);
  EXPECT_EQ(partition(objects), expected_objects) << "kd-tree: " << objects.size() << " objects";

  // The whole hostile cloud straight into the detectors (no segmentation): the hostile points
  // are ignored and counted, nothing crashes.
  LabeledCloud all;
  all.resize(kTotalPoints);
  for (std::size_t i = 0; i < kTotalPoints; ++i) {
    all[i].x = scene.cloud[i].x;
    all[i].y = scene.cloud[i].y;
    all[i].z = scene.cloud[i].z;
    all[i].index = static_cast<std::uint32_t>(i);
  }
  grid.detect(all, &objects);
  EXPECT_EQ(grid.stats().invalid_points + grid.stats().outside_points, 50000u);
  for (const core::DetectedObject& o : objects) {
    for (const std::uint32_t i : o.indices) ASSERT_NE(scene.tags[i], kTagHostile);
  }
}

}  // namespace
}  // namespace urban_detection
