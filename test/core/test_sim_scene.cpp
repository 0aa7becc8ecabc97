// Scene primitives, ray caster and the procedural street generator of the simulator.
// Expected distances are computed by hand in the comments; the grid caster is checked against
// the brute-force caster (a different route through the same primitives).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/sim_scene.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace ud = urban_detection::core;
using Eigen::Vector3d;

namespace {
constexpr double kPi = 3.14159265358979323846;

const Vector3d kX(1, 0, 0), kY(0, 1, 0), kZ(0, 0, 1);
}  // namespace

TEST(SimPrimitive, BoxDistancesByHand) {
  // Unit-half box centred at (10, 0, 1): its -x face is at x = 9.
  ud::Primitive b = ud::makeBox(Vector3d(10, 0, 1), Vector3d(2, 2, 2), 0.0);
  EXPECT_NEAR(b.intersect(Vector3d(0, 0, 1), kX, 0.0), 9.0, 1e-12);
  EXPECT_NEAR(b.intersect(Vector3d(0, 0.9, 1.9), kX, 0.0), 9.0, 1e-12);
  EXPECT_LT(b.intersect(Vector3d(0, 1.1, 1), kX, 0.0), 0.0);  // passes beside it
  EXPECT_LT(b.intersect(Vector3d(0, 0, 1), -kX, 0.0), 0.0);   // points away
  EXPECT_LT(b.intersect(Vector3d(10, 0, 1), kX, 0.0), 0.0);   // starts inside
  // Diagonal ray from (0,-10,1) to the face x = 9 at y = -1 (corner region): direction
  // (9, 9, 0)/|.| reaches x = 9 at t = 9 * sqrt(2).
  EXPECT_NEAR(b.intersect(Vector3d(0, -10, 1), Vector3d(1, 1, 0).normalized(), 0.0),
              9.0 * std::sqrt(2.0), 1e-9);
  // Yawed by 45 deg: the edge pointing at the origin is at x = 10 - sqrt(2).
  ud::Primitive r = ud::makeBox(Vector3d(10, 0, 1), Vector3d(2, 2, 2), kPi / 4);
  EXPECT_NEAR(r.intersect(Vector3d(0, 0, 1), kX, 0.0), 10.0 - std::sqrt(2.0), 1e-9);
  // Moving at 1 m/s along x: at t = 2 s the face is at x = 11.
  b.velocity = Vector3d(1, 0, 0);
  EXPECT_NEAR(b.intersect(Vector3d(0, 0, 1), kX, 2.0), 11.0, 1e-12);
  EXPECT_TRUE(b.contains(Vector3d(12.95, 0, 1), 2.0));
  EXPECT_FALSE(b.contains(Vector3d(13.05, 0, 1), 2.0));
  EXPECT_TRUE(b.contains(Vector3d(13.05, 0, 1), 2.0, 0.1));
}

TEST(SimPrimitive, CylinderAndEllipsoidDistancesByHand) {
  // Cylinder radius 1, height 2, centre (5,0,0): side at x = 4, top cap at z = 1.
  const ud::Primitive c = ud::makeCylinder(Vector3d(5, 0, 0), 1.0, 2.0);
  EXPECT_NEAR(c.intersect(Vector3d(0, 0, 0), kX, 0.0), 4.0, 1e-12);
  EXPECT_NEAR(c.intersect(Vector3d(5, 0, 10), -kZ, 0.0), 9.0, 1e-12);
  // Off-centre by 0.6: side at x = 5 - sqrt(1 - 0.36) = 4.2.
  EXPECT_NEAR(c.intersect(Vector3d(0, 0.6, 0), kX, 0.0), 4.2, 1e-12);
  EXPECT_LT(c.intersect(Vector3d(0, 0, 1.5), kX, 0.0), 0.0);  // above the top
  // Ellipsoid with semi-axes (1, 2, 3) at the origin.
  const ud::Primitive e = ud::makeEllipsoid(Vector3d::Zero(), Vector3d(1, 2, 3));
  EXPECT_NEAR(e.intersect(Vector3d(0, -10, 0), kY, 0.0), 8.0, 1e-12);
  EXPECT_NEAR(e.intersect(Vector3d(0, 0, 10), -kZ, 0.0), 7.0, 1e-12);
  EXPECT_NEAR(e.intersect(Vector3d(-5, 0, 0), kX, 0.0), 4.0, 1e-12);
  EXPECT_LT(e.intersect(Vector3d(-5, 0, 2.9), kX, 0.0) - 4.0, 1.0);
  EXPECT_LT(e.intersect(Vector3d(-5, 0, 3.1), kX, 0.0), 0.0);
  // Bounds: cylinder is 2 x 2 x 2.
  const Eigen::AlignedBox3d bb = c.bounds();
  EXPECT_NEAR(bb.min().x(), 4.0, 1e-12);
  EXPECT_NEAR(bb.max().y(), 1.0, 1e-12);
  EXPECT_NEAR(bb.max().z(), 1.0, 1e-12);
}

