// HDL-64E decoding: each correction term on crafted packets against closed-form values, bad
// packets, encoder/decoder round trips and revolution cutting.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace uc = urban_detection::core;
using urban_detection::CloudXYZIRT;
using urban_detection::PointXYZIRT;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Nominal geometry with every correction of laser `laser` zeroed, vertical angle 0.
uc::Calibration plainCalibration(int laser = 0) {
  uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  cal.lasers[laser].vert_correction_rad = 0.0;
  cal.finalize();
  return cal;
}

// Firings whose azimuths are all different (so the packet is single-return), no returns.
std::array<uc::Firing, 6> emptyFirings(std::uint16_t first_azimuth) {
  std::array<uc::Firing, 6> f{};
  for (int i = 0; i < 6; ++i)
    f[i].azimuth = static_cast<std::uint16_t>((first_azimuth + 17 * i) % 36000);
  return f;
}

// Decodes a packet carrying one return of `laser` at raw azimuth/distance/intensity in firing 0.
PointXYZIRT decodeOne(const uc::Calibration& cal, int laser, std::uint16_t azimuth,
                      std::uint16_t raw, std::uint8_t intensity = 0) {
  auto firings = emptyFirings(azimuth);
  firings[0].distance[laser] = raw;
  firings[0].intensity[laser] = intensity;
  const uc::RawPacket packet = uc::PacketEncoder(cal).encode(firings.data(), 0);
  uc::DecoderParams params;
  params.min_range_m = 0.1;
  uc::PacketDecoder decoder(cal, params);
  CloudXYZIRT cloud;
  uc::DecodeStats stats;
  EXPECT_EQ(decoder.decode(packet.data(), packet.size(), 0.0, &cloud, &stats),
            uc::PacketStatus::kOk);
  EXPECT_EQ(cloud.size(), 1u);
  EXPECT_EQ(stats.no_return, 6u * 64u - 1u);
  return cloud.empty() ? PointXYZIRT{} : cloud[0];
}

void expectPoint(const PointXYZIRT& p, double x, double y, double z, double tol = 1e-4) {
  EXPECT_NEAR(p.x, x, tol);
  EXPECT_NEAR(p.y, y, tol);
  EXPECT_NEAR(p.z, z, tol);
}

}  // namespace

// ---- Each correction term on its own ----------------------------------------------------------

TEST(Hdl64eDecode, PlainGeometryAzimuthIsClockwiseFromX) {
  const uc::Calibration cal = plainCalibration();
  // raw 5000 * 2 mm = 10 m. Azimuth 0 looks along +x, 90 deg along -y (the head spins clockwise
  // seen from above), 180 deg along -x.
  expectPoint(decodeOne(cal, 0, 0, 5000), 10.0, 0.0, 0.0);
  expectPoint(decodeOne(cal, 0, 9000, 5000), 0.0, -10.0, 0.0);
  expectPoint(decodeOne(cal, 0, 18000, 5000), -10.0, 0.0, 0.0);
  expectPoint(decodeOne(cal, 0, 4500, 5000), 10.0 / std::sqrt(2.0), -10.0 / std::sqrt(2.0), 0.0);
}

TEST(Hdl64eDecode, RotationalCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].rot_correction_rad = 0.1;  // the laser looks 0.1 rad counter-clockwise
  cal.finalize();
  // theta = azimuth - rot = -0.1 rad: x = 10 cos 0.1, y = +10 sin 0.1.
  expectPoint(decodeOne(cal, 0, 0, 5000), 10.0 * std::cos(0.1), 10.0 * std::sin(0.1), 0.0);
  // azimuth 30 deg: theta = 30 deg - 0.1 rad.
  const double t = 30 * kDeg - 0.1;
  expectPoint(decodeOne(cal, 0, 3000, 5000), 10.0 * std::cos(t), -10.0 * std::sin(t), 0.0);
}

TEST(Hdl64eDecode, VerticalCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].vert_correction_rad = -0.2;
  cal.finalize();
  expectPoint(decodeOne(cal, 0, 0, 5000), 10.0 * std::cos(0.2), 0.0, -10.0 * std::sin(0.2));
}

TEST(Hdl64eDecode, DistanceCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].dist_correction_m = 1.5;
  cal.finalize();
  // 2500 * 2 mm + 1.5 m = 6.5 m.
  expectPoint(decodeOne(cal, 0, 0, 2500), 6.5, 0.0, 0.0);
  // two-point terms are ignored when not available.
  cal.lasers[0].dist_correction_x_m = 1.7;
  cal.lasers[0].dist_correction_y_m = 1.1;
  cal.finalize();
  expectPoint(decodeOne(cal, 0, 4500, 2500), 6.5 / std::sqrt(2.0), -6.5 / std::sqrt(2.0), 0.0);
}

