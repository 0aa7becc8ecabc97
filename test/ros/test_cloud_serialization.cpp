// The pipeline's clouds as ROS messages (cloud_serialization.h): what a typed subscription
// (subscribe<CloudXYZIRT>) makes of a sensor_msgs/PointCloud2 from another process. Sound
// clouds convert field by field; every malformed one (the cases that crashed or passed
// pcl_ros's deserialiser) arrives as an empty cloud naming what is wrong. No master needed.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>
#include <ros/serialization.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstring>
#include <string>
#include <vector>

#include "urban_detection/ros/cloud_serialization.h"

namespace urban_detection {
namespace {

namespace ser = ros::serialization;

// An XYZIRT cloud as velodyne_pointcloud publishes it: packed 22-byte points
// (x y z intensity float32, ring uint16, time float32).
sensor_msgs::PointCloud2 velodyneStyle(std::uint32_t n) {
  sensor_msgs::PointCloud2 m;
  m.header.frame_id = "velodyne";
  m.header.seq = 5;
  m.height = 1;
  m.width = n;
  const char* names[] = {"x", "y", "z", "intensity", "ring", "time"};
  const std::uint8_t types[] = {7, 7, 7, 7, 4, 7};
  const std::uint32_t offsets[] = {0, 4, 8, 12, 16, 18};
  for (int i = 0; i < 6; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = offsets[i];
    f.datatype = types[i];
    f.count = 1;
    m.fields.push_back(f);
  }
  m.point_step = 22;
  m.row_step = 22 * n;
  m.data.resize(m.row_step);
  for (std::uint32_t i = 0; i < n; ++i) {
    std::uint8_t* p = m.data.data() + 22 * i;
    const float xyzi[4] = {1.0f + i, -2.0f, 0.5f, 7.0f};
    const std::uint16_t ring = static_cast<std::uint16_t>(i % 64);
    const float time = 0.001f * i;
    std::memcpy(p, xyzi, 16);
    std::memcpy(p + 16, &ring, 2);
    std::memcpy(p + 18, &time, 4);
  }
  m.is_dense = true;
  return m;
}

template <typename M>
std::vector<std::uint8_t> bytesOf(const M& m) {
  std::vector<std::uint8_t> buf(ser::serializationLength(m));
  ser::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
  ser::serialize(out, m);
  return buf;
}

CloudXYZIRT typedRead(const std::vector<std::uint8_t>& bytes) {
  CloudXYZIRT cloud;
  std::vector<std::uint8_t> copy(bytes);  // IStream takes a non-const pointer
  ser::IStream in(copy.data(), static_cast<std::uint32_t>(copy.size()));
  ser::deserialize(in, cloud);
  return cloud;
}

TEST(CloudSerialization, SoundVelodyneCloudConvertsByFieldName) {
  const CloudXYZIRT cloud = typedRead(bytesOf(velodyneStyle(100)));
  ASSERT_EQ(ros_conv::cloudRefusal(cloud), "");
  ASSERT_EQ(cloud.size(), 100u);
  EXPECT_EQ(cloud.header.frame_id, "velodyne");
  EXPECT_EQ(cloud.header.seq, 5u);
  EXPECT_FLOAT_EQ(cloud[42].x, 43.0f);
  EXPECT_FLOAT_EQ(cloud[42].y, -2.0f);
  EXPECT_FLOAT_EQ(cloud[42].intensity, 7.0f);
  EXPECT_EQ(cloud[42].ring, 42);
  EXPECT_FLOAT_EQ(cloud[42].time, 0.042f);
}

TEST(CloudSerialization, PclRoundTripKeepsEveryPoint) {
  CloudXYZIRT in;
  for (int i = 0; i < 50; ++i) in.push_back(makePoint(0.5f * i, 1.0f, -1.0f, 3.0f, 9, 0.01f));
  in.header.frame_id = "velodyne";
  const CloudXYZIRT out = typedRead(bytesOf(in));
  ASSERT_EQ(ros_conv::cloudRefusal(out), "");
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].x, in[i].x);
    EXPECT_EQ(out[i].ring, in[i].ring);
    EXPECT_EQ(out[i].time, in[i].time);
  }
  // A cloud whose width x height disagrees with its points is written as one row of them.
  in.width = 1000;
  EXPECT_EQ(typedRead(bytesOf(in)).size(), 50u);
}

