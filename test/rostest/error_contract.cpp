// Error contract, nodelets loaded into this process:
//  * a PointCloud2 without x, y, z (CloudInput, the adapter of PointCloud2 sources): one clear
//    ERROR naming the fields it has (not one per message), every such cloud counted
//    (rejected_inputs), the next good cloud processed by the segmentation behind it;
//  * non-finite points: kept at their index but labelled unknown, never in the foreground,
//    counted (non_finite_points);
//  * a truncated pcap: the whole revolutions before the cut are published, one ERROR saying
//    the file is truncated, the replay stops (counted: truncated_captures), no crash.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/PointCloud2.h>
#include <unistd.h>
#include <urban_detection/VelodyneScan.h>
#include "urban_detection/ros/cloud_serialization.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "../core/spin_packets.h"
#include "rostest_util.h"
#include "urban_detection/core/common/segment_class.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"

namespace urban_detection {
namespace {

using rostest_util::DiagnosticsWatcher;
using rostest_util::RosoutWatcher;
using rostest_util::waitFor;

// Flat road (0.25 m grid, 30 x 30 m) and a 1.5 m high box: ground and short points.
boost::shared_ptr<CloudXYZIRT> street() {
  auto cloud = boost::make_shared<CloudXYZIRT>();
  auto add = [&](float x, float y, float z) { cloud->push_back(makePoint(x, y, z, 1.0f)); };
  for (float x = -15.f; x <= 15.f; x += 0.25f)
    for (float y = -15.f; y <= 15.f; y += 0.25f) add(x, y, -1.73f);
  for (float x = 5.f; x <= 7.f; x += 0.1f)
    for (float y = 3.f; y <= 4.f; y += 0.1f) add(x, y, -0.23f);
  cloud->header.frame_id = "velodyne";
  return cloud;
}

TEST(ErrorContract, CloudWithoutXyzIsReportedOnceAndCounted) {
  RosoutWatcher rosout;
  DiagnosticsWatcher diagnostics;
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ec_fields/input", "urban_detection/CloudInput", {}, {}));
  ASSERT_TRUE(manager.load("/ec_fields/seg", "urban_detection/GridSegmentation", {}, {}));
  ros::NodeHandle nh("/ec_fields");
  std::mutex mutex;
  int outputs = 0;
  // Advertised before the subscriptions that make the lazy nodelet subscribe to it: a
  // subscription racing an advertise of the same process may never be connected (roscpp).
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points_in", 10);
  ros::Subscriber sub = nh.subscribe<LabeledCloud>(
      "segmentation/foreground", 10, [&](const boost::shared_ptr<const LabeledCloud>&) {
        std::lock_guard<std::mutex> lock(mutex);
        ++outputs;
      });
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  sensor_msgs::PointCloud2 bad;  // one float field "intensity", two points
  bad.header.frame_id = "velodyne";
  bad.height = 1;
  bad.width = 2;
  bad.fields.resize(1);
  bad.fields[0].name = "intensity";
  bad.fields[0].offset = 0;
  bad.fields[0].datatype = sensor_msgs::PointField::FLOAT32;
  bad.fields[0].count = 1;
  bad.point_step = 4;
  bad.row_step = 8;
  bad.data.assign(8, 0);
  const int rejected = 5;
  for (int i = 0; i < rejected; ++i) {
    pub.publish(bad);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  sensor_msgs::PointCloud2 good;
  pcl::toROSMsg(*street(), good);
  pub.publish(good);
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return outputs == 1;
      },
      10.0))
      << "the good cloud after the bad ones was not processed";
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.value("ec_fields/input", "rejected_inputs") == rejected; }, 5.0));
  EXPECT_EQ(
      rosout.count(rosgraph_msgs::Log::ERROR, "without x, y and z fields (fields: intensity)"), 1);
}