TEST(Hdl64eDecode, TwoPointNearRangeCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].dist_correction_m = 1.5;
  cal.lasers[0].dist_correction_x_m = 1.6;
  cal.lasers[0].dist_correction_y_m = 1.3;
  cal.lasers[0].two_pt_correction_available = true;
  cal.finalize();
  // Azimuth 90 deg, the beam is along the Velodyne X axis (ROS -y), |X| = d.
  // At |X| = 2.4 m the correction is dist_correction_x - dist_correction = +0.1 m:
  // raw (2.4 - 1.5) / 2 mm = 450.
  expectPoint(decodeOne(cal, 0, 9000, 450), 0.0, -2.5, 0.0);
  // At |X| = 25.04 m the correction vanishes: raw (25.04 - 1.5) / 2 mm = 11770.
  expectPoint(decodeOne(cal, 0, 9000, 11770), 0.0, -25.04, 0.0);
  // Halfway, |X| = 13.72 m: correction = 0.1 * (1 - (13.72 - 2.4) / 22.64) = 0.05 m.
  expectPoint(decodeOne(cal, 0, 9000, 6110), 0.0, -13.77, 0.0);
  // Azimuth 0, beam along the Velodyne Y axis (ROS +x): at |Y| = 1.93 m, correction -0.2 m.
  // d = 1.93 needs raw (1.93 - 1.5) / 2 mm = 215.
  expectPoint(decodeOne(cal, 0, 0, 215), 1.73, 0.0, 0.0);
  // Oblique, 30 deg: the X and Y components are corrected separately.
  const double d = 2000 * 0.002 + 1.5;  // 5.5 m
  const double ax = std::fabs(d * std::sin(30 * kDeg)), ay = d * std::cos(30 * kDeg);
  const double cx = 0.1 * (1.0 - (ax - 2.4) / (25.04 - 2.4));
  const double cy = -0.2 * (1.0 - (ay - 1.93) / (25.04 - 1.93));
  expectPoint(decodeOne(cal, 0, 3000, 2000), (d + cy) * std::cos(30 * kDeg),
              -(d + cx) * std::sin(30 * kDeg), 0.0);
  // z uses the Y-corrected distance (as the Velodyne manual does).
  cal.lasers[0].vert_correction_rad = -0.1;
  cal.finalize();
  const double ay2 = d * std::cos(0.1) * std::cos(30 * kDeg);
  const double cy2 = -0.2 * (1.0 - (ay2 - 1.93) / (25.04 - 1.93));
  EXPECT_NEAR(decodeOne(cal, 0, 3000, 2000).z, -(d + cy2) * std::sin(0.1), 1e-4);
}

TEST(Hdl64eDecode, VerticalOffsetCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].vert_offset_correction_m = 0.2;
  cal.finalize();
  // Horizontal beam: the origin is raised by 0.2 m.
  expectPoint(decodeOne(cal, 0, 0, 5000), 10.0, 0.0, 0.2);
  // Tilted beam (v = -0.1 rad): the origin is offset perpendicular to the beam,
  // horizontal distance d cos v - vo sin v, height d sin v + vo cos v.
  cal.lasers[0].vert_correction_rad = -0.1;
  cal.finalize();
  expectPoint(decodeOne(cal, 0, 0, 5000), 10.0 * std::cos(0.1) + 0.2 * std::sin(0.1), 0.0,
              -10.0 * std::sin(0.1) + 0.2 * std::cos(0.1));
}

TEST(Hdl64eDecode, HorizontalOffsetCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].horiz_offset_correction_m = 0.03;
  cal.finalize();
  // Azimuth 0: the beam is displaced 3 cm to the left (Velodyne -X = ROS +y).
  expectPoint(decodeOne(cal, 0, 0, 5000), 10.0, 0.03, 0.0);
  // Azimuth 90 deg: displaced forward.
  expectPoint(decodeOne(cal, 0, 9000, 5000), 0.03, -10.0, 0.0);
}

TEST(Hdl64eDecode, IntensityFocalCorrection) {
  uc::Calibration cal = plainCalibration();
  cal.lasers[0].focal_distance = 13.107;  // one tenth of the 131.07 m full scale
  cal.lasers[0].focal_slope = 1.5;
  cal.finalize();
  // raw 6553.5 ~ one tenth of full scale: at the focal distance the correction is ~0.
  const double at_focus =
      100.0 + 1.5 * std::fabs(256.0 * 0.81 - 256.0 * std::pow(1.0 - 6554 / 65535.0, 2));
  EXPECT_NEAR(decodeOne(cal, 0, 0, 6554, 100).intensity, at_focus, 1e-3);
  EXPECT_NEAR(at_focus, 100.0, 0.01);
  // At 2 m (raw 1000): 100 + 1.5 * |207.36 - 256 (1 - 1000/65535)^2|.
  const double near = 100.0 + 1.5 * std::fabs(207.36 - 256.0 * std::pow(1.0 - 1000 / 65535.0, 2));
  EXPECT_NEAR(decodeOne(cal, 0, 0, 1000, 100).intensity, near, 1e-3);
  EXPECT_GT(near, 150.0);
  // Clamped to [min_intensity, max_intensity].
  cal.lasers[0].min_intensity = 120;
  cal.lasers[0].max_intensity = 140;
  cal.finalize();
  EXPECT_FLOAT_EQ(decodeOne(cal, 0, 0, 1000, 100).intensity, 140.0f);
  EXPECT_FLOAT_EQ(decodeOne(cal, 0, 0, 6554, 100).intensity, 120.0f);
}

