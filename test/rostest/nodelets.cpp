// PacketSource and PacketToCloud loaded into this process with nodelet::Loader: the process is
// a nodelet manager, and the test's own subscribers sit in the same manager as the nodelets.
// Covers zero copy, laziness, UDP on 127.0.0.1, pcap replay, bad packets and bad parameters.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <arpa/inet.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <nodelet/loader.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/PointCloud2.h>
#include <sys/socket.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <unistd.h>
#include <urban_detection/VelodyneScan.h>
#include "urban_detection/ros/cloud_serialization.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "../core/spin_packets.h"
#include "rostest_util.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {
namespace ros_conv {
namespace {

using rostest_util::Collector;
using rostest_util::DiagnosticsWatcher;
using rostest_util::freeUdpPort;
using rostest_util::RosoutWatcher;
using rostest_util::waitFor;

constexpr int kPacketsPerRevolution = 60;     // a coarse but valid spin: 1 deg between firings
constexpr std::uint16_t kDistanceRaw = 5000;  // 10 m at 2 mm per unit: inside every range
constexpr std::size_t kReturnsPerPacket = 384;

// Packets of a spin starting at `first_az_deg` with 6 deg per packet (1 deg per firing). The
// azimuths are offset by half a degree from the cut angle 0 so the cut is unambiguous.
// Intensities 40..45 by firing, packets 1667 us apart.
std::vector<core::RawPacket> makePackets(int count, double first_az_deg) {
  return test::spinPackets(count, first_az_deg, 1.0, 1667, 40, 1, kDistanceRaw);
}

VelodyneScan::Ptr makeScan(const std::vector<core::RawPacket>& packets, ros::Time stamp,
                           double packet_period_s) {
  auto scan = boost::make_shared<VelodyneScan>();
  scan->header.frame_id = "velodyne";
  scan->header.stamp = stamp;
  for (const core::RawPacket& raw : packets) {
    scan->packets.emplace_back();
    toMessage(raw, stamp, &scan->packets.back());
    stamp += ros::Duration(packet_period_s);
  }
  return scan;
}

class UdpSender {
 public:
  explicit UdpSender(int port, const char* from_ip = "127.0.0.1") {
    fd_ = socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    inet_pton(AF_INET, from_ip, &local.sin_addr);
    bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof(local));
    to_.sin_family = AF_INET;
    to_.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, "127.0.0.1", &to_.sin_addr);
  }
  ~UdpSender() { close(fd_); }
  void send(const std::uint8_t* data, std::size_t size) {
    sendto(fd_, data, size, 0, reinterpret_cast<sockaddr*>(&to_), sizeof(to_));
    // Paced like the sensor's burst rate, so the default kernel buffer never overflows.
    std::this_thread::sleep_for(std::chrono::microseconds(300));
  }

 private:
  int fd_;
  sockaddr_in to_{};
};

void decodeReference(const VelodyneScan& scan, CloudXYZIRT* cloud) {
  const core::PacketDecoder decoder(core::Calibration::nominalHdl64eS2(), core::DecoderParams());
  ScanDecodeStats stats;
  decodeScan(decoder, scan, PacketTransformFn(), cloud, &stats);
}

// ------------------------------------------------------------------------------------------
// Zero copy: the cloud PacketToCloud publishes reaches a subscriber in the same manager as the
// very object it built. The proof uses the cloud's sensor pose (sensor_origin_ and
// sensor_orientation_): PacketToCloud sets it, and it is not part of the PointCloud2 wire format,
// so any serialisation on the way would reset it to zero/identity. A second subscription that
// forces serialisation (sensor_msgs/PointCloud2) shows that the check can fail.
TEST(PacketToCloud, ZeroCopyInsideTheManagerAndPerPacketTransform) {
  ros::NodeHandle nh("/zc");
  tf2_ros::StaticTransformBroadcaster broadcaster;
  geometry_msgs::TransformStamped sensor_in_base;
  sensor_in_base.header.frame_id = "base_link";
  sensor_in_base.child_frame_id = "velodyne";
  sensor_in_base.transform.translation.x = 1.0;
  sensor_in_base.transform.translation.y = 2.0;
  sensor_in_base.transform.translation.z = 3.0;
  sensor_in_base.transform.rotation.z = std::sqrt(0.5);  // yaw +90 deg
  sensor_in_base.transform.rotation.w = std::sqrt(0.5);
  broadcaster.sendTransform(sensor_in_base);

  ros::param::set("/zc/packet_to_cloud/target_frame", "base_link");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/zc/packet_to_cloud", "urban_detection/PacketToCloud", {}, {}));

  // Advertise before subscribing downstream: roscpp can miss an in-process connection when a
  // publisher is advertised while a subscription to its topic is being set up in another thread.
  ros::Publisher pub = nh.advertise<VelodyneScan>("velodyne_packets", 5);
  Collector<CloudXYZIRT> same_type;
  Collector<sensor_msgs::PointCloud2> serialised;
  ros::Subscriber sub1 =
      nh.subscribe("velodyne_points", 5, &Collector<CloudXYZIRT>::callback, &same_type);
  ros::Subscriber sub2 = nh.subscribe("velodyne_points", 5,
                                      &Collector<sensor_msgs::PointCloud2>::callback, &serialised);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));

  const auto scan = makeScan(makePackets(kPacketsPerRevolution, 0.5), ros::Time(100.0), 0.0);
  ASSERT_TRUE(waitFor(
      [&] {
        if (same_type.size() == 0) pub.publish(scan);  // retried until tf_static has arrived
        return same_type.size() > 0 && serialised.size() > 0;
      },
      10.0));

  const auto cloud = same_type.at(0);
  EXPECT_EQ(cloud->header.frame_id, "base_link");
  EXPECT_FLOAT_EQ(cloud->sensor_origin_.x(), 1.0f);
  EXPECT_FLOAT_EQ(cloud->sensor_origin_.y(), 2.0f);
  EXPECT_FLOAT_EQ(cloud->sensor_origin_.z(), 3.0f);
  EXPECT_NEAR(cloud->sensor_orientation_.z(), std::sqrt(0.5), 1e-6);

  CloudXYZIRT copy;  // the same message after serialisation: the sensor pose is lost
  pcl::fromROSMsg(*serialised.at(0), copy);
  EXPECT_EQ(copy.size(), cloud->size());
  EXPECT_FLOAT_EQ(copy.sensor_origin_.x(), 0.0f);

  // Points: the reference decode in the sensor frame, rotated by +90 deg and shifted.
  CloudXYZIRT reference;
  decodeReference(*scan, &reference);
  ASSERT_EQ(reference.size(), kPacketsPerRevolution * kReturnsPerPacket);
  ASSERT_EQ(cloud->size(), reference.size());
  for (std::size_t i = 0; i < cloud->size(); i += 97) {
    EXPECT_NEAR(cloud->points[i].x, 1.0f - reference.points[i].y, 1e-4);
    EXPECT_NEAR(cloud->points[i].y, 2.0f + reference.points[i].x, 1e-4);
    EXPECT_NEAR(cloud->points[i].z, 3.0f + reference.points[i].z, 1e-4);
    EXPECT_EQ(cloud->points[i].ring, reference.points[i].ring);
  }
}

