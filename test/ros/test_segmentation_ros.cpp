// ROS layer of the segmentation: PointCloud2 input conversion by field name and parameter
// range checks. No master needed.
#include "urban_detection/core/common/point_types.h"

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sensor_msgs/PointCloud2.h>

#include "urban_detection/ros/pointcloud2_input.h"

namespace urban_detection {
namespace {

using sensor_msgs::PointField;

void addField(sensor_msgs::PointCloud2* m, const std::string& name, std::uint32_t offset,
              std::uint8_t type) {
  PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = 1;
  m->fields.push_back(f);
}

template <typename T>
void put(sensor_msgs::PointCloud2* m, std::size_t byte, T v) {
  std::memcpy(m->data.data() + byte, &v, sizeof(T));
}

// A KITTI-style cloud: x y z intensity float32 only, 16-byte points plus 4 bytes of padding.
sensor_msgs::PointCloud2 kittiStyle(int n) {
  sensor_msgs::PointCloud2 m;
  m.header.frame_id = "velodyne";
  m.header.stamp.fromSec(12.5);
  addField(&m, "x", 0, PointField::FLOAT32);
  addField(&m, "y", 4, PointField::FLOAT32);
  addField(&m, "z", 8, PointField::FLOAT32);
  addField(&m, "intensity", 12, PointField::FLOAT32);
  m.point_step = 20;
  m.width = n;
  m.height = 1;
  m.row_step = m.point_step * n;
  m.data.assign(m.row_step, 0);
  for (int i = 0; i < n; ++i) {
    put<float>(&m, i * 20 + 0, 1.0f * i);
    put<float>(&m, i * 20 + 4, -2.0f * i);
    put<float>(&m, i * 20 + 8, 0.5f);
    put<float>(&m, i * 20 + 12, 7.0f);
  }
  return m;
}

TEST(PointCloud2Input, XyzIntensityOnlyFillsRingAndTimeWithZero) {
  const sensor_msgs::PointCloud2 m = kittiStyle(5);
  CloudXYZIRT cloud;
  ros_conv::PointCloud2InputInfo info;
  std::string err;
  ASSERT_TRUE(ros_conv::fromPointCloud2(m, &cloud, &info, &err)) << err;
  ASSERT_EQ(cloud.size(), 5u);
  EXPECT_TRUE(info.has_intensity);
  EXPECT_FALSE(info.has_ring);
  EXPECT_FALSE(info.has_time);
  EXPECT_FLOAT_EQ(cloud[3].x, 3.0f);
  EXPECT_FLOAT_EQ(cloud[3].y, -6.0f);
  EXPECT_FLOAT_EQ(cloud[3].z, 0.5f);
  EXPECT_FLOAT_EQ(cloud[3].intensity, 7.0f);
  EXPECT_EQ(cloud[3].ring, 0);
  EXPECT_FLOAT_EQ(cloud[3].time, 0.0f);
  EXPECT_EQ(cloud.header.frame_id, "velodyne");
  EXPECT_EQ(cloud.header.stamp, 12500000u);  // PCL stamps are microseconds
}

TEST(PointCloud2Input, FieldsOfOtherTypesAndOrderAreFoundByName) {
  // time as float64 first, then ring uint16, intensity uint8, xyz float64 last.
  sensor_msgs::PointCloud2 m;
  addField(&m, "time", 0, PointField::FLOAT64);
  addField(&m, "ring", 8, PointField::UINT16);
  addField(&m, "intensity", 10, PointField::UINT8);
  addField(&m, "x", 11, PointField::FLOAT64);
  addField(&m, "y", 19, PointField::FLOAT64);
  addField(&m, "z", 27, PointField::FLOAT64);
  m.point_step = 35;
  m.width = 1;
  m.height = 1;
  m.row_step = 35;
  m.data.assign(35, 0);
  put<double>(&m, 0, 0.025);
  put<std::uint16_t>(&m, 8, 42);
  put<std::uint8_t>(&m, 10, 200);
  put<double>(&m, 11, 1.5);
  put<double>(&m, 19, -2.5);
  put<double>(&m, 27, 0.25);
  CloudXYZIRT cloud;
  ros_conv::PointCloud2InputInfo info;
  std::string err;
  ASSERT_TRUE(ros_conv::fromPointCloud2(m, &cloud, &info, &err)) << err;
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_TRUE(info.has_ring && info.has_time);
  EXPECT_FLOAT_EQ(cloud[0].x, 1.5f);
  EXPECT_FLOAT_EQ(cloud[0].y, -2.5f);
  EXPECT_FLOAT_EQ(cloud[0].z, 0.25f);
  EXPECT_FLOAT_EQ(cloud[0].intensity, 200.0f);
  EXPECT_EQ(cloud[0].ring, 42);
  EXPECT_FLOAT_EQ(cloud[0].time, 0.025f);
}

TEST(PointCloud2Input, RejectsMalformedMessages) {
  CloudXYZIRT cloud;
  ros_conv::PointCloud2InputInfo info;
  std::string err;
  sensor_msgs::PointCloud2 truncated = kittiStyle(10);
  truncated.data.resize(truncated.data.size() - 1);
  EXPECT_FALSE(ros_conv::fromPointCloud2(truncated, &cloud, &info, &err));
  EXPECT_NE(err.find("shorter"), std::string::npos) << err;
  EXPECT_TRUE(cloud.empty());

  sensor_msgs::PointCloud2 no_z = kittiStyle(2);
  no_z.fields.erase(no_z.fields.begin() + 2);
  EXPECT_FALSE(ros_conv::fromPointCloud2(no_z, &cloud, &info, &err));

  sensor_msgs::PointCloud2 outside = kittiStyle(2);
  outside.fields[3].offset = 18;  // a float32 at 18 overruns the 20-byte point
  EXPECT_FALSE(ros_conv::fromPointCloud2(outside, &cloud, &info, &err));

  sensor_msgs::PointCloud2 big_endian = kittiStyle(2);
  big_endian.is_bigendian = true;
  EXPECT_FALSE(ros_conv::fromPointCloud2(big_endian, &cloud, &info, &err));

  sensor_msgs::PointCloud2 twice = kittiStyle(2);  // a second "x" (the intensity's bytes)
  twice.fields.push_back(twice.fields[3]);
  twice.fields.back().name = "x";
  EXPECT_FALSE(ros_conv::fromPointCloud2(twice, &cloud, &info, &err));
  EXPECT_NE(err.find("'x' defined twice"), std::string::npos) << err;

  sensor_msgs::PointCloud2 empty = kittiStyle(0);
  EXPECT_TRUE(ros_conv::fromPointCloud2(empty, &cloud, &info, &err));
  EXPECT_TRUE(cloud.empty());
}

}  // namespace
}  // namespace urban_detection
