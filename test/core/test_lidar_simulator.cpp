// The simulated HDL-64E: packets decoded by the real PacketDecoder must reproduce the simulated
// hits, in the order of the ground truth; ranges of a single box are computed by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "test_files.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/ground_truth.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace ud = urban_detection::core;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;

ud::SimulationConfig demoConfig() {
  return ud::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
}

std::unique_ptr<ud::LidarSimulator> makeSim(const ud::SimulationConfig& c) {
  return std::make_unique<ud::LidarSimulator>(ud::generateScene(c.scene, c.drive), c.scene, c.drive,
                                              ud::Calibration::nominalHdl64eS2(), c.sensor);
}

// Decodes a revolution the way PacketToCloud does (packet time relative to the scan stamp).
void decodeRevolution(const ud::SimRevolution& rev, const ud::PacketDecoder& decoder,
                      urban_detection::CloudXYZIRT* cloud, std::vector<std::uint8_t>* lasers,
                      std::vector<std::uint16_t>* azimuths) {
  cloud->clear();
  for (std::size_t i = 0; i < rev.packets.size(); ++i) {
    ud::DecodeStats stats;
    ASSERT_EQ(decoder.decode(rev.packets[i].data(), rev.packets[i].size(),
                             rev.packet_stamps_s[i] - rev.stamp_s, cloud, &stats, lasers, azimuths),
              ud::PacketStatus::kOk);
  }
}

}  // namespace

TEST(LidarSimulator, SingleBoxRangesMatchHandComputation) {
  // One wall: its face is the plane x = 9 m, 40 m wide (|y| < 20), 60 m tall. The platform
  // stands at the origin on a flat road (no slope, no camber), sensor 1.73 m up, no pitch.
  ud::SceneParams flat;
  flat.slope = 0.0;
  flat.camber = 0.0;
  ud::Scene scene;
  scene.addBackground(ud::makeBox(Vector3d(9.5, 0, 0), Vector3d(1, 40, 60), 0.0));
  scene.primitives.back().object_class = ud::ObjectClass::kWall;
  ud::DriveParams standing;
  standing.waypoints = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0)};
  standing.speed_mps = 0.0;
  ud::SimSensorParams sensor;
  sensor.range_noise_m = 0.005;
  sensor.dropout_probability = 0.0;
  const ud::Calibration cal = ud::Calibration::nominalHdl64eS2();
  for (const auto& l : cal.lasers) {  // the hand formula assumes no origin offsets
    ASSERT_EQ(l.vert_offset_correction_m, 0.0);
    ASSERT_EQ(l.horiz_offset_correction_m, 0.0);
  }
  ud::LidarSimulator sim(std::move(scene), flat, standing, cal, sensor);
  ud::SimRevolution rev;
  sim.simulateNext(&rev);

  // Expected count: a laser at horizontal angle theta (from +x, clockwise) hits the face iff
  // |9 tan(theta)| < 20; the face is tall enough for every elevation.
  std::size_t expected_count = 0;
  for (const auto& packet : rev.packets) {
    for (int b = 0; b < ud::kBlocksPerPacket; b += 2) {
      const std::uint16_t az = ud::blockAzimuth(packet.data(), b);
      for (int l = 0; l < ud::kNumLasers; ++l) {
        const double theta = az * kPi / 18000.0 - cal.lasers[l].rot_correction_rad;
        if (std::cos(theta) > 0 && std::abs(9.0 * std::tan(theta)) < 20.0) ++expected_count;
      }
    }
  }
  ud::PacketDecoder decoder(cal, ud::DecoderParams());
  urban_detection::CloudXYZIRT cloud;
  std::vector<std::uint8_t> lasers;
  std::vector<std::uint16_t> azimuths;
  decodeRevolution(rev, decoder, &cloud, &lasers, &azimuths);
  ASSERT_GT(expected_count, 30000u);
  EXPECT_EQ(cloud.size(), expected_count);
  EXPECT_EQ(rev.instance_ids.size(), cloud.size());
  // Range of each point: 9 / (cos(elevation) cos(theta)), +- noise (5 sigma) + quantisation.
  double worst = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    const ud::LaserCorrection& lc = cal.lasers[lasers[i]];
    const double theta = azimuths[i] * kPi / 18000.0 - lc.rot_correction_rad;
    const double expected = 9.0 / (std::cos(lc.vert_correction_rad) * std::cos(theta));
    const double range = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    worst = std::max(worst, std::abs(range - expected));
    EXPECT_EQ(rev.classes[i], static_cast<std::uint8_t>(ud::ObjectClass::kWall));
  }
  EXPECT_LT(worst, 5 * 0.005 + 0.002);
  EXPECT_GT(worst, 0.002);  // the noise is really there
}

