// The simulator's bag output read back with the rosbag API: scans decode to exactly as many
// points as the ground truth has labels, stamps pair up, tf covers every packet.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>

#include "../core/test_files.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/simulation_config.h"
#include "urban_detection/ros/simulation_conversions.h"

namespace ud = urban_detection;

TEST(SimulationBag, WrittenBagReplaysThroughTheDecoder) {
  ros::Time::init();
  const ud::core::SimulationConfig c =
      ud::core::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  ud::core::LidarSimulator sim(ud::core::generateScene(c.scene, c.drive), c.scene, c.drive,
                               ud::core::Calibration::nominalHdl64eS2(), c.sensor);
  const std::string path = ud_test::tempPath("sim_test.bag");
  std::vector<std::size_t> expected_points;
  {
    ud::ros_conv::SimulationBagWriter writer(path);
    ud::core::SimRevolution rev;
    for (int r = 0; r < 3; ++r) {
      sim.simulateNext(&rev);
      expected_points.push_back(rev.instance_ids.size());
      writer.write(sim, rev);
    }
  }
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  ud::core::PacketDecoder decoder(sim.calibration(), ud::core::DecoderParams());
  std::map<double, std::size_t> decoded;  // scan stamp -> decoded points
  std::map<double, std::size_t> labels;   // ground-truth stamp -> labels
  std::vector<double> tf_stamps;
  int scans = 0, gts = 0, statics = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto scan = m.instantiate<ud::VelodyneScan>()) {
      EXPECT_EQ(m.getTopic(), "/velodyne_packets");
      EXPECT_EQ(scan->header.frame_id, "velodyne");
      ud::CloudXYZIRT cloud;
      for (const auto& p : scan->packets) {
        ASSERT_EQ(decoder.decode(p.data.data(), p.data.size(),
                                 (p.stamp - scan->header.stamp).toSec(), &cloud, nullptr),
                  ud::core::PacketStatus::kOk);
      }
      decoded[scan->header.stamp.toSec()] = cloud.size();
      ++scans;
    } else if (auto gt = m.instantiate<ud::GroundTruth>()) {
      EXPECT_EQ(gt->instance_ids.size(), gt->classes.size());
      EXPECT_EQ(gt->revolution, static_cast<std::uint32_t>(gts));
      labels[gt->header.stamp.toSec()] = gt->instance_ids.size();
      ++gts;
    } else if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
      ASSERT_EQ(tf->transforms.size(), 1u);
      if (m.getTopic() == "/tf_static") {
        EXPECT_EQ(tf->transforms[0].child_frame_id, "velodyne");
        EXPECT_NEAR(tf->transforms[0].transform.translation.z, c.sensor.height_m, 1e-12);
        ++statics;
      } else {
        EXPECT_EQ(tf->transforms[0].header.frame_id, "odom");
        EXPECT_EQ(tf->transforms[0].child_frame_id, "base_link");
        tf_stamps.push_back(tf->transforms[0].header.stamp.toSec());
      }
    }
  }
  EXPECT_EQ(scans, 3);
  EXPECT_EQ(gts, 3);
  EXPECT_EQ(statics, 1);
  EXPECT_EQ(decoded, labels);  // same stamps, same lengths
  std::size_t r = 0;
  for (const auto& kv : decoded) EXPECT_EQ(kv.second, expected_points[r++]);
  // tf brackets the drive: first sample at the first scan's first packet (a scan is stamped
  // with its last packet, one revolution later), last one after the last packet.
  ASSERT_EQ(tf_stamps.size(), 4u);
  EXPECT_NEAR(tf_stamps.front(), decoded.begin()->first - 0.1, 0.001);
  EXPECT_GE(tf_stamps.back(), decoded.rbegin()->first);
  bag.close();
  std::remove(path.c_str());
}

