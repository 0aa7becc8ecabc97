// Step 6 of the hierarchical grid (far_object_merger.h): far pieces of one
// vehicle join; near pieces, pieces too far apart along or across the line of
// sight, and groups that would be longer or wider than a vehicle stay apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "detection_test_utils.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/far_object_merger.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/object_geometry.h"

namespace urban_detection {
namespace {

using core::DetectedObject;
using core::FarObjectMerger;
using core::FarObjectMergerParams;
using test::addPoint;

// A vertical face across the line of sight along +x: at distance x, y in [y0,
// y1], z in [z0, z1] (sensor frame, road at -1.73), points every 0.1 m; label
// `truth`.
void addFace(LabeledCloud* cloud, float x, float y0, float y1, float z0, float z1,
             std::uint32_t truth) {
  const int ny = static_cast<int>(std::lround((y1 - y0) / 0.1f));
  const int nz = static_cast<int>(std::lround((z1 - z0) / 0.1f));
  for (int i = 0; i <= ny; ++i) {
    for (int k = 0; k <= nz; ++k) {
      addPoint(cloud, x, i == ny ? y1 : y0 + 0.1f * i, k == nz ? z1 : z0 + 0.1f * k, truth);
    }
  }
}

// One object per label (labels 1..), in label order, geometry by
// ObjectGeometry.
std::vector<DetectedObject> objectsByLabel(const LabeledCloud& cloud) {
  std::vector<DetectedObject> objects;
  core::ObjectGeometry geometry;
  for (std::uint32_t label = 1;; ++label) {
    std::vector<std::uint32_t> pos;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (cloud.points[i].label == label) pos.push_back(static_cast<std::uint32_t>(i));
    }
    if (pos.empty()) break;
    DetectedObject o;
    geometry.compute(cloud, pos, &o);
    for (const std::uint32_t p : pos) o.indices.push_back(cloud.points[p].index);
    o.id = label;
    objects.push_back(o);
  }
  return objects;
}

// A car seen end-on from behind at distance x: the lower body's rear face (1.8
// m wide, 0.6 m high) and, `gap_m` farther, the cabin's rear face (1.4 m wide,
// above the body's top).
void addEndOnCar(LabeledCloud* cloud, float x, float y, float gap_m, std::uint32_t body,
                 std::uint32_t cabin) {
  addFace(cloud, x, y - 0.9f, y + 0.9f, -1.7f, -1.1f, body);
  addFace(cloud, x + gap_m, y - 0.7f, y + 0.7f, -0.8f, -0.45f, cabin);
}

std::size_t merge(const LabeledCloud& cloud, std::vector<DetectedObject>* objects,
                  const FarObjectMergerParams& p = FarObjectMergerParams()) {
  FarObjectMerger merger(p);
  return merger.apply(cloud, objects);
}

TEST(FarObjectMerger, JoinsBodyAndCabinOfAFarCarSeenEndOn) {
  LabeledCloud cloud;
  addEndOnCar(&cloud, 45.0f, 0.0f, 1.1f, 1, 2);
  std::vector<DetectedObject> objects = objectsByLabel(cloud);
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(merge(cloud, &objects), 1u);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].id, 1u);
  EXPECT_EQ(objects[0].indices.size(), cloud.size());
  // Geometry of the joined points: the box spans both faces.
  EXPECT_NEAR(objects[0].min_pt.x(), 45.0f, 1e-4f);
  EXPECT_NEAR(objects[0].max_pt.x(), 46.1f, 1e-4f);
  EXPECT_NEAR(objects[0].max_pt.z(), -0.45f, 1e-4f);
  EXPECT_NEAR(objects[0].obb_size.x(), 1.8f, 0.06f);
  EXPECT_NEAR(objects[0].obb_size.y(), 1.1f, 0.06f);
}