TEST(SimPrimitive, SpanIsTheEntryAndExitOfTheWholeLine) {
  double t_in = 0, t_out = 0;
  // Box centred at (10, 0, 1), 2 m wide: the line along x from the origin is inside for
  // x in [9, 11].
  const ud::Primitive b = ud::makeBox(Vector3d(10, 0, 1), Vector3d(2, 2, 2), 0.0);
  ASSERT_TRUE(b.span(Vector3d(0, 0, 1), kX, 0.0, &t_in, &t_out));
  EXPECT_NEAR(t_in, 9.0, 1e-12);
  EXPECT_NEAR(t_out, 11.0, 1e-12);
  // From inside: the entry lies behind the origin (negative), the exit ahead.
  ASSERT_TRUE(b.span(Vector3d(10, 0, 1), kX, 0.0, &t_in, &t_out));
  EXPECT_NEAR(t_in, -1.0, 1e-12);
  EXPECT_NEAR(t_out, 1.0, 1e-12);
  EXPECT_FALSE(b.span(Vector3d(0, 1.5, 1), kX, 0.0, &t_in, &t_out));
  // Cylinder radius 1 at (5, 0, 0), 0.6 off its axis: chord half-length sqrt(1 - 0.36) = 0.8.
  const ud::Primitive c = ud::makeCylinder(Vector3d(5, 0, 0), 1.0, 2.0);
  ASSERT_TRUE(c.span(Vector3d(0, 0.6, 0), kX, 0.0, &t_in, &t_out));
  EXPECT_NEAR(t_in, 4.2, 1e-12);
  EXPECT_NEAR(t_out, 5.8, 1e-12);
  // Ellipsoid with semi-axes (1, 2, 3) at the origin, crossed along y: y in [-2, 2].
  const ud::Primitive e = ud::makeEllipsoid(Vector3d::Zero(), Vector3d(1, 2, 3));
  ASSERT_TRUE(e.span(Vector3d(0, -10, 0), kY, 0.0, &t_in, &t_out));
  EXPECT_NEAR(t_in, 8.0, 1e-12);
  EXPECT_NEAR(t_out, 12.0, 1e-12);
  // intersect() is the span's entry when it lies ahead.
  EXPECT_NEAR(e.intersect(Vector3d(0, -10, 0), kY, 0.0), 8.0, 1e-12);
}

TEST(SimRayCaster, NearestOfSeveralAndRangeLimit) {
  ud::Scene s;
  s.addBackground(ud::makeBox(Vector3d(20, 0, 0), Vector3d(2, 10, 10), 0.0));  // face x = 19
  ud::SceneObject o;
  o.object_class = ud::ObjectClass::kBin;
  const std::uint32_t id = s.addObject(o, {ud::makeCylinder(Vector3d(8, 0, 0), 0.5, 2.0)});
  ud::RayCaster rc(s);
  ud::RayHit h = rc.cast(Vector3d(0, 0, 0), kX, 100.0, 0.0);
  EXPECT_NEAR(h.distance_m, 7.5, 1e-12);
  EXPECT_EQ(s.primitives[h.primitive].instance_id, id);
  h = rc.cast(Vector3d(0, 2, 0), kX, 100.0, 0.0);  // passes the bin, hits the wall
  EXPECT_NEAR(h.distance_m, 19.0, 1e-12);
  EXPECT_EQ(s.primitives[h.primitive].instance_id, 0u);
  EXPECT_LT(rc.cast(Vector3d(0, 2, 0), kX, 18.0, 0.0).distance_m, 0.0);  // beyond max range
  EXPECT_LT(rc.cast(Vector3d(0, 2, 0), -kX, 100.0, 0.0).distance_m, 0.0);
}