TEST(Hdl64eDecode, RingTimeAndLaserBookkeeping) {
  const uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  auto firings = emptyFirings(1000);
  for (int f = 0; f < 6; ++f) {
    for (int l = 0; l < 64; ++l) firings[f].distance[l] = 5000;
  }
  const uc::RawPacket packet = uc::PacketEncoder(cal).encode(firings.data(), 123456);
  uc::PacketDecoder decoder(cal, uc::DecoderParams{});
  CloudXYZIRT cloud;
  std::vector<std::uint8_t> lasers;
  std::vector<std::uint16_t> azimuths;
  uc::DecodeStats stats;
  ASSERT_EQ(decoder.decode(packet.data(), packet.size(), 0.5, &cloud, &stats, &lasers, &azimuths),
            uc::PacketStatus::kOk);
  ASSERT_EQ(cloud.size(), 384u);
  ASSERT_EQ(lasers.size(), 384u);
  ASSERT_EQ(azimuths.size(), 384u);
  EXPECT_EQ(stats.points, 384u);
  EXPECT_EQ(cloud.width, 384u);
  EXPECT_EQ(cloud.height, 1u);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int firing = static_cast<int>(i / 64);
    const int laser = static_cast<int>(i % 64);
    EXPECT_EQ(lasers[i], laser);
    EXPECT_EQ(azimuths[i], firings[firing].azimuth);
    // Nominal: laser 0 is the highest beam, laser 63 the lowest.
    EXPECT_EQ(cloud[i].ring, 63 - laser);
    EXPECT_NEAR(cloud[i].time, 0.5 + firing * 48e-6, 1e-7);
    const double elevation = std::atan2(cloud[i].z, std::hypot(cloud[i].x, cloud[i].y));
    EXPECT_NEAR(elevation / kDeg, 2.0 - laser * 26.8 / 63.0, 1e-4);
  }
  EXPECT_DOUBLE_EQ(uc::firingTimeOffset(3), 3 * 48e-6);
  EXPECT_EQ(uc::blockAzimuth(packet.data(), 4), firings[2].azimuth);
}

// ---- Bad input --------------------------------------------------------------------------------

class BadPackets : public ::testing::Test {
 protected:
  BadPackets() : cal_(uc::Calibration::nominalHdl64eS2()), decoder_(cal_, uc::DecoderParams{}) {
    auto firings = emptyFirings(200);
    for (auto& f : firings) f.distance.fill(5000);
    good_ = uc::PacketEncoder(cal_).encode(firings.data(), 0);
    cloud_.push_back(PointXYZIRT{});  // pre-existing content must stay untouched
  }
  uc::PacketStatus decode(const std::uint8_t* data, std::size_t size) {
    return decoder_.decode(data, size, 0.0, &cloud_, &stats_);
  }
  void expectNothingEmitted() {
    EXPECT_EQ(cloud_.size(), 1u);
    EXPECT_EQ(stats_.points, 0u);
  }
  uc::Calibration cal_;
  uc::PacketDecoder decoder_;
  uc::RawPacket good_;
  CloudXYZIRT cloud_;
  uc::DecodeStats stats_;
};

TEST_F(BadPackets, WrongSize) {
  EXPECT_EQ(decode(good_.data(), 1205), uc::PacketStatus::kWrongSize);
  std::vector<std::uint8_t> longer(good_.begin(), good_.end());
  longer.push_back(0);
  EXPECT_EQ(decode(longer.data(), longer.size()), uc::PacketStatus::kWrongSize);
  EXPECT_EQ(decode(nullptr, 0), uc::PacketStatus::kWrongSize);
  EXPECT_EQ(stats_.packets, 3u);
  EXPECT_EQ(stats_.bad_packets, 3u);
  expectNothingEmitted();
}

TEST_F(BadPackets, UnknownBlockIdInLastBlockRejectsWholePacket) {
  uc::RawPacket p = good_;
  p[11 * 100] = 0x12;  // block 11 id
  EXPECT_EQ(decode(p.data(), p.size()), uc::PacketStatus::kUnknownBlockId);
  EXPECT_EQ(stats_.bad_packets, 1u);
  expectNothingEmitted();
}

TEST_F(BadPackets, AzimuthOutOfRange) {
  uc::RawPacket p = good_;
  p[7 * 100 + 2] = 36000 & 0xFF;
  p[7 * 100 + 3] = 36000 >> 8;
  EXPECT_EQ(decode(p.data(), p.size()), uc::PacketStatus::kBadAzimuth);
  p[7 * 100 + 2] = 0xFF;
  p[7 * 100 + 3] = 0xFF;
  EXPECT_EQ(decode(p.data(), p.size()), uc::PacketStatus::kBadAzimuth);
  expectNothingEmitted();
}

TEST_F(BadPackets, DualReturnIsRejectedNotMisread) {
  // Dual-return layout: the strongest and last echo of one firing of one bank in two blocks at
  // the same azimuth.
  auto firings = emptyFirings(500);
  for (auto& f : firings) f.distance.fill(5000);
  firings[1].azimuth = firings[0].azimuth;
  const uc::RawPacket p = uc::PacketEncoder(cal_).encode(firings.data(), 0);
  EXPECT_EQ(decode(p.data(), p.size()), uc::PacketStatus::kDualReturn);
  EXPECT_STRNE(uc::toString(uc::PacketStatus::kDualReturn), uc::toString(uc::PacketStatus::kOk));
  expectNothingEmitted();
}

TEST_F(BadPackets, StoppedMotorIsNamedNotTakenForDualReturn) {
  // A motor that stands still: every firing of the packet at one azimuth.
  auto firings = emptyFirings(500);
  for (auto& f : firings) {
    f.distance.fill(5000);
    f.azimuth = firings[0].azimuth;
  }
  const uc::RawPacket p = uc::PacketEncoder(cal_).encode(firings.data(), 0);
  EXPECT_EQ(decode(p.data(), p.size()), uc::PacketStatus::kStoppedMotor);
  EXPECT_NE(std::string(uc::toString(uc::PacketStatus::kStoppedMotor)).find("motor is stopped"),
            std::string::npos);
  expectNothingEmitted();
}