namespace {

// A standing sensor at the origin (flat road) facing a hedge, a box 1 m deep whose front face is
// the plane x = 6 m (|y| < 8 m, z in [-5, 5] m), in front of a wall whose face is x = 12 m.
// Returns the revolution's true hit points and classes for the rays aimed at the hedge's
// middle (|y / x| < 1: they cross the hedge from its front to its back face).
struct HedgeShot {
  std::vector<Vector3d> points;
  std::vector<ud::ObjectClass> classes;
  ud::SimStats stats;
  std::vector<std::uint8_t> intensities;  // of the same returns, from the packets
};

HedgeShot shootHedge(float transmission, float penetration_m, std::uint64_t noise_seed = 1) {
  ud::SceneParams flat;
  flat.slope = 0.0;
  flat.camber = 0.0;
  ud::Scene scene;
  scene.addBackground(ud::makeBox(Vector3d(12.5, 0, 0), Vector3d(1, 40, 60), 0.0));
  scene.primitives.back().object_class = ud::ObjectClass::kWall;
  ud::Primitive hedge = ud::makeBox(Vector3d(6.5, 0, 0), Vector3d(1, 16, 10), 0.0);
  hedge.object_class = ud::ObjectClass::kVegetation;
  hedge.transmission = transmission;
  hedge.penetration_m = penetration_m;
  ud::SceneObject o;
  o.object_class = ud::ObjectClass::kVegetation;
  scene.addObject(o, {hedge});
  ud::DriveParams standing;
  standing.waypoints = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0)};
  standing.speed_mps = 0.0;
  ud::SimSensorParams sensor;
  sensor.dropout_probability = 0.0;
  sensor.noise_seed = noise_seed;
  ud::LidarSimulator sim(std::move(scene), flat, standing, ud::Calibration::nominalHdl64eS2(),
                         sensor);
  ud::SimRevolution rev;
  sim.simulateNext(&rev);
  ud::PacketDecoder decoder(sim.calibration(), ud::DecoderParams());
  urban_detection::CloudXYZIRT cloud;
  decodeRevolution(rev, decoder, &cloud, nullptr, nullptr);
  HedgeShot shot;
  shot.stats = rev.stats;
  for (std::size_t i = 0; i < rev.world_points.size(); ++i) {
    const Vector3d p = rev.world_points[i].cast<double>();
    if (p.x() <= 0.0 || std::abs(p.y() / p.x()) >= 1.0) continue;
    // Elevation inside the hedge's height at its back face.
    const double z_at_back = 1.73 + (p.z() - 1.73) * 7.0 / p.x();
    if (std::abs(z_at_back) > 4.5) continue;
    shot.points.push_back(p);
    shot.classes.push_back(static_cast<ud::ObjectClass>(rev.classes[i]));
    shot.intensities.push_back(static_cast<std::uint8_t>(cloud[i].intensity));
  }
  return shot;
}

}  // namespace

TEST(LidarSimulator, PorousHedgeTransmitsItsShareOfRaysToTheWallBehind) {
  for (float transmission : {0.0f, 0.12f, 0.3f, 0.6f}) {
    const HedgeShot shot = shootHedge(transmission, 0.12f);
    ASSERT_GT(shot.points.size(), 5000u);
    std::size_t wall = 0;
    for (std::size_t i = 0; i < shot.points.size(); ++i) {
      const Vector3d& p = shot.points[i];
      if (shot.classes[i] == ud::ObjectClass::kWall) {
        ++wall;
        EXPECT_NEAR(p.x(), 12.0, 1e-6);  // transmitted rays end on the wall
      } else {
        ASSERT_EQ(shot.classes[i], ud::ObjectClass::kVegetation);
        EXPECT_GE(p.x(), 6.0 - 1e-6);  // inside the hedge, never in front of it
        EXPECT_LE(p.x(), 7.0 + 1e-6);
      }
    }
    const double fraction = static_cast<double>(wall) / shot.points.size();
    // Binomial: with > 5000 rays the standard deviation is below 0.007.
    EXPECT_NEAR(fraction, transmission, 0.03) << "transmission " << transmission;
    if (transmission == 0.0f) {
      EXPECT_EQ(wall, 0u);
    }
  }
}