TEST(SimRayCaster, MovingObjectPlacedAtRayTime) {
  ud::Scene s;
  ud::SceneObject o;
  o.object_class = ud::ObjectClass::kCar;
  o.velocity = Vector3d(0, 10, 0);  // crosses the ray's line at t = 1 s
  s.addObject(o, {ud::makeBox(Vector3d(10, -10, 0), Vector3d(4, 2, 2), 0.0)});
  s.addBackground(ud::makeBox(Vector3d(50, 0, 0), Vector3d(2, 100, 10), 0.0));
  ud::RayCaster rc(s);
  rc.setTimeWindow(0.0, 2.0);
  EXPECT_NEAR(rc.cast(Vector3d::Zero(), kX, 100.0, 0.0).distance_m, 49.0, 1e-12);
  EXPECT_NEAR(rc.cast(Vector3d::Zero(), kX, 100.0, 1.0).distance_m, 8.0, 1e-12);
  EXPECT_NEAR(rc.cast(Vector3d::Zero(), kX, 100.0, 2.0).distance_m, 49.0, 1e-12);
}

class GeneratedScene : public ::testing::Test {
 protected:
  void SetUp() override { scene_ = ud::generateScene(params_, drive_); }
  ud::SceneParams params_;
  ud::DriveParams drive_;
  ud::Scene scene_;
};

TEST_F(GeneratedScene, GridCasterEqualsBruteForce) {
  ud::RayCaster rc(scene_);
  rc.setTimeWindow(5.0, 5.2);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-30.0, 200.0), uy(-1.0, 1.0), ut(5.0, 5.2);
  std::uniform_real_distribution<double> uaz(-kPi, kPi), uel(-0.45, 0.1);
  int hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const double x = ux(rng), y = -1.9 + uy(rng);
    const Vector3d o(x, y, ud::groundHeight(params_, x, y) + 1.73);
    const double az = uaz(rng), el = uel(rng);
    const Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const double t = ut(rng);
    const ud::RayHit a = rc.cast(o, d, 120.0, t);
    const ud::RayHit b = rc.castBruteForce(o, d, 120.0, t);
    ASSERT_NEAR(a.distance_m, b.distance_m, 1e-9) << "ray " << i;
    if (a.distance_m > 0) {
      ++hits;
      // Same surface (or another one at the very same distance).
      if (a.primitive != b.primitive) {
        EXPECT_NEAR(scene_.primitives[a.primitive].intersect(o, d, t), a.distance_m, 1e-9);
      }
    }
  }
  EXPECT_GT(hits, 2500);  // the street is enclosed: nearly every downward/sideways ray hits
}

TEST_F(GeneratedScene, SameSeedSameSceneOtherSeedOtherScene) {
  const ud::Scene again = ud::generateScene(params_, drive_);
  ASSERT_EQ(again.primitives.size(), scene_.primitives.size());
  for (std::size_t i = 0; i < again.primitives.size(); ++i) {
    ASSERT_EQ(again.primitives[i].center, scene_.primitives[i].center);
    ASSERT_EQ(again.primitives[i].half_extents, scene_.primitives[i].half_extents);
  }
  ud::SceneParams other = params_;
  other.seed = 43;
  const ud::Scene diff = ud::generateScene(other, drive_);
  bool differs = diff.primitives.size() != scene_.primitives.size();
  for (std::size_t i = 0; !differs && i < diff.primitives.size(); ++i) {
    differs = diff.primitives[i].center != scene_.primitives[i].center;
  }
  EXPECT_TRUE(differs);
}