TEST_F(BadPackets, GarbageBytesNeverEmitHalfPackets) {
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> byte(0, 255);
  int rejected = 0;
  for (int i = 0; i < 2000; ++i) {
    uc::RawPacket p;
    for (auto& b : p) b = static_cast<std::uint8_t>(byte(rng));
    if (i % 2 == 1) {  // plausible headers, garbage elsewhere: must decode without crashing
      for (int b = 0; b < 12; ++b) {
        p[b * 100] = 0xFF;
        p[b * 100 + 1] = b % 2 ? 0xDD : 0xEE;
        const int az = (b / 2) * 20 + i % 30000;
        p[b * 100 + 2] = az & 0xFF;
        p[b * 100 + 3] = az >> 8;
      }
    }
    const std::size_t before = cloud_.size();
    const uc::PacketStatus s = decode(p.data(), p.size());
    if (s != uc::PacketStatus::kOk) {
      ++rejected;
      EXPECT_EQ(cloud_.size(), before);
    }
  }
  EXPECT_GE(rejected, 1000);  // all fully random packets
  EXPECT_EQ(stats_.packets, 2000u);
  for (const auto& pt : cloud_.points) {
    EXPECT_TRUE(std::isfinite(pt.x) && std::isfinite(pt.y) && std::isfinite(pt.z));
    EXPECT_LE(std::sqrt(pt.x * pt.x + pt.y * pt.y + pt.z * pt.z), 130.5f);
  }
}

TEST_F(BadPackets, ZeroAndMaximalDistancesAreCountedNotEmitted) {
  auto firings = emptyFirings(300);
  firings[0].distance.fill(0xFFFF);  // 131.07 m > max_range 130 m
  firings[1].distance.fill(200);     // 0.4 m < min_range 0.9 m
  firings[2].distance.fill(5000);
  const uc::RawPacket p = uc::PacketEncoder(cal_).encode(firings.data(), 0);
  EXPECT_EQ(decode(p.data(), p.size()), uc::PacketStatus::kOk);
  EXPECT_EQ(stats_.out_of_range, 128u);
  EXPECT_EQ(stats_.no_return, 3u * 64u);
  EXPECT_EQ(stats_.points, 64u);
  EXPECT_EQ(cloud_.size(), 65u);
}

// ---- Encoder / decoder round trip --------------------------------------------------------------

namespace {

void roundTrip(const uc::Calibration& cal, int trials_per_laser) {
  uc::PacketEncoder encoder(cal);
  uc::DecoderParams params;
  params.min_range_m = 0.5;
  params.max_range_m = 131.0;
  uc::PacketDecoder decoder(cal, params);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> az(0, 35999);
  std::uniform_int_distribution<int> dist(600, 60000);  // ~1.2 m .. 120 m raw
  double worst = 0.0;
  int compared = 0;
  for (int trial = 0; trial < trials_per_laser; ++trial) {
    auto firings = emptyFirings(static_cast<std::uint16_t>(az(rng)));
    for (int l = 0; l < 64; ++l) firings[0].distance[l] = static_cast<std::uint16_t>(dist(rng));
    const uc::RawPacket p = encoder.encode(firings.data(), 0);
    CloudXYZIRT cloud;
    std::vector<std::uint8_t> lasers;
    ASSERT_EQ(decoder.decode(p.data(), p.size(), 0.0, &cloud, nullptr, &lasers, nullptr),
              uc::PacketStatus::kOk);
    // Invert every decoded point, re-encode, decode again.
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      std::uint16_t raw_az = 0, raw_d = 0;
      ASSERT_TRUE(encoder.invert(lasers[i], cloud[i].x, cloud[i].y, cloud[i].z, &raw_az, &raw_d));
      EXPECT_EQ(raw_az, firings[0].azimuth) << "laser " << int(lasers[i]);
      EXPECT_NEAR(raw_d, firings[0].distance[lasers[i]], 1.0) << "laser " << int(lasers[i]);
      // A single-laser packet at the recovered azimuth.
      auto one = emptyFirings(raw_az);
      one[0].distance[lasers[i]] = raw_d;
      const uc::RawPacket q = encoder.encode(one.data(), 0);
      CloudXYZIRT back;
      ASSERT_EQ(decoder.decode(q.data(), q.size(), 0.0, &back, nullptr), uc::PacketStatus::kOk);
      ASSERT_EQ(back.size(), 1u);
      const double e =
          std::sqrt(std::pow(back[0].x - cloud[i].x, 2) + std::pow(back[0].y - cloud[i].y, 2) +
                    std::pow(back[0].z - cloud[i].z, 2));
      worst = std::max(worst, e);
      ++compared;
    }
  }
  EXPECT_LT(worst, 0.002) << "worst round-trip error over " << compared << " points";
  EXPECT_GE(compared, trials_per_laser * 60);
}

}  // namespace

TEST(Hdl64eRoundTrip, NominalGeometry) {
  roundTrip(uc::Calibration::nominalHdl64eS2(), 60);
}

TEST(Hdl64eRoundTrip, SztakiCalibration) {
  const std::string path = std::string(UD_SHARED_DATA) + "/calibration/64e_s2.1-sztaki.yaml";
  if (!std::ifstream(path).good()) GTEST_SKIP() << "SZTAKI calibration not found: " << path;
  roundTrip(uc::loadCalibration(path), 60);
}