// Lazy: no subscription to the packets while nobody listens to the points.
TEST(PacketToCloud, SubscribesUpstreamOnlyWhileSomeoneListens) {
  ros::NodeHandle nh("/lazy");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/lazy/packet_to_cloud", "urban_detection/PacketToCloud", {}, {}));
  ros::Publisher pub = nh.advertise<VelodyneScan>("velodyne_packets", 5);
  ros::Duration(1.0).sleep();
  EXPECT_EQ(pub.getNumSubscribers(), 0u);

  Collector<CloudXYZIRT> clouds;
  ros::Subscriber sub =
      nh.subscribe("velodyne_points", 5, &Collector<CloudXYZIRT>::callback, &clouds);
  EXPECT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  sub.shutdown();
  EXPECT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 0; }, 10.0));
  sub = nh.subscribe("velodyne_points", 5, &Collector<CloudXYZIRT>::callback, &clouds);
  EXPECT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
}

// Bad packets inside a scan are dropped whole and counted; the good ones are all decoded.
// Revolutions skipped upstream (gaps in header.seq) are counted too.
TEST(PacketToCloud, DropsBadPacketsWholeAndCountsThem) {
  ros::NodeHandle nh("/badscan");
  DiagnosticsWatcher diagnostics;
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/badscan/packet_to_cloud", "urban_detection/PacketToCloud", {}, {}));
  ros::Publisher pub = nh.advertise<VelodyneScan>("velodyne_packets", 5);  // first (see above)
  Collector<CloudXYZIRT> clouds;
  ros::Subscriber sub =
      nh.subscribe("velodyne_points", 5, &Collector<CloudXYZIRT>::callback, &clouds);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));

  // Revolutions numbered 1 and 4 by their source: 2 and 3 were skipped upstream.
  auto first = makeScan(makePackets(2, 0.5), ros::Time(199.0), 0.000288);
  first->header.seq = 1;
  pub.publish(first);
  // One at a time: the input queue is 2 deep and drops the oldest revolution when full.
  ASSERT_TRUE(waitFor([&] { return clouds.size() == 1; }, 10.0));
  auto packets = makePackets(10, 0.5);
  packets[2][100] = 0x12;  // block 1 id 0xEEFF -> 0x12FF: unknown block id
  packets[5][1] = 0x00;    // block 0 id -> 0x00FF
  packets[7][2] = 0xFF;    // block 0 azimuth 0xFF.. >= 36000
  packets[7][3] = 0xFF;
  auto scan = makeScan(packets, ros::Time(200.0), 0.000288);
  scan->header.seq = 4;
  pub.publish(scan);
  ASSERT_TRUE(waitFor([&] { return clouds.size() == 2; }, 10.0));
  auto empty = boost::make_shared<VelodyneScan>();
  empty->header.frame_id = "velodyne";
  pub.publish(empty);
  EXPECT_EQ(clouds.at(0)->size(), 2 * kReturnsPerPacket);
  EXPECT_EQ(clouds.at(1)->size(), 7 * kReturnsPerPacket);
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics.value("badscan/packet_to_cloud", "bad_packets") == 3 &&
               diagnostics.value("badscan/packet_to_cloud", "empty_scans") == 1 &&
               diagnostics.value("badscan/packet_to_cloud", "skipped_revolutions") == 2;
      },
      10.0));
  ros::Duration(0.3).sleep();
  EXPECT_EQ(clouds.size(), 2u);  // the empty scan produced no cloud
}

