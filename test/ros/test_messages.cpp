// urban_detection/VelodynePacket and VelodyneScan: wire compatibility with velodyne_msgs and
// serialisation round trip; Detection3DArray: wire compatibility with vision_msgs and the
// conversion of detected objects into it (no master needed).
#include <gtest/gtest.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <urban_detection/VelodyneScan.h>

#include "urban_detection/ros/standard_outputs.h"

#include <cstring>
#include <vector>

namespace urban_detection {
namespace {

// The MD5 sums published by velodyne_msgs (velodyne_msgs/VelodynePacket, VelodyneScan); equal
// sums let velodyne drivers and their bags connect to our topics.
TEST(Messages, Md5SumsEqualVelodyneMsgs) {
  EXPECT_STREQ(ros::message_traits::MD5Sum<VelodynePacket>::value(),
               "ae4f90a23256f44e82baa08dd45c3456");
  EXPECT_STREQ(ros::message_traits::MD5Sum<VelodyneScan>::value(),
               "50804fc9533a0e579e6322c04ae70566");
  EXPECT_STREQ(ros::message_traits::DataType<VelodyneScan>::value(),
               "urban_detection/VelodyneScan");
}

// vision_msgs' published MD5 of Detection3DArray (ROS 1): its subscribers connect.
TEST(Messages, Detection3DArrayMd5EqualsVisionMsgs) {
  EXPECT_STREQ(ros::message_traits::MD5Sum<Detection3DArray>::value(),
               "05c51d9aea1fb4cfdc8effb94f197b6f");
}

TEST(Messages, ObjectsAsDetection3D) {
  DetectedObjectArray in;
  in.header.frame_id = "velodyne";
  in.header.stamp = ros::Time(5, 6);
  DetectedObject o;
  o.obb_pose.position.x = 7.0;
  o.obb_pose.orientation.w = 1.0;
  o.obb_dimensions.x = 4.0;
  o.class_label = "cyclist";
  o.class_confidence = 0.75f;
  in.objects = {o, o};
  in.objects[1].class_label = "no such class";
  Detection3DArray out;
  ros_conv::toDetection3DArray(in, &out);
  EXPECT_EQ(out.header.frame_id, "velodyne");
  ASSERT_EQ(out.detections.size(), 2u);
  EXPECT_EQ(out.detections[0].header.stamp, ros::Time(5, 6));
  ASSERT_EQ(out.detections[0].results.size(), 1u);
  EXPECT_EQ(out.detections[0].results[0].id, 3);
  EXPECT_DOUBLE_EQ(out.detections[0].results[0].score, 0.75);
  EXPECT_DOUBLE_EQ(out.detections[0].bbox.center.position.x, 7.0);
  EXPECT_DOUBLE_EQ(out.detections[0].bbox.size.x, 4.0);
  EXPECT_EQ(out.detections[1].results[0].id, 255);
  EXPECT_EQ(ros_conv::classId("vehicle"), 1);
  EXPECT_EQ(ros_conv::classId("non_object"), 0);
}

TEST(Messages, ScanSerialisationRoundTrip) {
  VelodyneScan scan;
  scan.header.seq = 7;
  scan.header.stamp = ros::Time(1700000000, 123456789);
  scan.header.frame_id = "velodyne";
  for (int p = 0; p < 3; ++p) {
    VelodynePacket packet;
    packet.stamp = ros::Time(1700000000, 123456789 + p * 288000);
    for (std::size_t i = 0; i < packet.data.size(); ++i) {
      packet.data[i] = static_cast<std::uint8_t>((i * 31 + p * 17) & 0xFF);
    }
    scan.packets.push_back(packet);
  }
  const uint32_t length = ros::serialization::serializationLength(scan);
  // Header: seq 4 + stamp 8 + string 4 + 8; array length 4; per packet: stamp 8 + 1206 bytes.
  EXPECT_EQ(length, 4u + 8u + 4u + 8u + 4u + 3u * (8u + 1206u));
  std::vector<uint8_t> buffer(length);
  ros::serialization::OStream out(buffer.data(), length);
  ros::serialization::serialize(out, scan);

  VelodyneScan copy;
  ros::serialization::IStream in(buffer.data(), length);
  ros::serialization::deserialize(in, copy);
  EXPECT_EQ(copy.header.seq, 7u);
  EXPECT_EQ(copy.header.stamp, scan.header.stamp);
  EXPECT_EQ(copy.header.frame_id, "velodyne");
  ASSERT_EQ(copy.packets.size(), 3u);
  for (int p = 0; p < 3; ++p) {
    EXPECT_EQ(copy.packets[p].stamp, scan.packets[p].stamp);
    EXPECT_EQ(std::memcmp(copy.packets[p].data.data(), scan.packets[p].data.data(), 1206), 0);
  }
  // The first packet's bytes sit right after the header and array length, in wire order.
  const std::size_t first_data = 4 + 8 + 4 + 8 + 4 + 8;
  EXPECT_EQ(buffer[first_data + 5], scan.packets[0].data[5]);
}

}  // namespace
}  // namespace urban_detection
