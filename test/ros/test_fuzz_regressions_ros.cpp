// Regression tests for ROS-layer bugs found by the libFuzzer targets of test/fuzz;
// the crashing inputs stay in test/fuzz/corpus/<target>/crash-* so the fuzzers replay them.
#include <gtest/gtest.h>

#include <cmath>

#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {
namespace ros_conv {
namespace {

VelodynePacket packetAt(const core::PacketEncoder& encoder, const ros::Time& stamp,
                        std::uint16_t azimuth) {
  core::Firing firings[6];
  for (int k = 0; k < 6; ++k) {
    firings[k].azimuth = static_cast<std::uint16_t>(azimuth + 10 * k);
    firings[k].distance.fill(5000);  // 10 m
    firings[k].intensity.fill(50);
  }
  VelodynePacket p;
  toMessage(encoder.encode(firings, 0), stamp, &p);
  return p;
}

// fuzz_velodyne_scan: packet stamps of one scan more than 68 years apart made
// ros::Time - ros::Time throw std::runtime_error ("Duration is out of dual 32-bit range") out
// of decodeScan, i.e. out of PacketToCloud's subscriber callback.
TEST(FuzzRegressions, DecodeScanSurvivesStampsFarApart) {
  const core::PacketEncoder encoder(core::Calibration::nominalHdl64eS2());
  const core::PacketDecoder decoder(core::Calibration::nominalHdl64eS2(), core::DecoderParams());
  VelodyneScan scan;
  scan.packets.push_back(packetAt(encoder, ros::Time(1000, 0), 0));
  scan.packets.push_back(packetAt(encoder, ros::Time(4000000000u, 500000000u), 100));  // +126 y
  scan.packets.push_back(packetAt(encoder, ros::Time(0, 0), 200));  // before the first packet
  CloudXYZIRT cloud;
  ScanDecodeStats stats;
  ASSERT_NO_THROW(decodeScan(decoder, scan, PacketTransformFn(), &cloud, &stats));
  ASSERT_EQ(stats.decode.points, 3u * 384u);
  ASSERT_EQ(cloud.size(), 3u * 384u);
  // Times: packet offset plus firing offset (48 us per firing pair, 32 points per block).
  const double expected_offset_s[3] = {0.0, 3999999000.5, -1000.0};
  for (int p = 0; p < 3; ++p) {
    for (int b = 0; b < 12; ++b) {
      const PointXYZIRT& pt = cloud[static_cast<std::size_t>(p * 384 + b * 32)];
      const double expected = expected_offset_s[p] + (b / 2) * 48e-6;
      EXPECT_NEAR(pt.time, expected, std::fabs(expected) * 1e-6 + 1e-9) << "packet " << p;
    }
  }
}

}  // namespace
}  // namespace ros_conv
}  // namespace urban_detection