TEST(FarObjectMerger, OffNearOrTooFarApartStaysApart) {
  LabeledCloud far_car;
  addEndOnCar(&far_car, 45.0f, 0.0f, 1.1f, 1, 2);
  std::vector<DetectedObject> objects = objectsByLabel(far_car);
  FarObjectMergerParams off;
  off.max_gap_m = 0.0;
  EXPECT_EQ(merge(far_car, &objects, off), 0u);
  EXPECT_EQ(objects.size(), 2u);

  LabeledCloud near_car;  // same car at 20 m: below min_range_m (30 m)
  addEndOnCar(&near_car, 20.0f, 0.0f, 1.1f, 1, 2);
  objects = objectsByLabel(near_car);
  EXPECT_EQ(merge(near_car, &objects), 0u);
  EXPECT_EQ(objects.size(), 2u);

  LabeledCloud long_gap;  // 1.6 m between the faces: more than max_gap_m (1.2)
  addEndOnCar(&long_gap, 45.0f, 0.0f, 1.6f, 1, 2);
  objects = objectsByLabel(long_gap);
  EXPECT_EQ(merge(long_gap, &objects), 0u);
  EXPECT_EQ(objects.size(), 2u);

  LabeledCloud high;  // the second piece 0.8 m above the first's top: more than
                      // max_z_gap_m
  addFace(&high, 45.0f, -0.9f, 0.9f, -1.7f, -1.1f, 1);
  addFace(&high, 46.0f, -0.7f, 0.7f, -0.3f, 0.0f, 2);
  objects = objectsByLabel(high);
  EXPECT_EQ(merge(high, &objects), 0u);
}

TEST(FarObjectMerger, EndOnCarsSideBySideStayApart) {
  // Two cars seen end-on at 37 m, 1.0 m apart across the line of sight:
  // together they would fit the vehicle box (4.6 m x 1.1 m), but the gap across
  // is more than max_across_gap_m.
  LabeledCloud cloud;
  addEndOnCar(&cloud, 37.0f, -1.4f, 1.1f, 1, 2);
  addEndOnCar(&cloud, 37.0f, 1.4f, 1.1f, 3, 4);
  std::vector<DetectedObject> objects = objectsByLabel(cloud);
  ASSERT_EQ(objects.size(), 4u);
  EXPECT_EQ(merge(cloud, &objects), 2u);  // each car's body and cabin
  ASSERT_EQ(objects.size(), 2u);
  test::Partition cars;
  for (std::uint32_t car = 0; car < 2; ++car) {
    std::set<std::uint32_t> pts;
    for (const LabeledPoint& q : cloud.points) {
      if ((q.label + 1) / 2 == car + 1) pts.insert(q.index);
    }
    cars.insert(pts);
  }
  EXPECT_EQ(test::partitionOf(objects), cars);
  for (const DetectedObject& o : objects) {
    EXPECT_LT(o.obb_size.x(), 2.0f);  // one car each, not both
  }
  // With gaps across allowed up to 1.2 m, the pairs join into one 4.6 m wide
  // group.
  FarObjectMergerParams wide;
  wide.max_across_gap_m = 1.2;
  objects = objectsByLabel(cloud);
  EXPECT_EQ(merge(cloud, &objects, wide), 3u);
  EXPECT_EQ(objects.size(), 1u);
}

TEST(FarObjectMerger, NeighbourBesideRatherThanBehindStaysApart) {
  // A car's rear face at 40 m (y in [-0.9, 0.9]) and, 1 m farther, a person-sized object at
  // y in [0.6, 1.4]: they overlap across the line of sight by 0.3 m, 0.375 of the narrower box,
  // less than min_across_overlap (0.5): beside, not behind. Joined they would fit the box.
  LabeledCloud cloud;
  addFace(&cloud, 40.0f, -0.9f, 0.9f, -1.7f, -1.1f, 1);
  addFace(&cloud, 41.0f, 0.6f, 1.4f, -1.7f, -0.2f, 2);
  std::vector<DetectedObject> objects = objectsByLabel(cloud);
  EXPECT_EQ(merge(cloud, &objects), 0u);
  EXPECT_EQ(objects.size(), 2u);
  FarObjectMergerParams any_overlap;
  any_overlap.min_across_overlap = 0.0;
  objects = objectsByLabel(cloud);
  EXPECT_EQ(merge(cloud, &objects, any_overlap), 1u);
  EXPECT_EQ(objects.size(), 1u);
}