// Bad parameters and a bad calibration file: one clear error, the nodelet stays inactive, the
// manager (this process) keeps running.
TEST(PacketToCloud, BadParametersAndCalibrationFailInitClearly) {
  RosoutWatcher rosout;
  nodelet::Loader manager(false);
  ros::param::set("/badparam/packet_to_cloud/min_range", 50.0);
  ros::param::set("/badparam/packet_to_cloud/max_range", 10.0);
  manager.load("/badparam/packet_to_cloud", "urban_detection/PacketToCloud", {}, {});
  ros::param::set("/badrange/packet_to_cloud/max_range", 1000.0);
  manager.load("/badrange/packet_to_cloud", "urban_detection/PacketToCloud", {}, {});

  const std::string calibration = "/tmp/urban_detection_bad_calibration.yaml";
  FILE* f = std::fopen(calibration.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs("lasers:\n  - {laser_id: 0, rot_correction: not-a-number}\n", f);
  std::fclose(f);
  ros::param::set("/badcal/packet_to_cloud/calibration", calibration);
  manager.load("/badcal/packet_to_cloud", "urban_detection/PacketToCloud", {}, {});

  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(rosgraph_msgs::Log::FATAL, "max_range") &&
               rosout.contains(rosgraph_msgs::Log::FATAL, "accepted [0.1, 250] m") &&
               rosout.contains(rosgraph_msgs::Log::FATAL, calibration) &&
               rosout.contains(rosgraph_msgs::Log::FATAL, "laser 0") &&
               rosout.contains(rosgraph_msgs::Log::FATAL, "field 'rot_correction'");
      },
      10.0));
  for (const char* ns : {"/badparam", "/badrange", "/badcal"}) {
    Collector<CloudXYZIRT> clouds;
    ros::Subscriber sub = ros::NodeHandle(ns).subscribe("velodyne_points", 1,
                                                        &Collector<CloudXYZIRT>::callback, &clouds);
    ros::Duration(0.5).sleep();
    EXPECT_EQ(sub.getNumPublishers(), 0u) << ns;
  }
  std::remove(calibration.c_str());
}

// ------------------------------------------------------------------------------------------
// UDP on 127.0.0.1: half a revolution, a whole one and the start of the next, sent by a
// "sensor": exactly the whole revolution arrives, with the sent bytes, cut at the cut angle; the
// partial revolutions at both ends are not published.
TEST(PacketSource, UdpRevolutionsCutAtTheCutAngle) {
  const int port = freeUdpPort();
  ros::NodeHandle nh("/udp");
  ros::param::set("/udp/packet_source/port", port);
  ros::param::set("/udp/packet_source/device_ip", "127.0.0.1");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/udp/packet_source", "urban_detection/PacketSource", {}, {}));
  Collector<VelodyneScan> scans;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 10, &Collector<VelodyneScan>::callback, &scans);
  ASSERT_TRUE(waitFor([&] { return sub.getNumPublishers() == 1; }, 10.0));

  // 30 packets of a partial revolution (180.5 .. 354.5 deg), one whole, 5 of the next.
  std::vector<core::RawPacket> packets = makePackets(30, 180.5);
  const std::vector<core::RawPacket> whole = makePackets(kPacketsPerRevolution, 0.5);
  packets.insert(packets.end(), whole.begin(), whole.end());
  const std::vector<core::RawPacket> next = makePackets(5, 0.5);
  packets.insert(packets.end(), next.begin(), next.end());
  UdpSender sender(port);
  const ros::Time before = ros::Time::now();
  for (const auto& p : packets) sender.send(p.data(), p.size());

  ASSERT_TRUE(waitFor([&] { return scans.size() >= 1; }, 10.0));
  const auto scan = scans.at(0);
  ASSERT_EQ(scan->packets.size(), static_cast<std::size_t>(kPacketsPerRevolution));
  EXPECT_EQ(scan->header.frame_id, "velodyne");
  EXPECT_EQ(scan->header.stamp, scan->packets.back().stamp);  // velodyne_driver's convention
  EXPECT_GE(scan->header.stamp, before);
  for (int i = 0; i < kPacketsPerRevolution; ++i) {
    EXPECT_TRUE(std::equal(whole[i].begin(), whole[i].end(), scan->packets[i].data.begin()))
        << "packet " << i;
    if (i > 0) {
      EXPECT_GE(scan->packets[i].stamp, scan->packets[i - 1].stamp);
    }
  }
  CloudXYZIRT cloud;
  decodeReference(*scan, &cloud);
  EXPECT_EQ(cloud.size(), kPacketsPerRevolution * kReturnsPerPacket);
  ros::Duration(0.3).sleep();
  EXPECT_EQ(scans.size(), 1u);  // the leading partial revolution was dropped, the next is open
}

