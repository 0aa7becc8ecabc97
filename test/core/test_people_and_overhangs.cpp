// People kept apart and upright: groups of people split by the hierarchical grid's step 7
// (group_splitter.h), short objects under an overhang kept short by the segmentation's step 5b
// (grid_segmenter.h), on ray-cast synthetic scenes with the KITTI HDL-64E's geometry.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "segmentation_scene.h"
#include "urban_detection/core/detection/group_splitter.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace {

using core::DetectedObject;
using core::GridSegmenter;
using core::GridSegmenterParams;
using core::HierarchicalGridDetector;
using core::HierarchicalGridDetectorParams;
using core::SegmentClass;

constexpr float kKittiHeight = 1.73f;

// A standing person facing the sensor along x: a 0.46 m wide, 0.28 m deep body up to the
// shoulders (0.82 of the stature) and a 0.2 m head up to `height`.
void addPerson(std::vector<test::Box>* boxes, float x, float y, int tag, float height = 1.75f) {
  const float shoulders = 0.82f * height;
  boxes->push_back({x - 0.14f, y - 0.23f, 0.0f, x + 0.14f, y + 0.23f, shoulders, tag});
  boxes->push_back({x - 0.1f, y - 0.1f, shoulders, x + 0.1f, y + 0.1f, height, tag});
}

// Ray-casts the boxes with an HDL-64E-like pattern (64 beams from -24.8 to +2 deg, 0.09 deg
// azimuth step), segments with `seg` and detects with `det`. `tags` receives per cloud point
// the box tag (0: ground).
std::vector<DetectedObject> detect(const std::vector<test::Box>& boxes,
                                   const GridSegmenterParams& seg,
                                   const HierarchicalGridDetectorParams& det,
                                   std::vector<int>* tags) {
  const CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, tags, 64, 4000);
  std::vector<SegmentClass> labels;
  GridSegmenter(seg).segment(cloud, &labels);
  LabeledCloud foreground;
  core::extractForeground(cloud, labels, &foreground);
  std::vector<DetectedObject> objects;
  HierarchicalGridDetector(det).detect(foreground, &objects);
  return objects;
}

// Tags found as objects of their own: an object whose points are more than 80 % one tag's and
// hold more than 80 % of that tag's points among all objects' points.
std::vector<int> separatedTags(const std::vector<DetectedObject>& objects,
                               const std::vector<int>& tags) {
  std::map<int, std::size_t> in_objects;
  for (const auto& o : objects) {
    for (const std::uint32_t i : o.indices) ++in_objects[tags[i]];
  }
  std::vector<int> found;
  for (const auto& o : objects) {
    std::map<int, std::size_t> count;
    for (const std::uint32_t i : o.indices) ++count[tags[i]];
    for (const auto& kv : count) {
      if (kv.first > 0 && kv.second > 0.8 * o.indices.size() &&
          kv.second > 0.8 * in_objects[kv.first]) {
        found.push_back(kv.first);
      }
    }
  }
  std::sort(found.begin(), found.end());
  return found;
}

HierarchicalGridDetectorParams splitOff() {
  HierarchicalGridDetectorParams p;
  p.group_split.min_length_m = 0.0;
  return p;
}

// The hierarchical grid with step 7 on (shipped off, see config/hierarchical_grid.yaml).
HierarchicalGridDetectorParams splitOn() {
  HierarchicalGridDetectorParams p;
  p.group_split.min_length_m = 1.0;
  return p;
}