TEST(Hdl64eRoundTrip, SyntheticOffsetsAndTwoPoint) {
  // Every correction term large, so the inversion is exercised without shared data.
  uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  for (int l = 0; l < 64; ++l) {
    uc::LaserCorrection& c = cal.lasers[l];
    c.rot_correction_rad = (l % 7 - 3) * 0.04;
    c.dist_correction_m = 1.2 + 0.01 * (l % 5);
    c.dist_correction_x_m = c.dist_correction_m + 0.05 * ((l % 3) - 1);
    c.dist_correction_y_m = c.dist_correction_m - 0.04 * ((l % 4) - 1.5);
    c.two_pt_correction_available = true;
    c.vert_offset_correction_m = 0.2 - 0.002 * l;
    c.horiz_offset_correction_m = l % 2 ? 0.026 : -0.026;
  }
  cal.finalize();
  roundTrip(cal, 60);
}

TEST(Hdl64eRoundTrip, RayMatchesDecoderInFarFieldModel) {
  uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  for (int l = 0; l < 64; ++l) {
    cal.lasers[l].rot_correction_rad = 0.03 * (l % 5 - 2);
    cal.lasers[l].dist_correction_m = 1.3;
    cal.lasers[l].vert_offset_correction_m = 0.15;
    cal.lasers[l].horiz_offset_correction_m = l % 2 ? 0.026 : -0.026;
  }
  cal.finalize();
  uc::PacketEncoder encoder(cal);
  for (int l : {0, 17, 40, 63}) {
    for (std::uint16_t a : {0, 4321, 18000, 35999}) {
      float o[3], d[3];
      encoder.ray(l, a, o, d);
      EXPECT_NEAR(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1.0, 1e-6);
      const std::uint16_t raw = 9000;  // 18 m + 1.3 m
      const PointXYZIRT p = decodeOne(cal, l, a, raw);
      const double s = raw * 0.002 + 1.3;
      expectPoint(p, o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2], 2e-4);
      std::uint16_t r = 0;
      ASSERT_TRUE(encoder.rawDistance(l, s, &r));
      EXPECT_EQ(r, raw);
    }
  }
  std::uint16_t r;
  EXPECT_FALSE(encoder.rawDistance(0, 200.0, &r));
  EXPECT_FALSE(encoder.rawDistance(0, 1.3, &r));  // raw 0 is "no return"
}

TEST(Hdl64eRoundTrip, InvertRejectsUnreachablePoints) {
  const uc::Calibration cal = plainCalibration();  // laser 0 horizontal, no corrections
  uc::PacketEncoder encoder(cal);
  std::uint16_t a, d;
  EXPECT_FALSE(encoder.invert(0, 500.0, 0.0, 0.0, &a, &d));         // beyond 131 m
  EXPECT_FALSE(encoder.invert(64, 5.0, 0.0, 0.0, &a, &d));          // no such laser
  EXPECT_FALSE(encoder.invert(0, std::nan(""), 0.0, 0.0, &a, &d));  // NaN
  EXPECT_TRUE(encoder.invert(0, 5.0, 0.0, 0.0, &a, &d));
  EXPECT_EQ(a, 0);
  EXPECT_EQ(d, 2500);
}

// ---- Revolution cutting ------------------------------------------------------------------------

namespace {

// Packet first-block azimuths of a sensor spinning at `rpm` for `seconds`, starting at
// `phase_deg`, one packet per 6 firings of 48 us.
std::vector<std::uint16_t> packetAzimuths(double rpm, double seconds, double phase_deg) {
  std::vector<std::uint16_t> out;
  const double packet_s = 6 * uc::kFiringPeriodS;
  for (double t = 0; t < seconds; t += packet_s) {
    const double deg = std::fmod(phase_deg + t * rpm / 60.0 * 360.0, 360.0);
    out.push_back(static_cast<std::uint16_t>(static_cast<int>(deg * 100.0) % 36000));
  }
  return out;
}

}  // namespace

TEST(RevolutionCutter, WholeRevolutionsAt300To1200Rpm) {
  for (double rpm : {300.0, 600.0, 1200.0}) {
    for (double cut : {0.0, 90.0, 359.5}) {
      SCOPED_TRACE("rpm " + std::to_string(rpm) + " cut " + std::to_string(cut));
      const auto az = packetAzimuths(rpm, 6 * 60.0 / rpm, 37.0);  // 2160 deg of rotation
      uc::RevolutionCutter cutter(cut);
      std::vector<std::size_t> starts;
      for (std::size_t i = 0; i < az.size(); ++i) {
        if (cutter.startsNewRevolution(az[i])) starts.push_back(i);
      }
      ASSERT_EQ(starts.size(), 6u);  // 6 crossings in 6 revolutions from 37 deg
      const double expected = 60.0 / rpm / (6 * uc::kFiringPeriodS);  // packets per revolution
      const double step_deg = 360.0 / expected;
      for (std::size_t k = 0; k + 1 < starts.size(); ++k) {
        const double n = static_cast<double>(starts[k + 1] - starts[k]);
        EXPECT_LE(std::fabs(n - expected), 1.0);
        // The first packet of a revolution is within one packet step past the cut angle.
        const double past = std::fmod(az[starts[k]] / 100.0 - cut + 720.0, 360.0);
        EXPECT_LT(past, step_deg + 0.01);
      }
    }
  }
}