TEST(ErrorContract, NonFinitePointsAreLabelledUnknownAndCounted) {
  DiagnosticsWatcher diagnostics;
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ec_nan/seg", "urban_detection/GridSegmentation", {}, {}));
  ros::NodeHandle nh("/ec_nan");
  std::mutex mutex;
  boost::shared_ptr<const LabeledCloud> labeled, foreground;
  ros::Publisher pub = nh.advertise<CloudXYZIRT>("velodyne_points", 10);
  ros::Subscriber s1 = nh.subscribe<LabeledCloud>(
      "segmentation/labeled_points", 10, [&](const boost::shared_ptr<const LabeledCloud>& m) {
        std::lock_guard<std::mutex> lock(mutex);
        labeled = m;
      });
  ros::Subscriber s2 = nh.subscribe<LabeledCloud>(
      "segmentation/foreground", 10, [&](const boost::shared_ptr<const LabeledCloud>& m) {
        std::lock_guard<std::mutex> lock(mutex);
        foreground = m;
      });
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  auto cloud = street();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<std::size_t> bad;  // every 97th point gets one non-finite coordinate
  for (std::size_t i = 5; i < cloud->size(); i += 97) {
    PointXYZIRT& p = (*cloud)[i];
    (bad.size() % 3 == 0   ? p.x
     : bad.size() % 3 == 1 ? p.y
                           : p.z) = bad.size() % 2 ? nan : (bad.size() % 4 == 0 ? inf : -inf);
    bad.push_back(i);
  }
  pub.publish(cloud);
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return labeled && foreground;
      },
      10.0));
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(labeled->size(), cloud->size());
  for (const std::size_t i : bad) {
    EXPECT_EQ((*labeled)[i].label, static_cast<std::uint32_t>(core::SegmentClass::kUnknown)) << i;
  }
  EXPECT_GT(foreground->size(), 100u) << "the box must still be found";
  for (const LabeledPoint& q : *foreground) {
    EXPECT_TRUE(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z)) << q.index;
  }
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics.value("ec_nan/seg", "non_finite_points") ==
               static_cast<long>(bad.size());
      },
      5.0))
      << bad.size();
}

TEST(ErrorContract, TruncatedPcapStopsTheReplayWithOneClearError) {
  RosoutWatcher rosout;
  DiagnosticsWatcher diagnostics;
  // Half a revolution of 60 packets (6 deg each, half a degree after the cut angle), three
  // whole ones, and two packets of a fourth: the first opens it, so the third is published;
  // then the file is cut in the middle of the last record.
  const std::string path = "/tmp/urban_detection_truncated_" + std::to_string(getpid()) + ".pcap";
  // the 2nd packet of the 4th revolution is cut
  const auto packets = test::spinPackets(30 + 60 * 3 + 2, 180.5, 1.0, 288, 9);
  {
    core::PcapWriter writer(path);
    for (std::size_t i = 0; i < packets.size(); ++i) writer.write(packets[i], 1000.0 + i * 288e-6);
  }
  FILE* f = std::fopen(path.c_str(), "r+");
  ASSERT_NE(f, nullptr);
  std::fseek(f, 0, SEEK_END);
  const long size = std::ftell(f);
  std::fclose(f);
  ASSERT_EQ(truncate(path.c_str(), size - 700), 0);  // the last record loses 700 bytes

  ros::param::set("/ec_pcap/source/pcap", path);
  ros::param::set("/ec_pcap/source/rate", 0.0);
  nodelet::Loader manager(false);
  ros::NodeHandle nh("/ec_pcap");
  std::mutex mutex;
  std::vector<std::size_t> sizes;
  ros::Subscriber sub =
      nh.subscribe<VelodyneScan>("velodyne_packets", 10, [&](const VelodyneScan::ConstPtr& scan) {
        std::lock_guard<std::mutex> lock(mutex);
        sizes.push_back(scan->packets.size());
      });
  ASSERT_TRUE(manager.load("/ec_pcap/source", "urban_detection/PacketSource", {}, {}));
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.count(rosgraph_msgs::Log::ERROR, "is truncated after " +
                                                           std::to_string(packets.size() - 1) +
                                                           " packets; replay stops") == 1;
      },
      10.0));
  EXPECT_TRUE(
      waitFor([&] { return diagnostics.value("ec_pcap/source", "truncated_captures") == 1; }, 5.0));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(sizes, (std::vector<std::size_t>{60, 60, 60}));
  std::remove(path.c_str());
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_error_contract");
}