TEST(GroupSplitter, TwoAndThreePeopleSideBySideAreSplitIntoOneObjectEach) {
  for (const float spacing : {0.6f, 0.7f, 0.8f}) {
    for (const int people : {2, 3}) {
      for (const float range : {8.0f, 15.0f}) {
        std::vector<test::Box> boxes;
        for (int k = 0; k < people; ++k) {
          addPerson(&boxes, range, spacing * (k - 0.5f * (people - 1)), k + 1,
                    k == 1 ? 1.65f : 1.8f);
        }
        const std::string what = std::to_string(people) + " people " + std::to_string(spacing) +
                                 " m apart at " + std::to_string(range) + " m";
        std::vector<int> tags;
        std::vector<int> all;
        for (int k = 1; k <= people; ++k) all.push_back(k);
        // The scene is what the rule is for: without it the group is one object.
        const auto merged = detect(boxes, GridSegmenterParams(), splitOff(), &tags);
        EXPECT_LT(separatedTags(merged, tags).size(), all.size()) << what << ", rule off";
        const auto split = detect(boxes, GridSegmenterParams(), splitOn(), &tags);
        EXPECT_EQ(separatedTags(split, tags), all) << what;
        EXPECT_EQ(split.size(), all.size()) << what;
      }
    }
  }
}

TEST(GroupSplitter, OnePersonACarAndACyclistStayWhole) {
  std::vector<test::Box> boxes;
  addPerson(&boxes, 9.0f, -4.0f, 1);
  // A 4.4 x 1.8 m car: body to 0.95 m, a 2.2 m cabin to 1.48 m.
  boxes.push_back({8.0f, 1.0f, 0.25f, 12.4f, 2.8f, 0.95f, 2});
  boxes.push_back({9.2f, 1.1f, 0.95f, 11.4f, 2.7f, 1.48f, 2});
  // A cyclist riding across the line of sight: wheels and frame to 1.0 m, 1.75 m long, the
  // rider's body above the saddle and the arms forward to the handlebar.
  boxes.push_back({14.95f, -6.0f, 0.0f, 15.05f, -4.25f, 1.0f, 3});
  boxes.push_back({14.85f, -5.5f, 1.0f, 15.15f, -5.2f, 1.55f, 3});
  boxes.push_back({14.9f, -5.45f, 1.55f, 15.1f, -5.25f, 1.8f, 3});
  boxes.push_back({14.8f, -5.2f, 1.2f, 15.2f, -4.4f, 1.3f, 3});
  std::vector<int> tags;
  const auto objects = detect(boxes, GridSegmenterParams(), splitOn(), &tags);
  EXPECT_EQ(separatedTags(objects, tags), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(objects.size(), 3u);
}

TEST(GroupSplitter, RejectsInconsistentParameters) {
  core::GroupSplitterParams p;
  EXPECT_EQ(core::validate(p), "");
  p.min_length_m = 1.0;
  EXPECT_EQ(core::validate(p), "");
  p.max_length_m = 0.5;
  EXPECT_NE(core::validate(p), "");
  EXPECT_THROW(core::GroupSplitter{p}, std::invalid_argument);
  p.min_length_m = 0.0;  // off: the length range is not used
  EXPECT_EQ(core::validate(p), "");
}

// The segmentation with step 5b on (shipped off, see config/segmentation.yaml).
GridSegmenterParams rulesOn() {
  GridSegmenterParams p;
  p.overhang_min_gap_m = 0.6;
  p.thin_max_width_m = 0.3;
  return p;
}

// Share of the points of box `tag` more than 0.16 m above the ground labelled `cls`.
double shareOf(const CloudXYZIRT& cloud, const std::vector<int>& tags,
               const std::vector<SegmentClass>& labels, int tag, SegmentClass cls) {
  int n = 0, k = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (tags[i] != tag || cloud[i].z + kKittiHeight < 0.16f) continue;
    ++n;
    k += labels[i] == cls;
  }
  return n == 0 ? -1.0 : static_cast<double>(k) / n;
}