// Bag tools and bag.launch see the scans as a velodyne driver records them: connection type
// velodyne_msgs/VelodyneScan with velodyne_msgs type names in its definition, our MD5 sum, and
// the messages still read back as urban_detection::VelodyneScan, every packet in place.
TEST(SimulationBag, ScansAreRecordedAsVelodyneMsgsVelodyneScan) {
  ros::Time::init();
  const ud::core::SimulationConfig c =
      ud::core::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  ud::core::LidarSimulator sim(ud::core::generateScene(c.scene, c.drive), c.scene, c.drive,
                               ud::core::Calibration::nominalHdl64eS2(), c.sensor);
  const std::string path = ud_test::tempPath("sim_velodyne_msgs.bag");
  std::vector<ud::core::SimRevolution> revs(2);
  {
    ud::ros_conv::SimulationBagWriter writer(path);
    for (auto& rev : revs) {
      sim.simulateNext(&rev);
      writer.write(sim, rev);
    }
  }
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/velodyne_packets"));
  const std::vector<const rosbag::ConnectionInfo*> connections = view.getConnections();
  ASSERT_EQ(connections.size(), 1u);
  EXPECT_EQ(connections[0]->datatype, "velodyne_msgs/VelodyneScan");
  EXPECT_EQ(connections[0]->md5sum, ros::message_traits::MD5Sum<ud::VelodyneScan>::value());
  EXPECT_EQ(connections[0]->md5sum, "50804fc9533a0e579e6322c04ae70566");  // velodyne_msgs'
  EXPECT_NE(connections[0]->msg_def.find("MSG: velodyne_msgs/VelodynePacket"), std::string::npos)
      << connections[0]->msg_def;
  EXPECT_EQ(connections[0]->msg_def.find("urban_detection"), std::string::npos)
      << connections[0]->msg_def;
  std::size_t r = 0;
  for (const rosbag::MessageInstance& m : view) {
    EXPECT_EQ(m.getDataType(), "velodyne_msgs/VelodyneScan");
    ASSERT_LT(r, revs.size());
    const ud::VelodyneScan::ConstPtr scan = m.instantiate<ud::VelodyneScan>();
    ASSERT_TRUE(scan);
    EXPECT_EQ(scan->header.frame_id, "velodyne");
    ASSERT_EQ(scan->packets.size(), revs[r].packets.size());
    ASSERT_GT(scan->packets.size(), 0u);
    for (std::size_t i = 0; i < scan->packets.size(); ++i) {
      ASSERT_TRUE(std::equal(revs[r].packets[i].begin(), revs[r].packets[i].end(),
                             scan->packets[i].data.begin()))
          << "revolution " << r << " packet " << i;
    }
    EXPECT_NEAR(scan->packets.back().stamp.toSec(), revs[r].packet_stamps_s.back(), 1e-6);
    ++r;
  }
  EXPECT_EQ(r, revs.size());
  bag.close();
  std::remove(path.c_str());
}

TEST(SimulationBag, ScanAndGroundTruthMessagesCopyTheRevolution) {
  ud::core::SimRevolution rev;
  rev.index = 7;
  rev.stamp_s = 1700000000.25;
  rev.packets.resize(2);
  rev.packets[1][5] = 42;
  rev.packet_stamps_s = {1700000000.25, 1700000000.250288};
  rev.instance_ids = {0, 3, 3};
  rev.classes = {1, 7, 7};
  ud::VelodyneScan scan;
  ud::ros_conv::toScanMsg(rev, "velodyne", &scan);
  ASSERT_EQ(scan.packets.size(), 2u);
  EXPECT_EQ(scan.packets[1].data[5], 42);
  // velodyne_driver's convention: the last packet's stamp, or the first's on request.
  EXPECT_DOUBLE_EQ(scan.header.stamp.toSec(), ros::Time().fromSec(1700000000.250288).toSec());
  ud::VelodyneScan first;
  ud::ros_conv::toScanMsg(rev, "velodyne", &first, ud::ros_conv::ScanStamp::kFirstPacket);
  EXPECT_DOUBLE_EQ(first.header.stamp.toSec(), ros::Time().fromSec(1700000000.25).toSec());
  EXPECT_NEAR(scan.packets[1].stamp.toSec(), 1700000000.250288, 1e-6);
  ud::GroundTruth gt;
  ud::ros_conv::toGroundTruthMsg(rev, "velodyne", &gt);
  EXPECT_EQ(gt.revolution, 7u);
  EXPECT_EQ(gt.header.stamp, scan.header.stamp);
  EXPECT_EQ(gt.instance_ids, rev.instance_ids);
  EXPECT_EQ(gt.classes, rev.classes);
  EXPECT_EQ(gt.classes[1], ud::GroundTruth::CAR);
}