TEST(RevolutionCutter, FirstPacketAndResetDoNotStartRevolution) {
  uc::RevolutionCutter cutter(0.0);
  EXPECT_FALSE(cutter.startsNewRevolution(35990));
  EXPECT_TRUE(cutter.startsNewRevolution(10));
  EXPECT_FALSE(cutter.startsNewRevolution(200));
  EXPECT_FALSE(cutter.startsNewRevolution(200));  // stationary head
  cutter.reset();
  EXPECT_FALSE(cutter.startsNewRevolution(5));
  uc::RevolutionCutter wrapped(-90.0);  // = 270 deg
  EXPECT_DOUBLE_EQ(wrapped.cutAngleDeg(), 270.0);
  EXPECT_FALSE(wrapped.startsNewRevolution(26990));
  EXPECT_TRUE(wrapped.startsNewRevolution(27000));
}

// Hostile streams: out-of-order and stray packets never cut a revolution; a real
// jump of the stream is followed after one confirming packet.
TEST(RevolutionCutter, ReorderedAndStrayPacketsDoNotCut) {
  using Step = uc::RevolutionCutter::Step;
  const auto az = packetAzimuths(600.0, 3 * 0.1, 37.0);  // three revolutions from 37 deg
  auto cuts = [](const std::vector<std::uint16_t>& stream, std::vector<Step>* steps = nullptr) {
    uc::RevolutionCutter cutter(0.0);
    std::vector<std::size_t> at;
    for (std::size_t i = 0; i < stream.size(); ++i) {
      const Step s = cutter.step(stream[i]);
      if (steps) steps->push_back(s);
      if (s == Step::kCut) at.push_back(i);
    }
    return at;
  };
  const std::vector<std::size_t> clean = cuts(az);
  ASSERT_EQ(clean.size(), 3u);
  // One swapped pair per revolution, one of them across the cut angle.
  std::vector<std::uint16_t> swapped = az;
  for (std::size_t k = 0; k < clean.size(); ++k) {
    const std::size_t i = k == 0 ? clean[k] - 1 : clean[k] - 100;  // k = 0: the pair around the cut
    std::swap(swapped[i], swapped[i + 1]);
  }
  std::vector<Step> steps;
  const std::vector<std::size_t> with_swaps = cuts(swapped, &steps);
  ASSERT_EQ(with_swaps.size(), 3u);
  EXPECT_EQ(with_swaps[0], clean[0] - 1);  // the late packet of the old revolution follows it
  EXPECT_EQ(with_swaps[1], clean[1]);
  EXPECT_EQ(std::count(steps.begin(), steps.end(), Step::kReordered), 3);
  // A stray packet per revolution, anywhere on the circle (another sender, garbage azimuth),
  // one of them just past the cut angle while the head is far from it.
  std::vector<std::uint16_t> strays;
  for (std::size_t i = 0; i < az.size(); ++i) {
    strays.push_back(az[i]);
    if (i % 347 == 200)
      strays.push_back(i < 347 ? 10 : static_cast<std::uint16_t>((az[i] + 18000) % 36000));
  }
  steps.clear();
  EXPECT_EQ(cuts(strays, &steps).size(), 3u);
  EXPECT_EQ(std::count(steps.begin(), steps.end(), Step::kJump), 3);
  // Packets lost across the cut angle (30 deg gap): the stream is followed, the cut seen once,
  // one packet late.
  std::vector<std::uint16_t> lost;
  for (std::size_t i = 0; i < az.size(); ++i) {
    if (i + 15 < clean[1] || i >= clean[1] + 15) lost.push_back(az[i]);
  }
  EXPECT_EQ(cuts(lost).size(), 3u);
  // A stream that restarts behind the head (a replay loop): kRestart, then whole revolutions.
  std::vector<std::uint16_t> restart(az.begin(), az.begin() + 500);
  restart.insert(restart.end(), az.begin(), az.end());
  steps.clear();
  cuts(restart, &steps);
  EXPECT_EQ(std::count(steps.begin(), steps.end(), Step::kRestart), 1);
}

TEST(RevolutionBoundary, InvalidAndStrayPacketsAreSkipped) {
  const uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  uc::PacketEncoder encoder(cal);
  uc::RevolutionBoundary boundary(0.0);
  using Action = uc::RevolutionBoundary::Action;
  auto packetAt = [&](std::uint16_t az) {
    auto f = emptyFirings(az);
    return encoder.encode(f.data(), 0);
  };
  EXPECT_EQ(boundary.add(packetAt(35000).data(), uc::kPacketSize), Action::kOpen);
  uc::RawPacket bad = packetAt(35100);
  bad[2] = 0xFF;  // first block azimuth 0xFFxx >= 36000
  bad[3] = 0xFF;
  EXPECT_EQ(boundary.add(bad.data(), bad.size()), Action::kSkip);
  EXPECT_EQ(boundary.lastStatus(), uc::PacketStatus::kBadAzimuth);
  EXPECT_EQ(boundary.add(packetAt(9000).data(), uc::kPacketSize), Action::kSkip);  // a stray
  EXPECT_EQ(boundary.lastStatus(), uc::PacketStatus::kOk);
  EXPECT_EQ(boundary.add(packetAt(35104).data(), uc::kPacketSize), Action::kAppend);
  EXPECT_EQ(boundary.add(packetAt(35600).data(), uc::kPacketSize), Action::kAppend);
  EXPECT_EQ(boundary.add(packetAt(5).data(), uc::kPacketSize), Action::kDrop);  // first cut
  EXPECT_EQ(boundary.invalidPackets(), 1u);
  EXPECT_EQ(boundary.strayPackets(), 1u);
  EXPECT_EQ(boundary.openPackets(), 1u);
  EXPECT_STREQ(uc::revolutionSizeProblem(347, 347), "");
  EXPECT_STREQ(uc::revolutionSizeProblem(300, 347), "too few packets");
  EXPECT_STREQ(uc::revolutionSizeProblem(694, 347), "too many packets");
  EXPECT_STREQ(uc::revolutionSizeProblem(5, 0), "");
}

