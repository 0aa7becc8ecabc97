// Range checks behind every parameter loader: one message naming parameter, value and range.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/param_loading.h"

namespace urban_detection {
namespace ros_conv {
namespace {

std::string errorOf(double value, double min, double max) {
  try {
    checkRange("/mgr/packet_to_cloud/max_range", value, min, max, "m");
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

TEST(ParamLoading, AcceptsValuesInsideTheClosedRange) {
  EXPECT_EQ(errorOf(0.1, 0.1, 250.0), "");
  EXPECT_EQ(errorOf(250.0, 0.1, 250.0), "");
  EXPECT_EQ(errorOf(130.0, 0.1, 250.0), "");
}

TEST(ParamLoading, RejectsOutOfRangeWithNameValueAndRange) {
  EXPECT_EQ(errorOf(-1.5, 0.1, 250.0),
            "parameter '/mgr/packet_to_cloud/max_range' = -1.5 is out of range: accepted "
            "[0.1, 250] m");
  EXPECT_NE(errorOf(250.001, 0.1, 250.0), "");
}

TEST(ParamLoading, RejectsNonFiniteValues) {
  EXPECT_NE(errorOf(std::numeric_limits<double>::quiet_NaN(), 0.1, 250.0), "");
  EXPECT_NE(errorOf(std::numeric_limits<double>::infinity(), 0.1, 250.0), "");
}

TEST(ParamLoading, IntegerRangeWithoutUnit) {
  EXPECT_NO_THROW(checkRange("port", 2368, 1, 65535));
  try {
    checkRange("port", 0, 1, 65535);
    FAIL() << "port 0 accepted";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "parameter 'port' = 0 is out of range: accepted [1, 65535]");
  }
}

}  // namespace
}  // namespace ros_conv
}  // namespace urban_detection

namespace urban_detection {
namespace ros_conv {
namespace {

// One packet every 6 x 48 us = 288 us: 60 / rpm / 288e-6 packets per revolution (by hand:
// 600 rpm -> 0.1 s / 288 us = 347.2; 300 rpm -> 694.4; 1200 rpm -> 173.6).
TEST(PacketSourceParams, RpmSizesTheRevolutionAndTheExpectedRate) {
  PacketSourceParams p;
  p.rpm = 600.0;
  EXPECT_EQ(p.expectedPacketsPerRevolution(), 347u);
  EXPECT_DOUBLE_EQ(p.expectedRevolutionRateHz(), 10.0);
  p.rpm = 300.0;
  EXPECT_EQ(p.expectedPacketsPerRevolution(), 694u);
  EXPECT_DOUBLE_EQ(p.expectedRevolutionRateHz(), 5.0);
  p.rpm = 1200.0;
  EXPECT_EQ(p.expectedPacketsPerRevolution(), 174u);
  // A replay at half speed delivers half the revolutions per second; "as fast as possible"
  // has no expected rate.
  p.pcap = "drive.pcap";
  p.rate = 0.5;
  EXPECT_DOUBLE_EQ(p.expectedRevolutionRateHz(), 10.0);
  p.rate = 0.0;
  EXPECT_DOUBLE_EQ(p.expectedRevolutionRateHz(), 0.0);
}

}  // namespace
}  // namespace ros_conv
}  // namespace urban_detection