TEST(GridSegmenterOverhang, PersonUnderATreeCanopyIsShortAndTheTreeTall) {
  // A tree 30 m ahead: a crown from 2.4 to 3.4 m over 27.6-31 m (its near face is what the top
  // rings see), a trunk; a person under the crown's near edge, in the same cells as the face.
  std::vector<test::Box> boxes = {{27.6f, -2.0f, 2.4f, 31.0f, 2.0f, 3.4f, 1},
                                  {29.8f, -0.2f, 0.0f, 30.2f, 0.2f, 2.4f, 2}};
  addPerson(&boxes, 27.85f, 0.8f, 3);
  std::vector<int> tags;
  const CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags, 64, 4000);
  GridSegmenterParams p = rulesOn();
  std::vector<SegmentClass> labels;
  p.overhang_min_gap_m = 0.0;
  GridSegmenter(p).segment(cloud, &labels);
  ASSERT_GT(shareOf(cloud, tags, labels, 3, SegmentClass::kTall), 0.5) << "the rule's case";
  GridSegmenter seg(rulesOn());
  seg.segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 3, SegmentClass::kShort), 0.95);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kTall), 0.95);
  EXPECT_GT(shareOf(cloud, tags, labels, 2, SegmentClass::kTall), 0.95);
  // Beyond overhang_max_range_m a gap may be missing scan rings: the rule stays out.
  p = rulesOn();
  p.overhang_max_range_m = 25.0;
  GridSegmenter(p).segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 3, SegmentClass::kTall), 0.5);
}

TEST(GridSegmenterOverhang, PersonBesideAPoleIsShortAndThePoleTall) {
  // A 4 m pole, 0.15 m thick, 12 m ahead; a person 7 cm beside it, in the same 0.5 m cells.
  std::vector<test::Box> boxes = {{12.0f, 3.0f, 0.0f, 12.15f, 3.15f, 4.0f, 1}};
  addPerson(&boxes, 12.25f, 3.45f, 2);
  std::vector<int> tags;
  const CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags, 64, 4000);
  std::vector<SegmentClass> labels;
  GridSegmenterParams p = rulesOn();
  p.thin_max_width_m = 0.0;
  GridSegmenter(p).segment(cloud, &labels);
  ASSERT_GT(shareOf(cloud, tags, labels, 2, SegmentClass::kTall), 0.3) << "the rule's case";
  GridSegmenter seg(rulesOn());
  seg.segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 2, SegmentClass::kShort), 0.9);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kTall), 0.99);
}

TEST(GridSegmenterOverhang, FacadeWithAPersonInFrontStaysTallAndThePersonShort) {
  // No empty band and no thin top: a facade (continuous from the ground) stays tall, wholly;
  // a person 1 m in front of it is short (its cells are its own).
  std::vector<test::Box> boxes = {{20.0f, -10.0f, 0.0f, 20.4f, 10.0f, 6.0f, 1}};
  addPerson(&boxes, 18.8f, -2.0f, 2);
  std::vector<int> tags;
  const CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags, 64, 4000);
  std::vector<SegmentClass> labels;
  GridSegmenter seg(rulesOn());
  seg.segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kTall), 0.99);
  EXPECT_GT(shareOf(cloud, tags, labels, 2, SegmentClass::kShort), 0.95);
}

TEST(GridSegmenterLongVehicles, VanSeenToTheTopOfTheFieldOfViewIsShortWithTheNearRule) {
  // A 5 x 2 x 2.4 m van crossing 12 m ahead: the +2 deg ring hits its side at 2.15 m, so its
  // roof is not seen and its cells reach the upper edge of the field of view, as a facade's
  // would. With vehicle_fov_test_near off that test is left to the Hough refinement inside its
  // window for groups as long as a van; a 4 m pole keeps it and stays tall.
  std::vector<test::Box> boxes = {{12.0f, -2.5f, 0.3f, 14.0f, 2.5f, 2.4f, 1},
                                  {9.0f, 6.0f, 0.0f, 9.15f, 6.15f, 4.0f, 2}};
  std::vector<int> tags;
  const CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags, 64, 4000);
  std::vector<SegmentClass> labels;
  GridSegmenterParams p;  // shipped: the test everywhere
  GridSegmenter(p).segment(cloud, &labels);
  ASSERT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kTall), 0.5) << "the rule's case";
  p.vehicle_fov_test_near = false;
  GridSegmenter seg(p);
  seg.segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kShort), 0.95);
  EXPECT_GT(shareOf(cloud, tags, labels, 2, SegmentClass::kTall), 0.99);
}

}  // namespace
}  // namespace urban_detection