TEST(LidarSimulator, ReturnsFromInsideFoliageGiveARoughRangeProfile) {
  // Returns of the vegetation: depth behind the front face exponential with the mean
  // penetration; an opaque hedge (penetration 0) returns from its face only.
  auto depths = [](const HedgeShot& shot) {
    std::vector<double> d;
    for (std::size_t i = 0; i < shot.points.size(); ++i) {
      if (shot.classes[i] == ud::ObjectClass::kVegetation) {
        const Vector3d& p = shot.points[i];
        d.push_back((p - Vector3d(0, 0, 1.73)).norm() * (1.0 - 6.0 / p.x()));  // along the ray
      }
    }
    return d;
  };
  const std::vector<double> porous = depths(shootHedge(0.0f, 0.15f));
  const std::vector<double> opaque = depths(shootHedge(0.0f, 0.0f));
  ASSERT_GT(porous.size(), 5000u);
  ASSERT_GT(opaque.size(), 5000u);
  double mean = 0.0, deep = 0.0;
  for (double d : porous) {
    mean += d;
    deep += d > 0.3 ? 1.0 : 0.0;
  }
  mean /= porous.size();
  deep /= porous.size();
  EXPECT_NEAR(mean, 0.15, 0.02);
  EXPECT_NEAR(deep, std::exp(-0.3 / 0.15), 0.03);  // exponential tail
  for (double d : opaque) EXPECT_NEAR(d, 0.0, 1e-6);
}

TEST(LidarSimulator, FoliageIsDeterministicForASeed) {
  const HedgeShot a = shootHedge(0.3f, 0.15f, 5), b = shootHedge(0.3f, 0.15f, 5);
  const HedgeShot c = shootHedge(0.3f, 0.15f, 6);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    ASSERT_EQ(a.points[i], b.points[i]);
    ASSERT_EQ(a.intensities[i], b.intensities[i]);
  }
  EXPECT_EQ(a.stats.transmitted, b.stats.transmitted);
  EXPECT_GT(a.stats.transmitted, 0u);
  EXPECT_GT(a.stats.foliage_returns, 0u);
  // Another noise seed: other rays pass through, other depths.
  std::size_t differ = 0;
  for (std::size_t i = 0; i < std::min(a.points.size(), c.points.size()); ++i) {
    differ += a.points[i] != c.points[i] ? 1 : 0;
  }
  EXPECT_GT(differ, a.points.size() / 4);
}

TEST(LidarSimulator, IntensitiesSpreadByMaterial) {
  // One revolution of the demo drive's street: per class, the standard deviation of the
  // intensity bytes. Vehicles (paint, glass, plates, lamps) spread more than foliage, foliage
  // more than walls and ground; foliage is brighter than the road.
  ud::SimulationConfig c = demoConfig();
  c.drive.waypoints = {Eigen::Vector2d(20.0, -1.9), Eigen::Vector2d(60.0, -1.9)};
  auto sim = makeSim(c);
  ud::SimRevolution rev;
  sim->simulateNext(&rev);
  sim->simulateNext(&rev);
  ud::PacketDecoder decoder(sim->calibration(), ud::DecoderParams());
  urban_detection::CloudXYZIRT cloud;
  decodeRevolution(rev, decoder, &cloud, nullptr, nullptr);
  ASSERT_EQ(cloud.size(), rev.classes.size());
  struct Acc {
    double n = 0, sum = 0, sq = 0;
    double mean() const { return sum / n; }
    double sd() const { return std::sqrt(std::max(0.0, sq / n - mean() * mean())); }
  };
  std::map<ud::ObjectClass, Acc> acc;
  std::map<std::uint32_t, Acc> per_car;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto p = cloud[i];
    if (std::hypot(p.x, p.y) > 30.0) continue;  // near returns: little fading
    const auto cls = static_cast<ud::ObjectClass>(rev.classes[i]);
    Acc& a = acc[cls == ud::ObjectClass::kVan ? ud::ObjectClass::kCar : cls];
    a.n += 1, a.sum += p.intensity, a.sq += p.intensity * p.intensity;
    if (cls == ud::ObjectClass::kCar || cls == ud::ObjectClass::kVan) {
      Acc& b = per_car[rev.instance_ids[i]];
      b.n += 1, b.sum += p.intensity, b.sq += p.intensity * p.intensity;
    }
  }
  for (auto cls :
       {ud::ObjectClass::kCar, ud::ObjectClass::kPedestrian, ud::ObjectClass::kVegetation,
        ud::ObjectClass::kTerrain, ud::ObjectClass::kWall, ud::ObjectClass::kGround}) {
    ASSERT_GT(acc[cls].n, 200) << ud::toString(cls);
  }
  const double car = acc[ud::ObjectClass::kCar].sd(), veg = acc[ud::ObjectClass::kVegetation].sd();
  EXPECT_GT(car, 1.3 * veg);
  EXPECT_GT(veg, 1.3 * acc[ud::ObjectClass::kGround].sd());
  EXPECT_GT(acc[ud::ObjectClass::kPedestrian].sd(), acc[ud::ObjectClass::kWall].sd());
  EXPECT_GT(acc[ud::ObjectClass::kVegetation].mean(), acc[ud::ObjectClass::kGround].mean());
  // Each well-seen vehicle mixes materials by itself: most spread more than the foliage.
  int wide = 0, seen = 0;
  for (const auto& kv : per_car) {
    if (kv.second.n < 200) continue;
    ++seen;
    wide += kv.second.sd() > veg ? 1 : 0;
  }
  ASSERT_GE(seen, 3);
  EXPECT_GE(wide * 2, seen);
}