TEST_F(GeneratedScene, ContainsEveryClassAndObjectMetadataIsConsistent) {
  std::vector<int> count(ud::kNumObjectClasses, 0);
  for (const ud::Primitive& p : scene_.primitives) ++count[static_cast<int>(p.object_class)];
  for (int c = 1; c < ud::kNumObjectClasses; ++c) {
    EXPECT_GT(count[c], 0) << ud::toString(static_cast<ud::ObjectClass>(c));
  }
  int moving = 0;
  for (std::size_t i = 0; i < scene_.objects.size(); ++i) {
    const ud::SceneObject& o = scene_.objects[i];
    EXPECT_EQ(o.instance_id, i + 1);
    ASSERT_GT(o.num_primitives, 0u);
    for (std::uint32_t k = 0; k < o.num_primitives; ++k) {
      EXPECT_EQ(scene_.primitives[o.first_primitive + k].instance_id, o.instance_id);
    }
    // The object stands on the ground: its lowest point is at most 0.3 m above the ground
    // (car bodies) and at most 0.45 m below (posts and trunks are sunk into it).
    const Eigen::AlignedBox3d b = scene_.objectBounds(o.instance_id, 0.0);
    EXPECT_LE(b.min().z() - o.position.z(), 0.31) << ud::toString(o.object_class);
    EXPECT_GE(b.min().z() - o.position.z(), -0.45) << ud::toString(o.object_class);
    EXPECT_NEAR(o.position.z(), ud::groundHeight(params_, o.position.x(), o.position.y()), 1e-9);
    moving += o.velocity.norm() > 0 ? 1 : 0;
  }
  EXPECT_GE(moving, params_.objects.moving_cars + params_.objects.cyclists);
}

namespace {
// Horizontal gap between two xy boxes (0 if they overlap).
double gapXY(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  const double dx = std::max({0.0, a.min().x() - b.max().x(), b.min().x() - a.max().x()});
  const double dy = std::max({0.0, a.min().y() - b.max().y(), b.min().y() - a.max().y()});
  return std::hypot(dx, dy);
}
}  // namespace

TEST_F(GeneratedScene, HardCasesOfTheDetectionPaperArePresent) {
  auto is = [&](const ud::SceneObject& o, ud::ObjectClass c) { return o.object_class == c; };
  bool close_cars = false, ped_beside_car = false, touching_wall = false, close_street = false;
  std::vector<Eigen::AlignedBox3d> walls;
  for (const ud::Primitive& p : scene_.primitives) {
    if (p.object_class == ud::ObjectClass::kWall) walls.push_back(p.bounds());
  }
  for (const ud::SceneObject& a : scene_.objects) {
    if (a.velocity.norm() > 0) continue;
    const Eigen::AlignedBox3d ba = scene_.objectBounds(a.instance_id, 0.0);
    for (const ud::SceneObject& b : scene_.objects) {
      if (b.instance_id <= a.instance_id || b.velocity.norm() > 0) continue;
      const double g = gapXY(ba, scene_.objectBounds(b.instance_id, 0.0));
      if (is(a, ud::ObjectClass::kCar) && is(b, ud::ObjectClass::kCar) && g < 0.6)
        close_cars = true;
      if (((is(a, ud::ObjectClass::kCar) && is(b, ud::ObjectClass::kPedestrian)) ||
           (is(b, ud::ObjectClass::kCar) && is(a, ud::ObjectClass::kPedestrian))) &&
          g < 0.6) {
        ped_beside_car = true;
      }
      if (ud::isStreetObject(a.object_class) && ud::isStreetObject(b.object_class) && g < 0.6 &&
          !is(a, ud::ObjectClass::kCar)) {
        close_street = true;
      }
    }
    if (ud::isStreetObject(a.object_class)) {
      for (const auto& w : walls) touching_wall |= gapXY(ba, w) < 0.01;
    }
  }
  EXPECT_TRUE(close_cars);
  EXPECT_TRUE(ped_beside_car);
  EXPECT_TRUE(touching_wall);
  EXPECT_TRUE(close_street);
}