TEST(FarObjectMerger, GroupLongerThanAVehicleStaysApart) {
  // Three 1.9 m long pieces along the line of sight, 1.1 m apart: two fit (4.9
  // m), three do not.
  LabeledCloud cloud;
  for (std::uint32_t k = 0; k < 3; ++k) {
    const float x0 = 40.0f + 3.0f * k;
    for (int i = 0; i <= 19; ++i) {
      for (int j = 0; j <= 4; ++j) {
        addPoint(&cloud, x0 + 0.1f * i, 0.0f, -1.6f + 0.2f * j, k + 1);
        addPoint(&cloud, x0 + 0.1f * i, 1.0f, -1.6f + 0.2f * j, k + 1);
      }
    }
  }
  std::vector<DetectedObject> objects = objectsByLabel(cloud);
  ASSERT_EQ(objects.size(), 3u);
  EXPECT_EQ(merge(cloud, &objects), 1u);
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_NEAR(objects[0].obb_size.x(), 4.9f, 0.06f);  // pieces 1 and 2
  EXPECT_NEAR(objects[1].obb_size.x(), 1.9f, 0.06f);  // piece 3 alone
  EXPECT_EQ(objects[0].id, 1u);
  EXPECT_EQ(objects[1].id, 2u);
}

TEST(FarObjectMerger, KeepsOrderAndNearObjects) {
  LabeledCloud cloud;
  addFace(&cloud, 8.0f, -0.3f, 0.3f, -1.7f, 0.0f,
          1);  // a near pedestrian, first
  addEndOnCar(&cloud, 45.0f, 0.0f, 1.1f, 2, 3);
  addFace(&cloud, 9.0f, 2.0f, 2.5f, -1.7f, -0.5f, 4);  // a near bin, last
  std::vector<DetectedObject> objects = objectsByLabel(cloud);
  const std::vector<DetectedObject> before = objects;
  ASSERT_EQ(merge(cloud, &objects), 1u);
  ASSERT_EQ(objects.size(), 3u);
  EXPECT_EQ(objects[0].indices, before[0].indices);
  EXPECT_EQ(objects[1].indices.size(), before[1].indices.size() + before[2].indices.size());
  EXPECT_EQ(objects[2].indices, before[3].indices);
  for (std::size_t k = 0; k < objects.size(); ++k) EXPECT_EQ(objects[k].id, k + 1);
}

// The joined object's geometry is that of the members' points, found by their `index` in the
// foreground, whether the foreground is in index order with gaps (the positions are looked up
// from the previous point's, then by binary search) or shuffled (searched linearly).
TEST(FarObjectMerger, JoinedGeometryReadsThePointsByIndexInAnyForegroundOrder) {
  for (const bool shuffled : {false, true}) {
    LabeledCloud car;
    addFace(&car, 8.0f, -0.3f, 0.3f, -1.7f, 0.0f, 3);  // a near pedestrian between the pieces
    addEndOnCar(&car, 45.0f, 0.0f, 1.1f, 1, 2);
    // Indices with gaps; the pedestrian's points come first in index order.
    for (std::size_t i = 0; i < car.size(); ++i) {
      car.points[i].index = static_cast<std::uint32_t>(3 * i + 7);
    }
    std::vector<LabeledPoint> pts(car.points.begin(), car.points.end());
    std::mt19937 rng(11);
    if (shuffled) {
      std::shuffle(pts.begin(), pts.end(), rng);
    } else {
      std::sort(pts.begin(), pts.end(),
                [](const LabeledPoint& a, const LabeledPoint& b) { return a.index < b.index; });
    }
    LabeledCloud cloud;
    for (const LabeledPoint& p : pts) cloud.push_back(p);
    std::vector<DetectedObject> objects = objectsByLabel(cloud);
    ASSERT_EQ(objects.size(), 3u);
    const std::vector<std::uint32_t> body = objects[0].indices, cabin = objects[1].indices;
    ASSERT_EQ(merge(cloud, &objects), 1u) << shuffled;
    ASSERT_EQ(objects.size(), 2u);
    // The same points, in the members' order, by position.
    std::vector<std::uint32_t> pos;
    for (const std::vector<std::uint32_t>* member : {&body, &cabin}) {
      for (const std::uint32_t index : *member) {
        for (std::size_t i = 0; i < cloud.size(); ++i) {
          if (cloud.points[i].index == index) pos.push_back(static_cast<std::uint32_t>(i));
        }
      }
    }
    ASSERT_EQ(pos.size(), body.size() + cabin.size());
    DetectedObject expected;
    core::ObjectGeometry().compute(cloud, pos, &expected);
    const DetectedObject& joined = objects[0];
    EXPECT_EQ(joined.indices.size(), pos.size());
    EXPECT_EQ(joined.centroid, expected.centroid) << shuffled;
    EXPECT_EQ(joined.min_pt, expected.min_pt) << shuffled;
    EXPECT_EQ(joined.max_pt, expected.max_pt) << shuffled;
    EXPECT_EQ(joined.obb_center, expected.obb_center) << shuffled;
    EXPECT_EQ(joined.obb_size, expected.obb_size) << shuffled;
    EXPECT_EQ(joined.obb_yaw_rad, expected.obb_yaw_rad) << shuffled;
  }
}