TEST(LidarSimulator, SameSeedSamePacketsOtherSeedOtherPackets) {
  const ud::SimulationConfig c = demoConfig();
  auto a = makeSim(c), b = makeSim(c);
  ud::SimulationConfig c2 = c;
  c2.sensor.noise_seed = 2;
  auto n = makeSim(c2);
  ud::SimRevolution ra, rb, rn;
  bool noise_differs = false;
  for (int r = 0; r < 3; ++r) {
    a->simulateNext(&ra);
    b->simulateNext(&rb);
    n->simulateNext(&rn);
    ASSERT_EQ(ra.packets.size(), rb.packets.size());
    for (std::size_t i = 0; i < ra.packets.size(); ++i) {
      ASSERT_EQ(ra.packets[i], rb.packets[i]) << "revolution " << r << " packet " << i;
    }
    EXPECT_EQ(ra.instance_ids, rb.instance_ids);
    EXPECT_EQ(ra.stamp_s, rb.stamp_s);
    noise_differs |= ra.packets != rn.packets;
  }
  EXPECT_TRUE(noise_differs);
  // reset() restarts the same stream.
  a->reset();
  a->simulateNext(&ra);
  auto fresh = makeSim(c);
  fresh->simulateNext(&rb);
  EXPECT_EQ(ra.packets, rb.packets);
}

TEST(LidarSimulator, DecodedCloudAndGroundTruthHaveEqualLengthAndOrder) {
  const ud::SimulationConfig c = demoConfig();
  auto sim = makeSim(c);
  ud::PacketDecoder decoder(sim->calibration(), ud::DecoderParams());
  ud::SimRevolution rev;
  urban_detection::CloudXYZIRT cloud;
  const double tol = 5 * c.sensor.range_noise_m + 0.01;
  for (int r = 0; r < 4; ++r) {
    sim->simulateNext(&rev);
    decodeRevolution(rev, decoder, &cloud, nullptr, nullptr);
    ASSERT_EQ(cloud.size(), rev.instance_ids.size());
    ASSERT_EQ(cloud.size(), rev.classes.size());
    ASSERT_EQ(cloud.size(), rev.stats.returns);
    ASSERT_GT(cloud.size(), 100000u);  // an enclosed street returns most of 133k rays
    // Point i, moved to the world with the platform pose at its own firing time, is the
    // i-th simulated hit.
    std::size_t bad = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const auto& p = cloud[i];
      const Eigen::Isometry3d pose = sim->sensorPose(rev.start_time_s + p.time);
      const Vector3d w = pose * Vector3d(p.x, p.y, p.z);
      if ((w - rev.world_points[i].cast<double>()).norm() > tol) ++bad;
    }
    EXPECT_EQ(bad, 0u) << "revolution " << r;
  }
}