// Streaming decoding (~decode): the same UDP stream gives, on velodyne_points, the cloud of the
// whole revolution, equal to the batch decode of the scan PacketSource publishes beside it,
// stamped with the revolution's first packet when timestamp_first_packet is true; a
// subscriber of the publisher's type gets the published object itself (two subscribers: one
// address).
TEST(PacketSource, StreamingDecodePublishesTheRevolutionsCloud) {
  const int port = freeUdpPort();
  ros::NodeHandle nh("/stream");
  ros::param::set("/stream/packet_source/port", port);
  ros::param::set("/stream/packet_source/device_ip", "127.0.0.1");
  ros::param::set("/stream/packet_source/decode", true);
  ros::param::set("/stream/packet_source/timestamp_first_packet", true);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/stream/packet_source", "urban_detection/PacketSource", {}, {}));
  Collector<VelodyneScan> scans;
  Collector<CloudXYZIRT> clouds, clouds2;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 10, &Collector<VelodyneScan>::callback, &scans);
  ros::Subscriber sub_points =
      nh.subscribe("velodyne_points", 10, &Collector<CloudXYZIRT>::callback, &clouds);
  ros::Subscriber sub_points2 =
      nh.subscribe("velodyne_points", 10, &Collector<CloudXYZIRT>::callback, &clouds2);
  ASSERT_TRUE(waitFor(
      [&] { return sub.getNumPublishers() == 1 && sub_points.getNumPublishers() == 1; }, 10.0));

  std::vector<core::RawPacket> packets = makePackets(30, 180.5);
  const std::vector<core::RawPacket> whole = makePackets(kPacketsPerRevolution, 0.5);
  packets.insert(packets.end(), whole.begin(), whole.end());
  const std::vector<core::RawPacket> next = makePackets(1, 0.5);  // closes the revolution
  packets.insert(packets.end(), next.begin(), next.end());
  UdpSender sender(port);
  for (const auto& p : packets) sender.send(p.data(), p.size());

  ASSERT_TRUE(waitFor(
      [&] { return scans.size() >= 1 && clouds.size() >= 1 && clouds2.size() >= 1; }, 10.0));
  const auto scan = scans.at(0);
  const auto cloud = clouds.at(0);
  EXPECT_EQ(cloud.get(), clouds2.at(0).get()) << "the cloud was copied on the way";
  EXPECT_EQ(scan->header.stamp, scan->packets.front().stamp);
  EXPECT_EQ(pcl_conversions::fromPCL(cloud->header.stamp).toNSec() / 1000,
            scan->header.stamp.toNSec() / 1000);  // PCL stamps are whole microseconds
  EXPECT_EQ(cloud->header.frame_id, "velodyne");
  CloudXYZIRT reference;
  decodeReference(*scan, &reference);
  ASSERT_EQ(cloud->size(), reference.size());
  ASSERT_EQ(reference.size(), kPacketsPerRevolution * kReturnsPerPacket);
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    ASSERT_EQ(cloud->points[i].x, reference.points[i].x) << i;
    ASSERT_EQ(cloud->points[i].y, reference.points[i].y) << i;
    ASSERT_EQ(cloud->points[i].z, reference.points[i].z) << i;
    ASSERT_EQ(cloud->points[i].ring, reference.points[i].ring) << i;
    ASSERT_NEAR(cloud->points[i].time, reference.points[i].time, 2e-6f) << i;
  }
}

// Zero copy on the real consumer: GridSegmentation, loaded in this manager, receives the cloud
// published here as the object itself. The proof is the cloud's sensor pose (sensor_origin_),
// which GridSegmentation copies into its outputs and which the PointCloud2 wire format does not
// carry: a serialised hop anywhere (velodyne_points -> GridSegmentation -> foreground) would
// reset it to zero. The same cloud sent as PointCloud2 through CloudInput (the bag path) arrives
// without it, which shows the check can fail.
TEST(GridSegmentation, ReceivesTheCloudItselfInsideTheManager) {
  ros::NodeHandle nh("/zcseg");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/zcseg/grid_segmentation", "urban_detection/GridSegmentation", {}, {}));
  ros::Publisher pub = nh.advertise<CloudXYZIRT>("velodyne_points", 2);
  Collector<LabeledCloud> foreground;
  ros::Subscriber sub =
      nh.subscribe("segmentation/foreground", 5, &Collector<LabeledCloud>::callback, &foreground);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));

  // A flat street with one box (a car) 10 m ahead: foreground is the box.
  auto cloud = boost::make_shared<CloudXYZIRT>();
  cloud->header.frame_id = "velodyne";
  for (float x = -30.f; x <= 30.f; x += 0.25f) {
    for (float y = -30.f; y <= 30.f; y += 0.25f) {
      PointXYZIRT p;
      p.x = x;
      p.y = y;
      p.z = -1.73f;
      p.intensity = 10.f;
      p.ring = 0;
      p.time = 0.f;
      cloud->push_back(p);
    }
  }
  for (float x = 9.f; x <= 13.f; x += 0.1f) {
    for (float z = -1.5f; z <= -0.3f; z += 0.1f) {
      for (float y : {-1.f, 1.f}) {
        PointXYZIRT p;
        p.x = x;
        p.y = y;
        p.z = z;
        p.intensity = 50.f;
        p.ring = 10;
        p.time = 0.f;
        cloud->push_back(p);
      }
    }
  }
  cloud->sensor_origin_ = Eigen::Vector4f(7.f, 8.f, 9.f, 0.f);
  ASSERT_TRUE(waitFor(
      [&] {
        pub.publish(boost::shared_ptr<const CloudXYZIRT>(cloud));
        return foreground.size() > 0;
      },
      10.0));
  const auto fg = foreground.at(0);
  ASSERT_GT(fg->size(), 50u);
  EXPECT_FLOAT_EQ(fg->sensor_origin_.x(), 7.f);
  EXPECT_FLOAT_EQ(fg->sensor_origin_.y(), 8.f);
  EXPECT_FLOAT_EQ(fg->sensor_origin_.z(), 9.f);

  // The bag path: PointCloud2 -> CloudInput -> GridSegmentation: the pose is lost on the wire.
  ASSERT_TRUE(manager.load("/zcseg/cloud_input", "urban_detection/CloudInput", {}, {}));
  pub.shutdown();
  ros::Publisher pub2 = nh.advertise<sensor_msgs::PointCloud2>("points_in", 2);
  ASSERT_TRUE(waitFor([&] { return pub2.getNumSubscribers() == 1; }, 10.0));
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(*cloud, msg);
  const std::size_t before = foreground.size();
  ASSERT_TRUE(waitFor(
      [&] {
        pub2.publish(msg);
        return foreground.size() > before;
      },
      10.0));
  const auto copied = foreground.at(foreground.size() - 1);
  EXPECT_EQ(copied->size(), fg->size());
  EXPECT_FLOAT_EQ(copied->sensor_origin_.x(), 0.f);
}