TEST_F(GeneratedScene, NarrowStreetFacadeWithinThreeMetresOfTheSensor) {
  // Default drive: in the narrow section (x in [94, 139]) the platform keeps y = -0.7 and the
  // right facade line is at y = -(2.7 + 0.8) = -3.5, i.e. 2.8 m away (unless a gap/recess).
  ud::RayCaster rc(scene_);
  int near_wall = 0;
  for (double x = 100.0; x < 135.0; x += 1.0) {
    const Vector3d o(x, -0.7, ud::groundHeight(params_, x, -0.7) + 1.73);
    const ud::RayHit h = rc.cast(o, -kY, 50.0, 0.0);
    ASSERT_GT(h.distance_m, 0.0);
    if (scene_.primitives[h.primitive].object_class == ud::ObjectClass::kWall) {
      EXPECT_GE(h.distance_m, 2.8 - 1e-9);
      if (h.distance_m < 3.0) ++near_wall;
    }
  }
  EXPECT_GT(near_wall, 10);
}

TEST_F(GeneratedScene, NoRayPassesThroughAWall) {
  // From the street, a horizontal ray at 3 m height perpendicular to each facade must end at
  // or before the facade plane, never behind it.
  ud::RayCaster rc(scene_);
  int checked = 0, on_wall = 0;
  for (const ud::Primitive& p : scene_.primitives) {
    if (p.object_class != ud::ObjectClass::kWall) continue;
    const Eigen::AlignedBox3d b = p.bounds();
    const bool left = b.min().y() > 0;
    const double facade_y = left ? b.min().y() : b.max().y();
    for (double x = b.min().x() + 0.25; x < b.max().x(); x += 1.0) {
      const Vector3d o(x, 0.0, ud::groundHeight(params_, x, 0.0) + 3.0);
      const ud::RayHit h = rc.cast(o, left ? kY : -kY, 100.0, 0.0);
      ASSERT_GT(h.distance_m, 0.0);
      EXPECT_LE(h.distance_m, std::abs(facade_y) + 1e-9) << "x=" << x;
      on_wall += std::abs(h.distance_m - std::abs(facade_y)) < 1e-9 ? 1 : 0;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
  EXPECT_GT(on_wall, checked / 2);
}

TEST_F(GeneratedScene, VerticalRaysFindTheGroundModel) {
  ud::RayCaster rc(scene_);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(-35.0, 215.0), uy(-9.0, 9.0);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const double x = ux(rng), y = uy(rng);
    const double expected = ud::groundHeight(params_, x, y);
    const ud::RayHit h = rc.cast(Vector3d(x, y, 60.0), -kZ, 200.0, 0.0);
    ASSERT_GT(h.distance_m, 0.0);
    if (scene_.primitives[h.primitive].object_class != ud::ObjectClass::kGround) continue;
    // Curb edges: skip points within 2 cm of a curb line (either surface is right).
    EXPECT_NEAR(60.0 - h.distance_m, expected, 0.01) << "x=" << x << " y=" << y;
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(SimConfig, DemoDriveFileParsesAndTyposAreRejected) {
  const ud::SimulationConfig c =
      ud::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  EXPECT_EQ(c.scene.sections.size(), 5u);
  EXPECT_DOUBLE_EQ(c.sensor.height_m, 1.73);
  EXPECT_GE(c.drive.waypoints.size(), 2u);
  EXPECT_THROW(ud::parseSimulationConfig("sensor: {rmp: 600}"), std::invalid_argument);
  try {
    ud::parseSimulationConfig("sensor: {rpm: 2000}");
    FAIL() << "rpm 2000 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rpm"), std::string::npos) << e.what();
  }
  try {
    ud::parseSimulationConfig("scene: {sections: [{type: roundabout}]}");
    FAIL() << "unknown section type accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("scene/sections[0]/type"), std::string::npos) << e.what();
  }
  // Every key goes through the field tables: a wrong type, an out-of-range value and an unknown
  // key inside a section are refused naming the key.
  const auto refusal = [](const std::string& yaml) {
    try {
      ud::parseSimulationConfig(yaml, "drive.yaml");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal("scene: {sections: [{type: street}, {length_m: long}]}")
                .find("drive.yaml: scene/sections[1]/length_m: wrong type"),
            std::string::npos)
      << refusal("scene: {sections: [{type: street}, {length_m: long}]}");
  EXPECT_NE(refusal("scene: {sections: [{road_half_width_m: 25}]}")
                .find("parameter 'scene/sections[0]/road_half_width_m' = 25 is out of range"),
            std::string::npos)
      << refusal("scene: {sections: [{road_half_width_m: 25}]}");
  EXPECT_NE(refusal("scene: {sections: [{type: street}, {lenght_m: 30}]}")
                .find("scene/sections[1]/lenght_m: unknown parameter"),
            std::string::npos)
      << refusal("scene: {sections: [{type: street}, {lenght_m: 30}]}");
  EXPECT_NE(refusal("scene: {sections: {type: street}}").find("scene/sections"), std::string::npos);
  EXPECT_NE(refusal("drive: {waypoints: [[0, 0, 1], [5, 0]]}").find("drive/waypoints[0]"),
            std::string::npos);
  EXPECT_NE(refusal("scene: {objects: {pedestrians: -1}}").find("scene/objects/pedestrians"),
            std::string::npos);
  EXPECT_NE(refusal("sensor: {calibration: [1, 2]}").find("sensor/calibration: wrong type"),
            std::string::npos);
  // A list of sections replaces the default list; unspecified fields keep their defaults.
  const ud::SimulationConfig two = ud::parseSimulationConfig(
      "scene: {sections: [{type: intersection, length_m: 12}, {sidewalk_width_m: 2}]}");
  ASSERT_EQ(two.scene.sections.size(), 2u);
  EXPECT_EQ(two.scene.sections[0].type, ud::StreetSection::Type::kIntersection);
  EXPECT_DOUBLE_EQ(two.scene.sections[0].length_m, 12.0);
  EXPECT_EQ(two.scene.sections[1].type, ud::StreetSection::Type::kStreet);
  EXPECT_DOUBLE_EQ(two.scene.sections[1].sidewalk_width_m, 2.0);
  EXPECT_DOUBLE_EQ(two.scene.sections[1].length_m, ud::StreetSection().length_m);
  EXPECT_THROW(ud::parseSimulationConfig("drive: {waypoints: [[0, 0]]}"), std::invalid_argument);
  EXPECT_THROW(ud::parseSimulationConfig("drive: {speed_mps: abc}"), std::invalid_argument);
  EXPECT_NO_THROW(ud::parseSimulationConfig(""));
  // The vegetation block mirrors VegetationParams, with the same checks.
  EXPECT_TRUE(c.scene.vegetation.enabled);
  EXPECT_DOUBLE_EQ(c.scene.vegetation.hedge_transmission,
                   ud::VegetationParams().hedge_transmission);
  EXPECT_DOUBLE_EQ(ud::parseSimulationConfig("scene: {vegetation: {crown_transmission: 0.7}}")
                       .scene.vegetation.crown_transmission,
                   0.7);
  EXPECT_THROW(ud::parseSimulationConfig("scene: {vegetation: {hedge_trasmission: 0.1}}"),
               std::invalid_argument);
  try {
    ud::parseSimulationConfig("scene: {vegetation: {bush_transmission: 1.5}}");
    FAIL() << "transmission 1.5 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bush_transmission"), std::string::npos) << e.what();
  }
  EXPECT_THROW(
      ud::parseSimulationConfig(
          "scene: {vegetation: {canopy_clearance_min_m: 3.0, canopy_clearance_max_m: 2.0}}"),
      std::invalid_argument);
}