TEST(LidarSimulator, LabelledPointsLieInsideTheirObjects) {
  std::set<ud::ObjectClass> seen;
  std::set<std::uint32_t> instances;
  // Drives starting at several places along the street (wide street, intersection, square,
  // narrow street, last street), one revolution each after the platform got moving.
  for (double start : {5.0, 35.0, 70.0, 110.0, 165.0}) {
    ud::SimulationConfig c = demoConfig();
    const double y = start > 94 && start < 139 ? -0.7 : -1.9;
    c.drive.waypoints = {Eigen::Vector2d(start, y), Eigen::Vector2d(start + 25.0, y)};
    auto sim = makeSim(c);
    const ud::Scene& scene = sim->scene();
    ud::PacketDecoder decoder(sim->calibration(), ud::DecoderParams());
    ud::SimRevolution rev;
    urban_detection::CloudXYZIRT cloud;
    const double margin = 5 * c.sensor.range_noise_m + 0.01;
    sim->simulateNext(&rev);
    sim->simulateNext(&rev);
    decodeRevolution(rev, decoder, &cloud, nullptr, nullptr);
    ASSERT_EQ(cloud.size(), rev.instance_ids.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const auto& p = cloud[i];
      const double t = rev.start_time_s + p.time;
      const Vector3d w = sim->sensorPose(t) * Vector3d(p.x, p.y, p.z);
      const std::uint32_t id = rev.instance_ids[i];
      const auto cls = static_cast<ud::ObjectClass>(rev.classes[i]);
      seen.insert(cls);
      if (id == 0) {
        ASSERT_TRUE(cls == ud::ObjectClass::kGround || cls == ud::ObjectClass::kWall ||
                    cls == ud::ObjectClass::kTerrain);
        continue;
      }
      instances.insert(id);
      ASSERT_LE(id, scene.objects.size());
      Eigen::AlignedBox3d box = scene.objectBounds(id, t);
      box.min().array() -= margin;
      box.max().array() += margin;
      ASSERT_TRUE(box.contains(w)) << ud::toString(cls) << " id " << id << " at " << w.transpose();
      // Tighter: inside one of the object's own primitives (+ margin).
      const ud::SceneObject& o = scene.objects[id - 1];
      bool inside = false;
      for (std::uint32_t k = 0; k < o.num_primitives && !inside; ++k) {
        inside = scene.primitives[o.first_primitive + k].contains(w, t, margin);
      }
      ASSERT_TRUE(inside) << ud::toString(cls) << " id " << id;
    }
  }
  for (auto cls : {ud::ObjectClass::kGround, ud::ObjectClass::kWall, ud::ObjectClass::kCar,
                   ud::ObjectClass::kPedestrian, ud::ObjectClass::kVegetation,
                   ud::ObjectClass::kTrunk, ud::ObjectClass::kPole, ud::ObjectClass::kTerrain}) {
    EXPECT_TRUE(seen.count(cls)) << ud::toString(cls);
  }
  EXPECT_GT(instances.size(), 40u);
}

TEST(LidarSimulator, RevolutionsFollowRpmCutAndTimestamps) {
  for (double rpm : {300.0, 600.0, 1200.0}) {
    ud::SimulationConfig c = demoConfig();
    c.sensor.rpm = rpm;
    auto sim = makeSim(c);
    ud::RevolutionCutter cutter(c.sensor.cut_angle_deg);
    const double packet_s = 6 * (ud::firingTimeOffset(1) - ud::firingTimeOffset(0));
    const double expected_packets = 60.0 / rpm / packet_s;
    ud::SimRevolution rev;
    double last_stamp = -1.0;
    for (int r = 0; r < 4; ++r) {
      sim->simulateNext(&rev);
      EXPECT_EQ(rev.index, static_cast<std::uint64_t>(r));
      EXPECT_NEAR(static_cast<double>(rev.packets.size()), expected_packets, 1.0) << rpm;
      EXPECT_DOUBLE_EQ(rev.stamp_s, rev.packet_stamps_s.front());
      for (std::size_t i = 0; i < rev.packets.size(); ++i) {
        const std::uint8_t* d = rev.packets[i].data();
        // The real cutter sees a new revolution exactly at our first packet.
        const bool starts = cutter.startsNewRevolution(ud::blockAzimuth(d, 0));
        if (r > 0) {
          EXPECT_EQ(starts, i == 0) << "rpm " << rpm << " rev " << r << " packet " << i;
        }
        if (last_stamp >= 0) {
          EXPECT_NEAR(rev.packet_stamps_s[i] - last_stamp, packet_s, 1e-6);
        }
        last_stamp = rev.packet_stamps_s[i];
        // Timestamp field: microseconds past the hour of the packet stamp.
        const std::uint32_t ts = d[1200] | (d[1201] << 8) | (d[1202] << 16) |
                                 (static_cast<std::uint32_t>(d[1203]) << 24);
        EXPECT_NEAR(ts, std::fmod(rev.packet_stamps_s[i], 3600.0) * 1e6, 1.0);
      }
    }
  }
}