TEST(FarObjectMerger, ValidatesItsParameters) {
  FarObjectMergerParams p;
  EXPECT_EQ(core::validate(p), "");
  p.max_gap_m = -0.1;
  EXPECT_NE(core::validate(p).find("max_gap_m"), std::string::npos);
  EXPECT_THROW(FarObjectMerger{p}, std::invalid_argument);
  p = FarObjectMergerParams();
  p.max_width_m = p.max_length_m + 1.0;
  const std::string order = core::validate(p);
  EXPECT_NE(order.find("'max_width_m'"), std::string::npos) << order;
  EXPECT_NE(order.find("must be at most 'max_length_m'"), std::string::npos) << order;
  p.max_width_m = p.max_length_m;  // equal is in order
  EXPECT_EQ(core::validate(p), "");
  core::HierarchicalGridDetectorParams h;
  h.far_merge.max_z_gap_m = -1.0;
  EXPECT_NE(core::validate(h).find("far_merge/max_z_gap_m"), std::string::npos);
}

// The pair rule of far_object_merger.h evaluated plainly, by projecting the four corners of
// each oriented box on the line of sight and across it; `slack` receives how far the pair is
// from the nearest threshold (its outcome is then unambiguous under rounding when > 1e-3).
bool pairRule(const DetectedObject& a, const DetectedObject& b, const FarObjectMergerParams& p,
              double* slack) {
  const Eigen::Vector2d mid = 0.5 * (a.centroid.head<2>() + b.centroid.head<2>()).cast<double>();
  const Eigen::Vector2d u = mid.normalized(), v(-u.y(), u.x());
  auto interval = [](const DetectedObject& o, const Eigen::Vector2d& d) {
    const Eigen::Vector2d ax(std::cos(o.obb_yaw_rad), std::sin(o.obb_yaw_rad)), ay(-ax.y(), ax.x());
    double lo = 1e9, hi = -1e9;
    for (const double sa : {-0.5, 0.5}) {
      for (const double sb : {-0.5, 0.5}) {
        const Eigen::Vector2d corner = o.obb_center.head<2>().cast<double>() +
                                       sa * o.obb_size.x() * ax + sb * o.obb_size.y() * ay;
        lo = std::min(lo, corner.dot(d));
        hi = std::max(hi, corner.dot(d));
      }
    }
    return Eigen::Vector2d(lo, hi);
  };
  const Eigen::Vector2d ua = interval(a, u), ub = interval(b, u);
  const Eigen::Vector2d va = interval(a, v), vb = interval(b, v);
  const double along = std::max(0.0, std::max(ua.x(), ub.x()) - std::min(ua.y(), ub.y()));
  const double across_raw = std::max(va.x(), vb.x()) - std::min(va.y(), vb.y());
  const double across = std::max(0.0, across_raw);
  const double overlap = -across_raw;
  const double narrower = std::min(va.y() - va.x(), vb.y() - vb.x());
  const double z_gap = std::max(a.min_pt.z(), b.min_pt.z()) - std::min(a.max_pt.z(), b.max_pt.z());
  *slack = std::min({std::fabs(along - p.max_gap_m), std::fabs(across_raw - p.max_across_gap_m),
                     std::fabs(across_raw), std::fabs(overlap - p.min_across_overlap * narrower),
                     std::fabs(z_gap - p.max_z_gap_m)});
  const bool behind = across > 0.0 || overlap >= p.min_across_overlap * narrower;
  return along <= p.max_gap_m && across <= p.max_across_gap_m && behind && z_gap <= p.max_z_gap_m;
}