// A lazy stage that had no subscriber for a while does not count the revolutions that passed
// meanwhile as skipped (they were never wanted); a real gap while it listens still counts.
TEST(GridSegmentation, RevolutionsPassedWhileUnsubscribedAreNotSkipped) {
  ros::NodeHandle nh("/lazyseq");
  DiagnosticsWatcher diagnostics;
  nodelet::Loader manager(false);
  ASSERT_TRUE(
      manager.load("/lazyseq/grid_segmentation", "urban_detection/GridSegmentation", {}, {}));
  ros::Publisher pub = nh.advertise<CloudXYZIRT>("velodyne_points", 20);
  auto make = [](std::uint32_t seq) {
    auto c = boost::make_shared<CloudXYZIRT>();
    c->header.frame_id = "velodyne";
    c->header.seq = seq;
    for (int i = 0; i < 100; ++i) {
      PointXYZIRT p;
      p.x = 5.f + 0.1f * static_cast<float>(i);
      p.y = 1.f;
      p.z = -1.7f;
      p.intensity = 1.f;
      p.ring = 0;
      p.time = 0.f;
      c->push_back(p);
    }
    return boost::shared_ptr<const CloudXYZIRT>(c);
  };
  std::uint32_t seq = 0;
  auto feed = [&](Collector<LabeledCloud>* out, int n) {
    for (int i = 0; i < n; ++i) {
      const std::size_t before = out ? out->size() : 0;
      pub.publish(make(++seq));
      if (out)
        ASSERT_TRUE(waitFor([&] { return out->size() > before; }, 5.0)) << seq;
      else
        ros::WallDuration(0.01).sleep();
    }
  };
  {
    Collector<LabeledCloud> labeled;
    ros::Subscriber sub = nh.subscribe("segmentation/labeled_points", 20,
                                       &Collector<LabeledCloud>::callback, &labeled);
    ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
    feed(&labeled, 5);
  }
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 0; }, 10.0));
  feed(nullptr, 40);  // nobody listens: the stage is unsubscribed
  Collector<LabeledCloud> labeled;
  ros::Subscriber sub =
      nh.subscribe("segmentation/labeled_points", 20, &Collector<LabeledCloud>::callback, &labeled);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  feed(&labeled, 5);
  seq += 3;  // three revolutions lost while it listens
  feed(&labeled, 2);
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics.value("lazyseq/grid_segmentation", "revolutions") == 12 &&
               diagnostics.value("lazyseq/grid_segmentation", "skipped_revolutions") == 3;
      },
      10.0))
      << "skipped " << diagnostics.value("lazyseq/grid_segmentation", "skipped_revolutions");
}

// Datagrams of the wrong size or from another sender never crash the source, never enter a
// scan, and are counted on /diagnostics.
TEST(PacketSource, BadUdpDatagramsAreDroppedAndCounted) {
  const int port = freeUdpPort();
  ros::NodeHandle nh("/badudp");
  DiagnosticsWatcher diagnostics;
  ros::param::set("/badudp/packet_source/port", port);
  ros::param::set("/badudp/packet_source/device_ip", "127.0.0.1");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/badudp/packet_source", "urban_detection/PacketSource", {}, {}));
  Collector<VelodyneScan> scans;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 10, &Collector<VelodyneScan>::callback, &scans);
  ASSERT_TRUE(waitFor([&] { return sub.getNumPublishers() == 1; }, 10.0));

  UdpSender sender(port), stranger(port, "127.0.0.2");
  const std::vector<std::uint8_t> garbage(1500, 0xAB);
  std::vector<core::RawPacket> packets = makePackets(30, 180.5);  // partial, then 2 whole
  const std::vector<core::RawPacket> more = makePackets(2 * kPacketsPerRevolution + 1, 0.5);
  packets.insert(packets.end(), more.begin(), more.end());
  int bad = 0, foreign = 0;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    if (i % 10 == 3) sender.send(garbage.data(), 100), ++bad;
    if (i % 10 == 6) sender.send(garbage.data(), 1300), ++bad;
    if (i % 10 == 8) sender.send(garbage.data(), 0), ++bad;
    if (i % 20 == 9) stranger.send(packets[i].data(), packets[i].size()), ++foreign;
    sender.send(packets[i].data(), packets[i].size());
  }
  ASSERT_TRUE(waitFor([&] { return scans.size() >= 2; }, 10.0));
  for (std::size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(scans.at(s)->packets.size(), static_cast<std::size_t>(kPacketsPerRevolution));
  }
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics.value("badudp/packet_source", "bad_size_packets") == bad &&
               diagnostics.value("badudp/packet_source", "partial_revolutions_dropped") == 1 &&
               diagnostics.value("badudp/packet_source", "other_sender_packets") == foreign &&
               diagnostics.value("badudp/packet_source", "packets") ==
                   static_cast<long>(packets.size());
      },
      10.0))
      << "bad " << bad << " foreign " << foreign;
}