TEST(LidarSimulator, RejectsInvalidSensorParams) {
  const ud::SimulationConfig c = demoConfig();
  for (auto mutate : std::vector<void (*)(ud::SimSensorParams*)>{
           [](ud::SimSensorParams* s) { s->rpm = 100; },
           [](ud::SimSensorParams* s) { s->height_m = -1; },
           [](ud::SimSensorParams* s) { s->max_range_m = 200; },
           [](ud::SimSensorParams* s) { s->range_noise_m = NAN; },
           [](ud::SimSensorParams* s) { s->dropout_probability = 1.5; }}) {
    ud::SimSensorParams s = c.sensor;
    mutate(&s);
    EXPECT_THROW(
        ud::LidarSimulator(ud::Scene(), c.scene, c.drive, ud::Calibration::nominalHdl64eS2(), s),
        std::invalid_argument);
  }
}

TEST(GroundTruthFile, RoundTripAndCorruptFiles) {
  const ud::SimulationConfig c = demoConfig();
  auto sim = makeSim(c);
  const std::string path = ud_test::tempPath("gt_roundtrip.udgt");
  std::vector<ud::GroundTruthFrame> written(2);
  {
    ud::GroundTruthWriter w(path);
    ud::SimRevolution rev;
    for (auto& f : written) {
      sim->simulateNext(&rev);
      ud::makeGroundTruthFrame(*sim, rev, &f);
      w.write(f);
    }
  }
  const auto read = ud::GroundTruthReader::readAll(path);
  ASSERT_EQ(read.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(read[i].revolution, written[i].revolution);
    EXPECT_EQ(read[i].stamp_s, written[i].stamp_s);
    EXPECT_EQ(read[i].num_packets, written[i].num_packets);
    EXPECT_EQ(read[i].instance_ids, written[i].instance_ids);
    EXPECT_EQ(read[i].classes, written[i].classes);
    EXPECT_TRUE(read[i].sensor_pose.isApprox(written[i].sensor_pose, 1e-12));
    ASSERT_EQ(read[i].objects.size(), written[i].objects.size());
    std::uint32_t total = 0;
    for (std::size_t k = 0; k < read[i].objects.size(); ++k) {
      EXPECT_EQ(read[i].objects[k].instance_id, written[i].objects[k].instance_id);
      EXPECT_EQ(read[i].objects[k].object_class, written[i].objects[k].object_class);
      EXPECT_EQ(read[i].objects[k].center, written[i].objects[k].center);
      EXPECT_EQ(read[i].objects[k].num_points, written[i].objects[k].num_points);
      total += read[i].objects[k].num_points;
    }
    // Per-object counts add up to the non-background points.
    std::uint32_t labelled = 0;
    for (auto id : read[i].instance_ids) labelled += id > 0 ? 1 : 0;
    EXPECT_EQ(total, labelled);
  }
  // Truncated: the first frame reads, the second is corrupt.
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = ud_test::tempPath("gt_cut.udgt");
  std::ofstream(cut, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size() - 100));
  ud::GroundTruthReader r(cut);
  ud::GroundTruthFrame f;
  EXPECT_EQ(r.next(&f), ud::GroundTruthReader::Result::kFrame);
  EXPECT_EQ(r.next(&f), ud::GroundTruthReader::Result::kCorrupt);
  EXPECT_FALSE(r.error().empty());
  EXPECT_THROW(ud::GroundTruthReader::readAll(cut), ud::GroundTruthError);
  // Not a ground-truth file at all.
  const std::string junk = ud_test::tempPath("gt_junk.udgt");
  std::ofstream(junk, std::ios::binary) << "this is not ground truth";
  EXPECT_THROW(ud::GroundTruthReader{junk}, ud::GroundTruthError);
  EXPECT_THROW(ud::GroundTruthReader{"/nonexistent/dir/file.udgt"}, ud::GroundTruthError);
  std::remove(path.c_str());
  std::remove(cut.c_str());
  std::remove(junk.c_str());
}