// ---- vegetation ---------------------------------------------------------------------

namespace {

bool isTree(const ud::Scene& s, const ud::SceneObject& o) {
  for (std::uint32_t k = 0; k < o.num_primitives; ++k) {
    if (s.primitives[o.first_primitive + k].object_class == ud::ObjectClass::kTrunk) return true;
  }
  return false;
}

// Lowest point of an unrotated-in-z-axis ellipsoid or box (all the generator makes).
double lowestZ(const ud::Primitive& p) {
  return p.bounds().min().z();
}

}  // namespace

TEST_F(GeneratedScene, DefaultStreetHasHedgesBushesVergesGardensAndLowCanopies) {
  const ud::VegetationParams& v = params_.vegetation;
  int hedges = 0, bushes = 0, trees = 0, lobes = 0, terrain_tiles = 0;
  double terrain_above_min = 1e9, terrain_above_max = -1e9;
  for (const ud::Primitive& p : scene_.primitives) {
    if (p.object_class != ud::ObjectClass::kTerrain) continue;
    ++terrain_tiles;
    EXPECT_EQ(p.instance_id, 0u);  // terrain is background
    const Eigen::Vector3d c = p.center + p.half_extents.z() * p.rotation.col(2);  // top centre
    const double above = c.z() - ud::groundHeight(params_, c.x(), c.y());
    terrain_above_min = std::min(terrain_above_min, above);
    terrain_above_max = std::max(terrain_above_max, above);
  }
  EXPECT_GT(terrain_tiles, 300);
  // Tile tops lie at most the largest step plus the roughness above the paved ground.
  EXPECT_GE(terrain_above_min, -1e-9);
  EXPECT_LE(terrain_above_max, v.garden_step_max_m + v.terrain_roughness_m + 1e-9);
  EXPECT_GT(terrain_above_max, 0.1);  // some gardens are raised (a terrain step)

  for (const ud::SceneObject& o : scene_.objects) {
    if (o.object_class != ud::ObjectClass::kVegetation) continue;
    const double gz = o.position.z();
    if (isTree(scene_, o)) {
      ++trees;
      for (std::uint32_t k = 1; k < o.num_primitives; ++k) {
        const ud::Primitive& p = scene_.primitives[o.first_primitive + k];
        ASSERT_EQ(p.object_class, ud::ObjectClass::kVegetation);
        EXPECT_TRUE(p.porous());
        EXPECT_FLOAT_EQ(p.transmission, static_cast<float>(v.crown_transmission));
        if (k < 2) continue;  // the main crown
        ++lobes;
        // A lobe's lowest leaves (at its centre's xy) keep the clearance above the ground.
        const double above = lowestZ(p) - ud::groundHeight(params_, p.center.x(), p.center.y());
        EXPECT_GE(above, v.canopy_clearance_min_m - 1e-9);
        EXPECT_LE(above, v.canopy_clearance_max_m + 1e-9);
        // ... and it reaches at most canopy_overhang_max_m from the trunk.
        const double reach =
            std::hypot(p.center.x() - o.position.x(), p.center.y() - o.position.y()) +
            p.half_extents.x();
        EXPECT_LE(reach, v.canopy_overhang_max_m + 1e-9);
      }
      continue;
    }
    const ud::Primitive& first = scene_.primitives[o.first_primitive];
    const double height = scene_.objectBounds(o.instance_id, 0.0).max().z() - gz;
    if (first.shape == ud::PrimitiveShape::kBox) {
      ++hedges;
      EXPECT_GE(height, v.hedge_height_min_m - 0.07);
      EXPECT_LE(height, v.hedge_height_max_m + v.garden_step_max_m + 0.07);
      EXPECT_FLOAT_EQ(first.transmission, static_cast<float>(v.hedge_transmission));
    } else {
      ++bushes;
      EXPECT_GE(height, v.bush_height_min_m - 1e-9);
      EXPECT_LE(height, v.bush_height_max_m + v.garden_step_max_m + 1e-9);
      EXPECT_FLOAT_EQ(first.transmission, static_cast<float>(v.bush_transmission));
    }
  }
  EXPECT_GE(hedges, 5);
  EXPECT_GE(bushes, 10);
  EXPECT_GE(trees, 15);
  EXPECT_GE(lobes, 2 * trees);
}