// pcap written with PcapWriter -> PacketSource replay (half speed) -> PacketToCloud -> clouds.
TEST(PacketSource, PcapReplayThroughPacketToCloud) {
  const std::string pcap = "/tmp/urban_detection_test_replay_" + std::to_string(getpid()) + ".pcap";
  const double packet_period_s = 0.1 / kPacketsPerRevolution;  // 600 rpm
  const double t0 = 1700000000.0;
  {
    core::PcapWriter writer(pcap);
    // A partial revolution, three whole ones, and the first packet of the next one.
    auto packets = makePackets(10, 300.5);
    const auto whole = makePackets(3 * kPacketsPerRevolution + 1, 0.5);
    packets.insert(packets.end(), whole.begin(), whole.end());
    for (std::size_t i = 0; i < packets.size(); ++i) {
      writer.write(packets[i], t0 + static_cast<double>(i) * packet_period_s);
    }
  }
  ros::NodeHandle nh("/pcap");
  ros::param::set("/pcap/packet_source/pcap", pcap);
  ros::param::set("/pcap/packet_source/rate", 0.5);
  ros::param::set("/pcap/packet_to_cloud/queue_size", 10);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/pcap/packet_source", "urban_detection/PacketSource", {}, {}));
  ASSERT_TRUE(manager.load("/pcap/packet_to_cloud", "urban_detection/PacketToCloud", {}, {}));
  std::vector<ros::WallTime> arrivals;
  std::mutex mutex;
  Collector<CloudXYZIRT> clouds;
  ros::Subscriber sub = nh.subscribe<CloudXYZIRT>(
      "velodyne_points", 10, [&](const boost::shared_ptr<const CloudXYZIRT>& cloud) {
        {
          std::lock_guard<std::mutex> lock(mutex);
          arrivals.push_back(ros::WallTime::now());
        }
        clouds.callback(cloud);
      });
  // Replay starts only once the chain is connected (lazy source), so no revolution is lost.
  ASSERT_TRUE(waitFor([&] { return clouds.size() == 3; }, 20.0));
  std::remove(pcap.c_str());
  for (std::size_t i = 0; i < 3; ++i) {
    const auto cloud = clouds.at(i);
    EXPECT_EQ(cloud->size(), kPacketsPerRevolution * kReturnsPerPacket);
    EXPECT_EQ(cloud->header.frame_id, "velodyne");
    float max_time = 0;
    for (const auto& p : cloud->points) {
      EXPECT_NEAR(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z), 10.0f, 0.01f);
      max_time = std::max(max_time, p.time);
      ASSERT_GE(p.time, 0.0f);
    }
    // Last packet starts 59 periods after the first; its firings last under 0.3 ms.
    EXPECT_GE(max_time, 59 * packet_period_s);
    EXPECT_LT(max_time, 59 * packet_period_s + 0.0004);
    if (i > 0) {  // stamps keep the recorded spacing whatever the replay rate
      const double dt_s = (pcl_conversions::fromPCL(cloud->header.stamp) -
                           pcl_conversions::fromPCL(clouds.at(i - 1)->header.stamp))
                              .toSec();
      EXPECT_NEAR(dt_s, 0.1, 1e-4);
    }
  }
  // At half speed the third revolution comes 2 x 0.2 s after the first; as fast as possible
  // would take milliseconds.
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_GT((arrivals[2] - arrivals[0]).toSec(), 0.3);
}

// Loop replay: every pass yields the file's whole revolution; stamps keep increasing across
// passes (shifted by the file's span plus one packet period).
TEST(PacketSource, PcapLoopKeepsStampsIncreasing) {
  const std::string pcap = "/tmp/urban_detection_test_loop_" + std::to_string(getpid()) + ".pcap";
  const double packet_period_s = 0.1 / kPacketsPerRevolution;
  std::size_t count = 0;
  {
    core::PcapWriter writer(pcap);
    auto packets = makePackets(10, 300.5);
    const auto whole = makePackets(kPacketsPerRevolution + 1, 0.5);
    packets.insert(packets.end(), whole.begin(), whole.end());
    for (const auto& packet : packets) {
      writer.write(packet, 1700000000.0 + static_cast<double>(count++) * packet_period_s);
    }
  }
  ros::NodeHandle nh("/loop");
  ros::param::set("/loop/packet_source/pcap", pcap);
  ros::param::set("/loop/packet_source/rate", 5.0);
  ros::param::set("/loop/packet_source/loop", true);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/loop/packet_source", "urban_detection/PacketSource", {}, {}));
  Collector<VelodyneScan> scans;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 100, &Collector<VelodyneScan>::callback, &scans);
  ASSERT_TRUE(waitFor([&] { return scans.size() >= 5; }, 20.0));
  sub.shutdown();
  manager.clear();
  std::remove(pcap.c_str());
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(scans.at(i)->packets.size(), static_cast<std::size_t>(kPacketsPerRevolution));
    if (i > 0) {
      EXPECT_NEAR((scans.at(i)->header.stamp - scans.at(i - 1)->header.stamp).toSec(),
                  static_cast<double>(count) * packet_period_s, 1e-5);
    }
  }
}

// Writes `packets` to a pcap, one packet period apart from t0 (600 rpm); returns its path.
std::string writePcap(const std::string& tag, const std::vector<core::RawPacket>& packets,
                      double packet_period_s, const std::vector<bool>& garbage_after = {}) {
  const std::string pcap =
      "/tmp/urban_detection_test_" + tag + "_" + std::to_string(getpid()) + ".pcap";
  core::PcapWriter writer(pcap);
  core::RawPacket garbage;
  for (std::size_t b = 0; b < garbage.size(); ++b) garbage[b] = static_cast<std::uint8_t>(b * 7);
  for (std::size_t i = 0; i < packets.size(); ++i) {
    const double t = 1700000000.0 + static_cast<double>(i) * packet_period_s;
    writer.write(packets[i], t);
    // Another sender's datagram with the capture time of the packet before it.
    if (i < garbage_after.size() && garbage_after[i]) writer.write(garbage, t);
  }
  return pcap;
}