// Other Velodyne models: their blocks all carry the upper-block id; refused and named.
TEST(PacketDecoder, OtherModelsAreRefusedAndNamed) {
  const uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  auto f = emptyFirings(1000);
  uc::RawPacket p = uc::PacketEncoder(cal).encode(f.data(), 0);
  ASSERT_EQ(uc::PacketDecoder::validate(p.data(), p.size()), uc::PacketStatus::kOk);
  for (int b = 0; b < uc::kBlocksPerPacket; ++b) {  // VLP-16 layout: every block 0xFF 0xEE
    p[static_cast<std::size_t>(b) * 100] = 0xFF;
    p[static_cast<std::size_t>(b) * 100 + 1] = 0xEE;
  }
  p[1204] = 0x37;
  p[1205] = 0x22;
  EXPECT_EQ(uc::PacketDecoder::validate(p.data(), p.size()), uc::PacketStatus::kOtherModel);
  EXPECT_EQ(uc::velodyneModelName(p.data(), p.size()), "VLP-16 (strongest return)");
  p[1204] = 0x39;
  p[1205] = 0x21;
  EXPECT_EQ(uc::velodyneModelName(p.data(), p.size()), "HDL-32E (dual return)");
  p[1205] = 0x99;
  EXPECT_EQ(uc::velodyneModelName(p.data(), p.size()),
            "an unknown model (factory bytes 0x39 0x99)");
  uc::PacketDecoder decoder(cal, uc::DecoderParams());
  CloudXYZIRT cloud;
  uc::DecodeStats stats;
  EXPECT_EQ(decoder.decode(p.data(), p.size(), 0.0, &cloud, &stats), uc::PacketStatus::kOtherModel);
  EXPECT_TRUE(cloud.empty());
}

// ---- The whole model against a double-precision reference -------------------------------------

namespace {

// Straight transcription of the HDL-64E correction model in double precision, written from the
// manual's description (not from the decoder's tables): returns x, y, z in the ROS frame and
// the calibrated intensity.
void referencePoint(const uc::Calibration& cal, int laser, int raw_azimuth, int raw_distance,
                    int raw_intensity, double out[4]) {
  const uc::LaserCorrection& c = cal.lasers[laser];
  const double d = raw_distance * cal.distance_resolution_m + c.dist_correction_m;
  const double theta = raw_azimuth / 100.0 * kDeg - c.rot_correction_rad;
  const double v = c.vert_correction_rad;
  const double xy = d * std::cos(v) - c.vert_offset_correction_m * std::sin(v);
  const double x_plain = xy * std::sin(theta) - c.horiz_offset_correction_m * std::cos(theta);
  const double y_plain = xy * std::cos(theta) + c.horiz_offset_correction_m * std::sin(theta);
  double dx = d, dy = d;
  if (c.two_pt_correction_available) {
    // Linear in |x| between (2.4 m, dist_correction_x) and (25.04 m, dist_correction), in |y|
    // between (1.93 m, dist_correction_y) and (25.04 m, dist_correction).
    const double cx = c.dist_correction_x_m + (c.dist_correction_m - c.dist_correction_x_m) *
                                                  (std::fabs(x_plain) - 2.4) / (25.04 - 2.4);
    const double cy = c.dist_correction_y_m + (c.dist_correction_m - c.dist_correction_y_m) *
                                                  (std::fabs(y_plain) - 1.93) / (25.04 - 1.93);
    dx = d + cx - c.dist_correction_m;
    dy = d + cy - c.dist_correction_m;
  }
  const double vx =
      (dx * std::cos(v) - c.vert_offset_correction_m * std::sin(v)) * std::sin(theta) -
      c.horiz_offset_correction_m * std::cos(theta);
  const double vy =
      (dy * std::cos(v) - c.vert_offset_correction_m * std::sin(v)) * std::cos(theta) +
      c.horiz_offset_correction_m * std::sin(theta);
  out[0] = vy;
  out[1] = -vx;
  out[2] = dy * std::sin(v) + c.vert_offset_correction_m * std::cos(v);
  const double focal = 256.0 * std::pow(1.0 - c.focal_distance / 131.07, 2);
  const double here = 256.0 * std::pow(1.0 - raw_distance / 65535.0, 2);
  double i = raw_intensity + c.focal_slope * std::fabs(focal - here);
  out[3] = std::min<double>(std::max<double>(i, c.min_intensity), c.max_intensity);
}

void compareWithReference(const uc::Calibration& cal) {
  uc::PacketEncoder encoder(cal);
  uc::DecoderParams params;
  params.min_range_m = 0.0;
  params.max_range_m = 200.0;
  uc::PacketDecoder decoder(cal, params);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> az(0, 35999), dist(1, 65535), inten(0, 255);
  double worst = 0.0, worst_i = 0.0;
  std::size_t compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    auto firings = emptyFirings(static_cast<std::uint16_t>(az(rng)));
    for (int l = 0; l < 64; ++l) {
      // Half near range (two-point region), half anywhere.
      firings[0].distance[l] =
          static_cast<std::uint16_t>(l % 2 ? dist(rng) : 300 + dist(rng) % 15000);
      firings[0].intensity[l] = static_cast<std::uint8_t>(inten(rng));
    }
    const uc::RawPacket p = encoder.encode(firings.data(), 0);
    CloudXYZIRT cloud;
    std::vector<std::uint8_t> lasers;
    ASSERT_EQ(decoder.decode(p.data(), p.size(), 0.0, &cloud, nullptr, &lasers, nullptr),
              uc::PacketStatus::kOk);
    ASSERT_EQ(cloud.size(), 64u);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const int l = lasers[i];
      double ref[4];
      referencePoint(cal, l, firings[0].azimuth, firings[0].distance[l], firings[0].intensity[l],
                     ref);
      const double e =
          std::sqrt(std::pow(cloud[i].x - ref[0], 2) + std::pow(cloud[i].y - ref[1], 2) +
                    std::pow(cloud[i].z - ref[2], 2));
      worst = std::max(worst, e);
      worst_i = std::max(worst_i, std::fabs(cloud[i].intensity - ref[3]));
      EXPECT_EQ(cloud[i].ring, cal.ring_of_laser[l]);
      ++compared;
    }
  }
  // float arithmetic on ranges up to 131 m: ~1e-5 relative.
  EXPECT_LT(worst, 2e-4) << "over " << compared << " points";
  EXPECT_LT(worst_i, 1e-3);
}

}  // namespace

