// rostest: CloudInput + the GridSegmentation nodelet segment a KITTI-style PointCloud2 (x y z
// intensity, no ring/time, published on points_in) of a synthetic street, publishes labelled and
// foreground clouds whose indices match the input, and survives a malformed message.
#include "urban_detection/core/common/point_types.h"

#include <cmath>
#include <mutex>
#include <vector>

#include <gtest/gtest.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <boost/shared_ptr.hpp>
#include "urban_detection/ros/cloud_serialization.h"

#include "urban_detection/core/common/segment_class.h"

namespace urban_detection {
namespace {

using core::SegmentClass;
constexpr float kSensorHeight = 1.73f;

// Road 40 x 40 m every 0.2 m, a car box (x 8..12.5, y -5..-3.2, 1.5 m high: top and sides
// every 0.1 m) and a 6 m facade at y = 15.
pcl::PointCloud<pcl::PointXYZI> scene() {
  pcl::PointCloud<pcl::PointXYZI> c;
  auto add = [&c](float x, float y, float h) {
    pcl::PointXYZI p;
    p.x = x;
    p.y = y;
    p.z = h - kSensorHeight;
    p.intensity = 1.0f;
    c.push_back(p);
  };
  for (float x = -20.f; x <= 20.f; x += 0.2f)
    for (float y = -20.f; y <= 20.f; y += 0.2f)
      if (!(x > 8.f && x < 12.5f && y > -5.f && y < -3.2f)) add(x, y, 0.f);
  for (float x = 8.f; x <= 12.5f; x += 0.1f) {
    for (float y = -5.f; y <= -3.2f; y += 0.1f) add(x, y, 1.5f);
    for (float h = 0.3f; h <= 1.5f; h += 0.1f) add(x, -3.2f, h);
  }
  for (float x = -20.f; x <= 20.f; x += 0.1f)
    for (float h = 0.3f; h <= 6.f; h += 0.2f) add(x, 15.f, h);
  return c;
}

class Listener {
 public:
  void labeled(const boost::shared_ptr<const LabeledCloud>& m) {
    std::lock_guard<std::mutex> l(mutex);
    last_labeled = m;
  }
  void foreground(const boost::shared_ptr<const LabeledCloud>& m) {
    std::lock_guard<std::mutex> l(mutex);
    last_foreground = m;
  }
  std::mutex mutex;
  boost::shared_ptr<const LabeledCloud> last_labeled, last_foreground;
};

TEST(GridSegmentationNodelet, SegmentsKittiStylePointCloud2) {
  ros::NodeHandle nh;
  Listener listener;
  ros::Subscriber s1 =
      nh.subscribe("segmentation/labeled_points", 2, &Listener::labeled, &listener);
  ros::Subscriber s2 = nh.subscribe("segmentation/foreground", 2, &Listener::foreground, &listener);
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("points_in", 2);
  ros::AsyncSpinner spinner(1);
  spinner.start();

  // Lazy nodelets: CloudInput subscribes to points_in once GridSegmentation subscribes to its
  // velodyne_points, which it does once our subscribers are connected.
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(20.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.05).sleep();
  }
  ASSERT_GT(pub.getNumSubscribers(), 0u) << "CloudInput never subscribed";

  // A malformed message first (no z field): it must be dropped, not crash the manager.
  sensor_msgs::PointCloud2 bad;
  bad.header.frame_id = "velodyne";
  bad.width = 1;
  bad.height = 1;
  bad.point_step = 4;
  bad.row_step = 4;
  bad.data.assign(4, 0);
  pub.publish(bad);

  const pcl::PointCloud<pcl::PointXYZI> cloud = scene();
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(cloud, msg);
  msg.header.frame_id = "velodyne";
  msg.header.stamp = ros::Time(100.0);
  for (const auto& f : msg.fields) ASSERT_TRUE(f.name != "ring" && f.name != "time");

  boost::shared_ptr<const LabeledCloud> labeled, foreground;
  const ros::WallTime deadline2 = ros::WallTime::now() + ros::WallDuration(20.0);
  while (ros::WallTime::now() < deadline2) {
    pub.publish(msg);
    ros::WallDuration(0.3).sleep();
    std::lock_guard<std::mutex> l(listener.mutex);
    if (listener.last_labeled && listener.last_foreground) {
      labeled = listener.last_labeled;
      foreground = listener.last_foreground;
      break;
    }
  }
  ASSERT_TRUE(labeled && foreground) << "no segmentation output";
  ASSERT_EQ(labeled->size(), cloud.size());
  EXPECT_EQ(labeled->header.frame_id, "velodyne");
  EXPECT_EQ(labeled->header.stamp, 100000000u);

  std::size_t shorts = 0;
  for (std::size_t i = 0; i < labeled->size(); ++i) {
    const LabeledPoint& q = (*labeled)[i];
    ASSERT_EQ(q.index, i);
    const float h = cloud[i].z + kSensorHeight;
    const bool in_car = cloud[i].x >= 8.f && cloud[i].x <= 12.6f && cloud[i].y >= -5.f &&
                        cloud[i].y <= -3.1f && h > 0.2f;
    const SegmentClass c = static_cast<SegmentClass>(q.label);
    if (h < 0.01f) {
      EXPECT_EQ(c, SegmentClass::kGround) << i;
    }
    if (in_car) {
      EXPECT_EQ(c, SegmentClass::kShort) << i;
    }
    if (cloud[i].y > 14.9f && h > 0.2f) {
      EXPECT_EQ(c, SegmentClass::kTall) << i;
    }
    shorts += c == SegmentClass::kShort;
  }
  ASSERT_GT(shorts, 500u);
  ASSERT_EQ(foreground->size(), shorts);
  for (const LabeledPoint& q : *foreground) {
    ASSERT_LT(q.index, cloud.size());
    EXPECT_EQ(q.x, cloud[q.index].x);
    EXPECT_EQ(q.z, cloud[q.index].z);
    EXPECT_EQ(q.label, static_cast<std::uint32_t>(SegmentClass::kShort));
  }
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "grid_segmentation_nodelet_test");
  return RUN_ALL_TESTS();
}