// A capture of whole revolutions from the cut angle to the cut angle (as the simulator writes
// them) gives every revolution, as the offline reader (PcapRevolutionReader) gives them: the
// first, begun at the cut, and the last, ended by the file, included; looped, every pass gives
// all of them and the stamps go on by one revolution period across the seam.
TEST(PacketSource, PcapReplayKeepsTheRevolutionsAtTheFileEndsAndTheLoopSeam) {
  const double packet_period_s = 0.1 / kPacketsPerRevolution;
  const auto packets = makePackets(4 * kPacketsPerRevolution, 0.5);
  const std::string pcap = writePcap("ends", packets, packet_period_s);
  {
    core::PcapRevolutionReader reader(pcap);
    std::vector<core::PcapPacket> revolution;
    std::size_t offline = 0;
    while (reader.next(&revolution) == core::PcapRevolutionReader::Result::kRevolution) ++offline;
    EXPECT_EQ(offline, 4u);
  }
  for (const bool loop : {false, true}) {
    const std::string ns = loop ? "/seam_loop" : "/seam_once";
    ros::NodeHandle nh(ns);
    ros::param::set(ns + "/packet_source/pcap", pcap);
    ros::param::set(ns + "/packet_source/rate", 4.0);
    ros::param::set(ns + "/packet_source/loop", loop);
    Collector<VelodyneScan> scans;
    ros::Subscriber sub =
        nh.subscribe("velodyne_packets", 100, &Collector<VelodyneScan>::callback, &scans);
    nodelet::Loader manager(false);
    ASSERT_TRUE(manager.load(ns + "/packet_source", "urban_detection/PacketSource", {}, {}));
    const std::size_t wanted = loop ? 12 : 4;  // three passes when looped
    ASSERT_TRUE(waitFor([&] { return scans.size() >= wanted; }, 30.0)) << scans.size();
    if (!loop) {  // nothing more comes once the file ended
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      EXPECT_EQ(scans.size(), 4u);
    }
    sub.shutdown();
    manager.clear();
    for (std::size_t i = 0; i < wanted; ++i) {
      EXPECT_EQ(scans.at(i)->packets.size(), static_cast<std::size_t>(kPacketsPerRevolution));
      EXPECT_EQ(scans.at(i)->header.seq, i + 1);
      if (i > 0) {
        EXPECT_NEAR((scans.at(i)->header.stamp - scans.at(i - 1)->header.stamp).toSec(), 0.1, 1e-5)
            << "revolution " << i << (loop ? " (looped)" : "");
      }
    }
  }
  std::remove(pcap.c_str());
}

// A replay paused while nobody listens resumes with stamps of the clock: the first packet
// after the pause is stamped now, not where the replay timeline stood (which would put every
// later stamp behind the clock by the idle time). The bound leaves a loaded machine ~1 s for
// the replay to resume; the idle time is 3 s.
TEST(PacketSource, PcapStampsFollowTheClockAfterIdleTime) {
  const double packet_period_s = 0.1 / kPacketsPerRevolution;
  const std::string pcap =
      writePcap("idle", makePackets(100 * kPacketsPerRevolution, 0.5), packet_period_s);
  ros::NodeHandle nh("/idle");
  ros::param::set("/idle/packet_source/pcap", pcap);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/idle/packet_source", "urban_detection/PacketSource", {}, {}));
  Collector<VelodyneScan> first, second;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 100, &Collector<VelodyneScan>::callback, &first);
  ASSERT_TRUE(waitFor([&] { return first.size() >= 3; }, 20.0));
  sub.shutdown();
  std::this_thread::sleep_for(std::chrono::seconds(3));
  sub = nh.subscribe("velodyne_packets", 100, &Collector<VelodyneScan>::callback, &second);
  ASSERT_TRUE(waitFor([&] { return second.size() >= 3; }, 20.0));
  const ros::Time now = ros::Time::now();
  sub.shutdown();
  manager.clear();
  std::remove(pcap.c_str());
  const auto last = second.at(2);
  EXPECT_LT((now - last->header.stamp).toSec(), 1.0) << "stamps behind the clock";
  EXPECT_GT(last->header.stamp, first.at(first.size() - 1)->header.stamp);
  for (std::size_t i = 0; i < 3; ++i) {  // a revolution open at the pause moved with it
    const auto& packets = second.at(i)->packets;
    EXPECT_NEAR((packets.back().stamp - packets.front().stamp).toSec(),
                (kPacketsPerRevolution - 1) * packet_period_s, 1e-5);
  }
}

// Datagrams that are not HDL-64E packets (here after every packet, with its capture time) are
// refused and counted but take no time of the replay: revolutions keep the sensor's 0.1 s.
TEST(PacketSource, RefusedDatagramsDoNotSlowThePcapReplay) {
  RosoutWatcher rosout;
  const double packet_period_s = 0.1 / kPacketsPerRevolution;
  const auto packets = makePackets(4 * kPacketsPerRevolution, 0.5);
  const std::string pcap =
      writePcap("garbage", packets, packet_period_s, std::vector<bool>(packets.size(), true));
  ros::NodeHandle nh("/garbage");
  ros::param::set("/garbage/packet_source/pcap", pcap);
  ros::param::set("/garbage/packet_source/rate", 4.0);
  Collector<VelodyneScan> scans;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 100, &Collector<VelodyneScan>::callback, &scans);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/garbage/packet_source", "urban_detection/PacketSource", {}, {}));
  ASSERT_TRUE(waitFor([&] { return scans.size() >= 4; }, 30.0));
  sub.shutdown();
  manager.clear();
  std::remove(pcap.c_str());
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_NEAR((scans.at(i)->header.stamp - scans.at(i - 1)->header.stamp).toSec(), 0.1, 1e-5);
  }
  EXPECT_TRUE(rosout.contains(rosgraph_msgs::Log::WARN, "refusing invalid packets"));
  EXPECT_FALSE(rosout.contains(rosgraph_msgs::Log::WARN, "capture time"));
}