TEST_F(GeneratedScene, CanopiesOverhangCarsAndPedestriansButNeverSwallowThem) {
  std::vector<const ud::Primitive*> foliage;
  for (const ud::Primitive& p : scene_.primitives) {
    if (p.object_class == ud::ObjectClass::kVegetation) foliage.push_back(&p);
  }
  ASSERT_FALSE(foliage.empty());
  int cars = 0, cars_under = 0, peds = 0, peds_under = 0;
  const double t_end = drive_.duration();
  for (const ud::SceneObject& o : scene_.objects) {
    const bool car =
        o.object_class == ud::ObjectClass::kCar || o.object_class == ud::ObjectClass::kVan;
    const bool ped = o.object_class == ud::ObjectClass::kPedestrian;
    if (!(car && o.velocity.isZero()) && !ped) continue;
    bool under = false;
    for (double t = 0.0; t <= t_end; t += o.velocity.isZero() ? 2.0 * t_end + 1.0 : 1.0) {
      const Eigen::AlignedBox3d b = scene_.objectBounds(o.instance_id, t);
      for (const ud::Primitive* f : foliage) {
        const Eigen::AlignedBox3d fb = f->bounds();
        if (fb.min().x() > b.max().x() || fb.max().x() < b.min().x() ||
            fb.min().y() > b.max().y() || fb.max().y() < b.min().y()) {
          continue;
        }
        for (double fx : {0.0, 0.25, 0.5, 0.75, 1.0}) {
          for (double fy : {0.0, 0.5, 1.0}) {
            const Vector3d top(b.min().x() + fx * b.sizes().x(), b.min().y() + fy * b.sizes().y(),
                               b.max().z());
            // No foliage within 0.2 m above the object's box (a crown or bush swallowing it
            // would hide it for no real reason) ...
            ASSERT_FALSE(f->contains(top + Vector3d(0, 0, 0.2), t))
                << ud::toString(o.object_class) << " " << o.instance_id << " at t=" << t;
            // ... but foliage within 2 m above it: it stands under a canopy.
            for (double dz = 0.3; dz <= 2.0 && !under; dz += 0.1) {
              under = f->contains(top + Vector3d(0, 0, dz), t);
            }
          }
        }
      }
    }
    (car ? cars : peds) += 1;
    if (under) ++(car ? cars_under : peds_under);
  }
  EXPECT_GT(cars, 20);
  EXPECT_GT(peds, 10);
  // Some, not all, stand under crowns.
  EXPECT_GE(cars_under, 3);
  EXPECT_LT(cars_under, cars);
  EXPECT_GE(peds_under, 1);
  EXPECT_LT(peds_under, peds);
}

