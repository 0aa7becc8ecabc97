// The simulated HDL-64E: packets decoded by the real PacketDecoder must reproduce the simulated
// hits, in the order of the ground truth; ranges of a single box are computed by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>

#include "urban_detection/core/ground_truth.h"
#include "urban_detection/core/hdl64e_packet.h"
#include "urban_detection/core/lidar_simulator.h"
#include "urban_detection/core/simulation_config.h"
#include "test_files.h"

namespace ud = urban_detection::core;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;

ud::SimulationConfig demoConfig() {
  return ud::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
}

std::unique_ptr<ud::LidarSimulator> makeSim(const ud::SimulationConfig& c) {
  return std::make_unique<ud::LidarSimulator>(ud::generateScene(c.scene, c.drive), c.scene,
                                              c.drive, ud::Calibration::nominalHdl64eS2(),
                                              c.sensor);
}

// Decodes a revolution the way PacketToCloud does (packet time relative to the scan stamp).
void decodeRevolution(const ud::SimRevolution& rev, const ud::PacketDecoder& decoder,
                      urban_detection::CloudXYZIRT* cloud, std::vector<std::uint8_t>* lasers,
                      std::vector<std::uint16_t>* azimuths) {
  cloud->clear();
  for (std::size_t i = 0; i < rev.packets.size(); ++i) {
    ud::DecodeStats stats;
    ASSERT_EQ(decoder.decode(rev.packets[i].data(), rev.packets[i].size(),
                             rev.packet_stamps_s[i] - rev.stamp_s, cloud, &stats, lasers,
                             azimuths),
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
        ASSERT_TRUE(cls == ud::ObjectClass::kGround || cls == ud::ObjectClass::kWall);
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
                   ud::ObjectClass::kTrunk, ud::ObjectClass::kPole}) {
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
    EXPECT_THROW(ud::LidarSimulator(ud::Scene(), c.scene, c.drive,
                                    ud::Calibration::nominalHdl64eS2(), s),
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
  std::ofstream(cut, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size() - 100));
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