// Two far pieces at random distances, bearings, sizes, yaws and offsets (some pairs far
// apart, many near, rotated so that the boxes' corners reach towards each other): the merger
// joins them exactly when the rule, evaluated plainly, accepts the pair and the joined box fits
// a vehicle. Its shortcuts (axes computed once per object, pairs whose box centres are too far
// apart for any gap within the limits skipped before any projection) change no decision.
TEST(FarObjectMerger, JoinsExactlyThePairsThePlainRuleAccepts) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  int joined = 0, apart = 0;
  for (int trial = 0; trial < 600; ++trial) {
    FarObjectMergerParams p;
    if (trial % 3 == 1) p.max_across_gap_m = 0.6;  // gaps across allowed too
    if (trial % 3 == 2) p.max_gap_m = 2.5;
    const float range = 32.0f + 30.0f * unit(rng), bearing = 6.2832f * unit(rng);
    const float cx = range * std::cos(bearing), cy = range * std::sin(bearing);
    const float offset = 4.5f * unit(rng), dir = 6.2832f * unit(rng);
    LabeledCloud cloud;
    for (std::uint32_t piece = 1; piece <= 2; ++piece) {
      const float x = piece == 1 ? cx : cx + offset * std::cos(dir);
      const float y = piece == 1 ? cy : cy + offset * std::sin(dir);
      const float len = 0.3f + 2.2f * unit(rng), wid = 0.2f + 1.2f * unit(rng);
      const float yaw = 3.1416f * unit(rng), z0 = -1.7f + 0.9f * unit(rng);
      const float c = std::cos(yaw), s = std::sin(yaw);
      for (int i = 0; i <= 8; ++i) {
        for (int k = 0; k <= 4; ++k) {
          const float a = len * (i / 8.0f - 0.5f), b = wid * (k / 4.0f - 0.5f);
          addPoint(&cloud, x + a * c - b * s, y + a * s + b * c, z0 + 0.1f * ((i + k) % 5), piece);
        }
      }
    }
    std::vector<DetectedObject> objects = objectsByLabel(cloud);
    ASSERT_EQ(objects.size(), 2u);
    double slack = 0.0;
    bool expected = pairRule(objects[0], objects[1], p, &slack);
    if (expected) {  // the joined group must still fit a vehicle box
      DetectedObject all;
      std::vector<std::uint32_t> pos(cloud.size());
      for (std::size_t i = 0; i < pos.size(); ++i) pos[i] = static_cast<std::uint32_t>(i);
      core::ObjectGeometry().compute(cloud, pos, &all);
      slack = std::min({slack, std::fabs(all.obb_size.x() - p.max_length_m),
                        std::fabs(all.obb_size.y() - p.max_width_m)});
      expected = all.obb_size.x() <= p.max_length_m && all.obb_size.y() <= p.max_width_m;
    }
    if (slack < 1e-3) continue;  // too close to a threshold for rounding to be ignored
    EXPECT_EQ(merge(cloud, &objects, p), expected ? 1u : 0u) << "trial " << trial;
    EXPECT_EQ(objects.size(), expected ? 1u : 2u) << "trial " << trial;
    (expected ? joined : apart) += 1;
  }
  EXPECT_GT(joined, 50);  // both outcomes are well represented
  EXPECT_GT(apart, 200);
}

TEST(FarObjectMerger, HierarchicalGridJoinsAFarCarSeenEndOn) {
  // Through the detector (step 6): the car's two faces at 45 m are 1.1 m apart
  // along the line of sight, farther than the far radial bridge reaches (3
  // near-empty sub-cells).
  LabeledCloud cloud;
  addEndOnCar(&cloud, 45.0f, 0.0f, 1.1f, 1, 2);
  core::HierarchicalGridDetectorParams p;
  p.far_merge.max_gap_m = 0.0;
  core::HierarchicalGridDetector off(p);
  std::vector<DetectedObject> objects;
  off.detect(cloud, &objects);
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(off.stats().far_joins, 0u);
  core::HierarchicalGridDetector shipped{core::HierarchicalGridDetectorParams()};
  shipped.detect(cloud, &objects);
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].indices.size(), cloud.size());
  EXPECT_EQ(shipped.stats().far_joins, 1u);
  EXPECT_EQ(shipped.stats().objects, 1u);
}

}  // namespace
}  // namespace urban_detection