TEST_F(GeneratedScene, VegetationHasItsOwnRandomStream) {
  // Switching the vegetation off (or changing it) moves none of the other objects.
  ud::SceneParams off = params_;
  off.vegetation.enabled = false;
  const ud::Scene bare = ud::generateScene(off, drive_);
  ud::SceneParams other = params_;
  other.vegetation.hedge_probability = 1.0;
  other.vegetation.bush_spacing_m = 1.5;
  other.vegetation.verge_bush_spacing_m = 3.0;
  other.vegetation.facade_shrub_spacing_m = 2.0;
  const ud::Scene denser = ud::generateScene(other, drive_);
  for (const ud::Scene* s : {&bare, &denser}) {
    std::size_t street_objects = 0;
    for (const ud::SceneObject& o : s->objects) {
      if (!ud::isStreetObject(o.object_class)) continue;
      ++street_objects;
      ASSERT_LE(o.instance_id, scene_.objects.size());
      const ud::SceneObject& a = scene_.objects[o.instance_id - 1];
      EXPECT_EQ(a.object_class, o.object_class);
      EXPECT_EQ(a.position, o.position);
      EXPECT_EQ(a.velocity, o.velocity);
    }
    EXPECT_GT(street_objects, 50u);
  }
  int terrain = 0, porous = 0;
  for (const ud::Primitive& p : bare.primitives) {
    terrain += p.object_class == ud::ObjectClass::kTerrain;
    porous += p.porous();
  }
  EXPECT_EQ(terrain, 0);
  EXPECT_EQ(porous, 0);
  // The denser variant really has more vegetation.
  EXPECT_GT(denser.objects.size(), scene_.objects.size());
}