TEST(Hdl64eDecode, WholeModelMatchesDoubleReferenceSztaki) {
  const std::string path = std::string(UD_SHARED_DATA) + "/calibration/64e_s2.1-sztaki.xml";
  if (!std::ifstream(path).good()) GTEST_SKIP() << "SZTAKI calibration not found: " << path;
  compareWithReference(uc::loadCalibration(path));
}

TEST(Hdl64eDecode, WholeModelMatchesDoubleReferenceS3) {
  const std::string path = std::string(UD_SHARED_DATA) + "/calibration/64e_s3-xiesc.yaml";
  if (!std::ifstream(path).good()) GTEST_SKIP() << "S3 calibration not found: " << path;
  compareWithReference(uc::loadCalibration(path));
}

TEST(Hdl64eDecode, PlainAndBookkeepingPathsEmitIdenticalPoints) {
  // decode() without bookkeeping stores four points at a time (SSE2); with bookkeeping it goes
  // point by point. Both must emit the same points, field by field, whatever the valid mask.
  uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  for (int l = 0; l < 64; ++l) {
    cal.lasers[l].rot_correction_rad = 0.01 * (l % 9 - 4);
    cal.lasers[l].focal_distance = 8.0;
    cal.lasers[l].focal_slope = 1.0;
  }
  cal.finalize();
  uc::PacketEncoder encoder(cal);
  uc::PacketDecoder decoder(cal, uc::DecoderParams{});
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> az(0, 35999), dist(0, 70000), inten(0, 255);
  CloudXYZIRT plain, booked;
  std::vector<std::uint8_t> lasers;
  uc::DecodeStats s1, s2;
  for (int packet = 0; packet < 300; ++packet) {
    auto firings = emptyFirings(static_cast<std::uint16_t>(az(rng)));
    for (auto& f : firings) {
      for (int l = 0; l < 64; ++l) {
        const int d = dist(rng);  // > 65535: no return; small: out of range
        f.distance[l] = static_cast<std::uint16_t>(d > 65535 ? 0 : d);
        f.intensity[l] = static_cast<std::uint8_t>(inten(rng));
      }
    }
    const uc::RawPacket p = encoder.encode(firings.data(), 0);
    const double t0 = packet * 288e-6;
    ASSERT_EQ(decoder.decode(p.data(), p.size(), t0, &plain, &s1), uc::PacketStatus::kOk);
    ASSERT_EQ(decoder.decode(p.data(), p.size(), t0, &booked, &s2, &lasers, nullptr),
              uc::PacketStatus::kOk);
  }
  EXPECT_EQ(s1.points, s2.points);
  EXPECT_EQ(s1.no_return, s2.no_return);
  EXPECT_EQ(s1.out_of_range, s2.out_of_range);
  EXPECT_GT(s1.no_return, 0u);
  EXPECT_GT(s1.out_of_range, 0u);
  ASSERT_EQ(plain.size(), booked.size());
  ASSERT_EQ(lasers.size(), booked.size());
  for (std::size_t i = 0; i < plain.size(); ++i) {
    ASSERT_EQ(plain[i].x, booked[i].x) << i;
    ASSERT_EQ(plain[i].y, booked[i].y) << i;
    ASSERT_EQ(plain[i].z, booked[i].z) << i;
    ASSERT_EQ(plain[i].data[3], 1.0f) << i;
    ASSERT_EQ(booked[i].data[3], 1.0f) << i;
    ASSERT_EQ(plain[i].intensity, booked[i].intensity) << i;
    ASSERT_EQ(plain[i].ring, booked[i].ring) << i;
    ASSERT_EQ(plain[i].ring, cal.ring_of_laser[lasers[i]]) << i;
    ASSERT_EQ(plain[i].time, booked[i].time) << i;
  }
}