void expectRefused(const sensor_msgs::PointCloud2& m, const std::string& why) {
  const CloudXYZIRT cloud = typedRead(bytesOf(m));
  EXPECT_TRUE(cloud.empty());
  const std::string refusal = ros_conv::cloudRefusal(cloud);
  EXPECT_EQ(refusal.rfind(why, 0), 0u) << "got '" << refusal << "', expected '" << why << "'";
}

TEST(CloudSerialization, MalformedCloudsAreRefusedNamingTheFault) {
  sensor_msgs::PointCloud2 longer = velodyneStyle(1000);  // crashed pcl_ros (heap overflow)
  longer.data.resize(longer.data.size() + 1000);
  expectRefused(longer, "data longer than row_step x height");

  sensor_msgs::PointCloud2 shorter = velodyneStyle(1000);
  shorter.data.resize(shorter.data.size() - 22);
  expectRefused(shorter, "data shorter than row_step x height");

  sensor_msgs::PointCloud2 zero_step = velodyneStyle(1000);
  zero_step.point_step = 0;
  expectRefused(zero_step, "point_step 0");

  sensor_msgs::PointCloud2 twice = velodyneStyle(10);
  twice.fields.push_back(twice.fields[0]);
  expectRefused(twice, "duplicate field: 'x'");

  sensor_msgs::PointCloud2 big = velodyneStyle(10);
  big.is_bigendian = true;
  expectRefused(big, "big-endian");

  sensor_msgs::PointCloud2 many = velodyneStyle(1);  // 2 M points declared, data to match
  many.width = 2000000;
  many.row_step = 22 * many.width;
  many.data.assign(many.row_step, 0);
  expectRefused(many, "too many points");

  sensor_msgs::PointCloud2 narrow = velodyneStyle(10);
  narrow.row_step = 21 * 10;
  narrow.data.resize(narrow.row_step);
  expectRefused(narrow, "row_step too small");

  sensor_msgs::PointCloud2 outside = velodyneStyle(10);
  outside.fields[5].offset = 20;  // float32 at 20 of a 22-byte point
  expectRefused(outside, "field beyond point_step: 'time'");

  sensor_msgs::PointCloud2 unknown = velodyneStyle(10);
  unknown.fields[3].datatype = 9;
  expectRefused(unknown, "unknown field datatype: 'intensity'");

  sensor_msgs::PointCloud2 no_z = velodyneStyle(10);
  no_z.fields.erase(no_z.fields.begin() + 2);
  expectRefused(no_z, "missing field: no 'z'");

  sensor_msgs::PointCloud2 stamp = velodyneStyle(10);  // would throw when published again
  stamp.header.stamp.sec = 0xFFFFFFFFu;
  stamp.header.stamp.nsec = 0xFFFFFFFFu;
  expectRefused(stamp, "bad stamp: nsec 4294967295");

  sensor_msgs::PointCloud2 ring8 = velodyneStyle(10);
  ring8.fields[4].datatype = 2;  // uint8 ring
  expectRefused(ring8, "field type: 'ring' is UINT8");
}

TEST(CloudSerialization, TruncatedAndHostileCountsAreRefusedWithoutAllocating) {
  std::vector<std::uint8_t> bytes = bytesOf(velodyneStyle(100));
  std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + bytes.size() / 2);
  const CloudXYZIRT truncated = typedRead(cut);
  EXPECT_TRUE(truncated.empty());
  EXPECT_EQ(ros_conv::cloudRefusal(truncated).rfind("truncated message", 0), 0u);

  // A field count of 0xFFFFFFFF (roscpp's own reader would resize to it first).
  sensor_msgs::PointCloud2 m = velodyneStyle(1);
  bytes = bytesOf(m);
  const std::size_t count_at = 4 + 8 + 4 + m.header.frame_id.size() + 8;
  const std::uint32_t huge = 0xFFFFFFFFu;
  std::memcpy(bytes.data() + count_at, &huge, 4);
  EXPECT_EQ(ros_conv::cloudRefusal(typedRead(bytes)).rfind("truncated message", 0), 0u);
}

TEST(CloudSerialization, InProcessCloudsAreCheckedToo) {
  CloudXYZIRT cloud;
  cloud.push_back(makePoint(1, 2, 3));
  EXPECT_EQ(ros_conv::cloudRefusal(cloud), "");
  cloud.width = 7;  // points and width x height disagree
  EXPECT_EQ(ros_conv::cloudRefusal(cloud).rfind("point count", 0), 0u);
  cloud.width = 1;
  EXPECT_EQ(ros_conv::cloudRefusal(cloud, 0).rfind("too many points", 0), 0u);
}

}  // namespace
}  // namespace urban_detection