// Faults that are logged as ERROR turn /diagnostics to ERROR too: a capture without a packet
// for the port; a live source without data goes WARN, then ERROR; and a source that refused
// to start shows only its ERROR, no OK status beside it.
TEST(PacketSource, DiagnosticsTellTheFaultsItLogs) {
  RosoutWatcher rosout;
  DiagnosticsWatcher diagnostics;
  const std::string empty = writePcap("noport", {}, 0.001);
  ros::param::set("/noport/packet_source/pcap", empty);
  const int port = freeUdpPort();
  ros::param::set("/silent/packet_source/port", port);
  ros::param::set("/badcal/packet_source/pcap", empty);
  ros::param::set("/badcal/packet_source/decode", true);
  ros::param::set("/badcal/packet_source/calibration", "/nonexistent/64e.yaml");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/noport/packet_source", "urban_detection/PacketSource", {}, {}));
  ASSERT_TRUE(manager.load("/silent/packet_source", "urban_detection/PacketSource", {}, {}));
  manager.load("/badcal/packet_source", "urban_detection/PacketSource", {}, {});
  ros::NodeHandle nh("/noport");
  Collector<VelodyneScan> scans;
  ros::Subscriber sub =
      nh.subscribe("velodyne_packets", 1, &Collector<VelodyneScan>::callback, &scans);
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.sawError("noport/packet_source", "no HDL-64E packet"); }, 10.0));
  EXPECT_TRUE(rosout.contains(rosgraph_msgs::Log::ERROR, "no HDL-64E packet for UDP port"));
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.sawWarning("silent/packet_source", "no sensor data"); }, 10.0));
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.sawError("silent/packet_source", "no sensor data"); }, 15.0));
  EXPECT_TRUE(waitFor(
      [&] { return diagnostics.sawError("badcal/packet_source", "/nonexistent/64e.yaml"); }, 5.0));
  // (diagnostic_updater announces every task once with OK "Node starting up"; the stage's
  // status of a refused source used to follow once a second with OK "waiting for input".)
  EXPECT_FALSE(diagnostics.saw("badcal/packet_source", diagnostic_msgs::DiagnosticStatus::OK,
                               "waiting for input"));
  sub.shutdown();
  manager.clear();
  std::remove(empty.c_str());
}

TEST(PacketSource, BadParametersFailInitClearly) {
  RosoutWatcher rosout;
  DiagnosticsWatcher diagnostics;
  nodelet::Loader manager(false);
  ros::param::set("/badsrc/packet_source/port", 70000);
  manager.load("/badsrc/packet_source", "urban_detection/PacketSource", {}, {});
  ros::param::set("/badip/packet_source/device_ip", "192.168.1");
  manager.load("/badip/packet_source", "urban_detection/PacketSource", {}, {});
  ros::param::set("/nopcap/packet_source/pcap", "/nonexistent/drive.pcap");
  manager.load("/nopcap/packet_source", "urban_detection/PacketSource", {}, {});
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(rosgraph_msgs::Log::FATAL, "'/badsrc/packet_source/port' = 70000") &&
               rosout.contains(rosgraph_msgs::Log::FATAL, "192.168.1") &&
               rosout.contains(rosgraph_msgs::Log::FATAL, "/nonexistent/drive.pcap");
      },
      10.0));
  // The same text on /diagnostics, at ERROR (not "waiting for input").
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics.sawError("badsrc/packet_source",
                                    "'/badsrc/packet_source/port' = 70000") &&
               diagnostics.sawError("nopcap/packet_source", "/nonexistent/drive.pcap");
      },
      5.0));
}

// A value of the wrong type is refused, never replaced by the default: strings where
// numbers belong, as YAML 1.1 reads `cell_size_m: half` and `min_points_per_cell: 5e0`.
TEST(GridSegmentation, WrongParameterTypesFailInitClearly) {
  RosoutWatcher rosout;
  nodelet::Loader manager(false);
  ros::param::set("/segstr/grid_segmentation/cell_size_m", std::string("half"));
  manager.load("/segstr/grid_segmentation", "urban_detection/GridSegmentation", {}, {});
  ros::param::set("/segint/grid_segmentation/min_points_per_cell", std::string("5e0"));
  manager.load("/segint/grid_segmentation", "urban_detection/GridSegmentation", {}, {});
  DiagnosticsWatcher diagnostics;
  EXPECT_TRUE(waitFor(
      [&] {
        return diagnostics.sawError("segstr/grid_segmentation",
                                    "parameter '/segstr/grid_segmentation/cell_size_m' must be a "
                                    "number");
      },
      10.0));
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(
                   rosgraph_msgs::Log::FATAL,
                   "parameter '/segstr/grid_segmentation/cell_size_m' must be a number") &&
               rosout.contains(
                   rosgraph_msgs::Log::FATAL,
                   "parameter '/segint/grid_segmentation/min_points_per_cell' must be an "
                   "integer");
      },
      10.0));
}

}  // namespace
}  // namespace ros_conv
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_nodelets");
}
