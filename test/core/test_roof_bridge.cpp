// Hierarchical grid detector, step 3b (roof bridge): a lone scan ring on a car roof, cut off
// from the car's side by the gap the rings leave on a horizontal surface near sensor height,
// joins the car; flat surfaces at another height, non-flat objects, sub-cells farther than
// roof_bridge_range_m and gaps longer than the ring spacing explains stay apart.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "detection_test_utils.h"
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE
#include "urban_detection/core/detection/hierarchical_grid_detector.h"

namespace urban_detection {
namespace {

using core::DetectedObject;
using core::HierarchicalGridDetector;
using core::HierarchicalGridDetectorParams;
using test::addPoint;

constexpr std::uint32_t kSide = 1, kRing = 2;

// A car side seen from the sensor at the origin: a vertical face across the line of sight
// (x in [-2, 2], at distance `y_face`, from 0.2 m above the road up to `top_z`, z in the
// sensor frame, road at -1.73), and one scan ring `gap_m` beyond it: a flat line of returns at
// height `ring_z` (points every 1 cm, `ring_thickness_m` of z spread), x in [-1.5, 1.5].
LabeledCloud sideAndRing(float y_face, float top_z, float gap_m, float ring_z,
                         float ring_thickness_m = 0.0f) {
  LabeledCloud cloud;
  for (float x = -2.0f; x <= 2.0f; x += 0.02f) {
    for (float z = -1.53f; z <= top_z + 1e-4f; z += 0.05f) addPoint(&cloud, x, y_face, z, kSide);
    addPoint(&cloud, x, y_face, top_z, kSide);
  }
  int k = 0;
  for (float x = -1.5f; x <= 1.5f; x += 0.01f, ++k) {
    addPoint(&cloud, x, y_face + gap_m, ring_z - ring_thickness_m * (k % 2), kRing);
  }
  return cloud;
}

std::vector<DetectedObject> detect(const LabeledCloud& cloud,
                                   const HierarchicalGridDetectorParams& p) {
  HierarchicalGridDetector det(p);
  std::vector<DetectedObject> objects;
  det.detect(cloud, &objects);
  return objects;
}

// One object holding every point of the cloud.
bool oneObjectHoldsAll(const LabeledCloud& cloud, const std::vector<DetectedObject>& objects) {
  return objects.size() == 1 && objects[0].indices.size() == cloud.size();
}

HierarchicalGridDetectorParams roofOff() {
  HierarchicalGridDetectorParams p;
  p.roof_bridge_subcells = 0;
  return p;
}

TEST(RoofBridge, DefaultsAreOnAndValid) {
  const HierarchicalGridDetectorParams p;
  EXPECT_GT(p.roof_bridge_subcells, 0);
  EXPECT_EQ(core::validate(p), "");
}

TEST(RoofBridge, LoneRoofRingJoinsTheCarSide) {
  // Roof 0.25 m below the sensor, side at 6.05 m: two rings land 6.05^2 * 0.5 deg / 0.25 m =
  // 1.28 m apart there, so a ring 1.2 m beyond the side (5 near-empty sub-cells between) is the
  // next ring on the roof.
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f);
  const auto off = detect(cloud, roofOff());
  ASSERT_EQ(off.size(), 2u) << "without the roof bridge the ring is a separate object";
  HierarchicalGridDetectorParams on;
  HierarchicalGridDetector det(on);
  std::vector<DetectedObject> objects;
  det.detect(cloud, &objects);
  EXPECT_TRUE(oneObjectHoldsAll(cloud, objects)) << objects.size() << " objects";
  EXPECT_GT(det.stats().roof_bridges, 0u);
}

TEST(RoofBridge, RingWithSomeThicknessStillJoins) {
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f, 0.1f);
  EXPECT_TRUE(oneObjectHoldsAll(cloud, detect(cloud, HierarchicalGridDetectorParams())));
}

TEST(RoofBridge, FlatSurfaceAtAnotherHeightStaysApart) {
  // 0.2 m above the side's top (the ring spacing would allow it there): not the same roof.
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.05f);
  EXPECT_EQ(detect(cloud, HierarchicalGridDetectorParams()).size(), 2u);
}

TEST(RoofBridge, ThickRingIsNotARoofAndStaysApart) {
  // z range 0.3 m in each sub-cell: a vertical surface (a pedestrian, a car behind), not a ring.
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f, 0.3f);
  EXPECT_EQ(detect(cloud, HierarchicalGridDetectorParams()).size(), 2u);
}

TEST(RoofBridge, TallerObjectBesideTheRingStaysApart) {
  // Something 0.3 m taller right behind the ring, in the ring's super-cells (a hedge, people
  // walking behind a low wall): the ring is not a lone ring on a roof.
  LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f);
  for (float x = -1.5f; x <= 1.5f; x += 0.01f) addPoint(&cloud, x, 7.5f, 0.05f, kRing);
  EXPECT_EQ(detect(cloud, HierarchicalGridDetectorParams()).size(), 2u);
}

TEST(RoofBridge, GapLongerThanTheRingSpacingExplainsStaysApart) {
  // With 0.2 deg between rings the next ring on that roof would be 0.51 m beyond the side.
  HierarchicalGridDetectorParams p;
  p.ring_spacing_deg = 0.2;
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f);
  EXPECT_EQ(detect(cloud, p).size(), 2u);
  p.ring_spacing_deg = 0.5;
  EXPECT_EQ(detect(cloud, p).size(), 1u);
}

TEST(RoofBridge, OnlyNearerThanTheRoofBridgeRange) {
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f);
  HierarchicalGridDetectorParams p;
  p.roof_bridge_range_m = 5.0;
  EXPECT_EQ(detect(cloud, p).size(), 2u);
}

TEST(RoofBridge, ReachIsBoundedBySubCells) {
  // 1.15 m is 5 near-empty sub-cells between side and ring: a reach of 3 does not span it.
  HierarchicalGridDetectorParams p;
  p.roof_bridge_subcells = 3;
  const LabeledCloud cloud = sideAndRing(6.05f, -0.25f, 1.2f, -0.25f);
  EXPECT_EQ(detect(cloud, p).size(), 2u);
}

TEST(RoofBridge, ParametersAreValidated) {
  HierarchicalGridDetectorParams p;
  p.roof_bridge_subcells = 9;
  EXPECT_NE(core::validate(p).find("roof_bridge_subcells"), std::string::npos);
  p = HierarchicalGridDetectorParams();
  p.roof_max_step_m = -0.1;
  EXPECT_NE(core::validate(p).find("roof_max_step_m"), std::string::npos);
  p = HierarchicalGridDetectorParams();
  p.ring_spacing_deg = 0.0;
  EXPECT_NE(core::validate(p).find("ring_spacing_deg"), std::string::npos);
  p = HierarchicalGridDetectorParams();
  p.roof_bridge_range_m = -1.0;
  EXPECT_NE(core::validate(p).find("roof_bridge_range_m"), std::string::npos);
}

}  // namespace
}  // namespace urban_detection
