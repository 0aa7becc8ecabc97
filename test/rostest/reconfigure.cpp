// dynamic_reconfigure of the detector and marker nodelets (loaded into this process):
//  * a valid update takes effect from the next revolution (min_points changes the object count
//    of a scene whose clusters are known by construction);
//  * an invalid combination is rejected naming the parameters, the previous values stay in
//    force and are what the service answers;
//  * a value outside the .cfg range is clamped by dynamic_reconfigure to the range bound;
//  * out-of-range parameters at start fail onInit naming the parameter and its range.
#include "urban_detection/core/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <pcl_ros/point_cloud.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <urban_detection/DetectedObjectArray.h>
#include <visualization_msgs/MarkerArray.h>

#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "urban_detection/core/segment_class.h"

namespace urban_detection {
namespace {

bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

struct RosoutWatcher {
  std::mutex mutex;
  std::vector<rosgraph_msgs::Log> logs;
  ros::Subscriber sub;
  RosoutWatcher() { sub = ros::NodeHandle().subscribe("/rosout", 100, &RosoutWatcher::cb, this); }
  void cb(const rosgraph_msgs::Log::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    logs.push_back(*msg);
  }
  bool contains(std::uint8_t level, const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& log : logs) {
      if (log.level == level && log.msg.find(text) != std::string::npos) return true;
    }
    return false;
  }
};

// Calls <ns>/set_parameters with the given values; returns the configuration it answers with.
dynamic_reconfigure::Config setParameters(const std::string& ns,
                                          const std::vector<std::pair<std::string, int>>& ints,
                                          const std::vector<std::pair<std::string, double>>& dbls) {
  dynamic_reconfigure::Reconfigure srv;
  for (const auto& [name, value] : ints) {
    dynamic_reconfigure::IntParameter p;
    p.name = name;
    p.value = value;
    srv.request.config.ints.push_back(p);
  }
  for (const auto& [name, value] : dbls) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    srv.request.config.doubles.push_back(p);
  }
  EXPECT_TRUE(ros::service::waitForService(ns + "/set_parameters", 10000)) << ns;
  EXPECT_TRUE(ros::service::call(ns + "/set_parameters", srv)) << ns;
  return srv.response.config;
}

int intOf(const dynamic_reconfigure::Config& c, const std::string& name) {
  for (const auto& p : c.ints) {
    if (p.name == name) return p.value;
  }
  ADD_FAILURE() << "no int " << name;
  return -1;
}

double doubleOf(const dynamic_reconfigure::Config& c, const std::string& name) {
  for (const auto& p : c.doubles) {
    if (p.name == name) return p.value;
  }
  ADD_FAILURE() << "no double " << name;
  return -1;
}

// Foreground with two compact clusters 10 m apart: 12 points and 4 points (short objects).
boost::shared_ptr<LabeledCloud> twoClusters(std::uint32_t seq) {
  auto cloud = boost::make_shared<LabeledCloud>();
  auto add = [&](float cx, int n) {
    for (int i = 0; i < n; ++i) {
      LabeledPoint p;
      p.x = cx + 0.05f * static_cast<float>(i % 3);
      p.y = 5.0f + 0.05f * static_cast<float>(i / 3);
      p.z = -1.0f + 0.1f * static_cast<float>(i % 4);
      p.intensity = 1.0f;
      p.label = static_cast<std::uint32_t>(core::SegmentClass::kShort);
      p.index = static_cast<std::uint32_t>(cloud->size());
      cloud->push_back(p);
    }
  };
  add(5.0f, 12);
  add(-5.0f, 4);
  cloud->header.frame_id = "velodyne";
  cloud->header.seq = seq;
  return cloud;
}

TEST(Reconfigure, HierarchicalGridMinPointsAppliesFromTheNextRevolution) {
  ros::param::set("/rc_hg/detector/hierarchical_grid/weight/enabled", false);  // plain counts
  ros::param::set("/rc_hg/detector/hierarchical_grid/dense_min_weighted_points", 1.0);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/rc_hg/detector", "urban_detection/HierarchicalGridDetector", {}, {}));
  ros::NodeHandle nh("/rc_hg");
  std::mutex mutex;
  std::vector<std::size_t> counts;
  // Advertised before the subscriptions that make the lazy nodelet subscribe to it: a
  // subscription racing an advertise of the same process may never be connected (roscpp).
  ros::Publisher pub = nh.advertise<LabeledCloud>("segmentation/foreground", 10);
  ros::Subscriber sub = nh.subscribe<DetectedObjectArray>(
      "objects", 10, [&](const DetectedObjectArray::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(mutex);
        counts.push_back(msg->objects.size());
      });
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  auto received = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return counts.size();
  };
  pub.publish(twoClusters(1));
  ASSERT_TRUE(waitFor([&] { return received() == 1; }, 5.0));
  const dynamic_reconfigure::Config c =
      setParameters("/rc_hg/detector/hierarchical_grid", {{"min_points", 3}}, {});
  EXPECT_EQ(intOf(c, "min_points"), 3);
  pub.publish(twoClusters(2));
  ASSERT_TRUE(waitFor([&] { return received() == 2; }, 5.0));
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(counts[0], 1u) << "min_points 10 (the default): the 4-point cluster is dropped";
  EXPECT_EQ(counts[1], 2u) << "min_points 3: both clusters";
}

TEST(Reconfigure, KdTreeRejectsAnInvalidSetAndClampsOutOfRangeValues) {
  RosoutWatcher rosout;
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/rc_kd/detector", "urban_detection/KdTreeDetector", {}, {}));
  const std::string ns = "/rc_kd/detector/kdtree";
  // min_cluster_size > max_cluster_size: rejected, previous values answered and kept.
  dynamic_reconfigure::Config c =
      setParameters(ns, {{"min_cluster_size", 2000}, {"max_cluster_size", 1000}}, {});
  EXPECT_EQ(intOf(c, "min_cluster_size"), 5);
  EXPECT_EQ(intOf(c, "max_cluster_size"), 1000000);
  EXPECT_TRUE(waitFor([&] {
    return rosout.contains(rosgraph_msgs::Log::ERROR, "max_cluster_size must be >= "
                                                      "min_cluster_size");
  }, 5.0));
  // 50 m is outside [0.01, 10] m: dynamic_reconfigure answers with the bound.
  c = setParameters(ns, {}, {{"cluster_tolerance_m", 50.0}});
  EXPECT_DOUBLE_EQ(doubleOf(c, "cluster_tolerance_m"), 10.0);
  // A valid update is answered as sent.
  c = setParameters(ns, {{"min_cluster_size", 20}}, {{"cluster_tolerance_m", 0.3}});
  EXPECT_EQ(intOf(c, "min_cluster_size"), 20);
  EXPECT_DOUBLE_EQ(doubleOf(c, "cluster_tolerance_m"), 0.3);
}

TEST(Reconfigure, MarkersApplyFromTheNextMessage) {
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/rc_mk/markers", "urban_detection/ObjectMarkers", {}, {}));
  ros::NodeHandle nh("/rc_mk");
  std::mutex mutex;
  std::vector<std::size_t> sizes;
  ros::Publisher pub = nh.advertise<DetectedObjectArray>("objects", 10);
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "objects/markers", 10, [&](const visualization_msgs::MarkerArray::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(mutex);
        sizes.push_back(msg->markers.size());
      });
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  DetectedObjectArray objects;
  objects.header.frame_id = "velodyne";
  objects.objects.resize(3);
  for (std::size_t i = 0; i < 3; ++i) objects.objects[i].id = static_cast<std::uint32_t>(i + 1);
  auto count = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    return sizes.size();
  };
  pub.publish(objects);
  ASSERT_TRUE(waitFor([&] { return count() == 1; }, 5.0));
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::BoolParameter show;
  show.name = "show_ids";
  show.value = false;
  srv.request.config.bools.push_back(show);
  ASSERT_TRUE(ros::service::waitForService("/rc_mk/markers/markers/set_parameters", 10000));
  ASSERT_TRUE(ros::service::call("/rc_mk/markers/markers/set_parameters", srv));
  pub.publish(objects);
  ASSERT_TRUE(waitFor([&] { return count() == 2; }, 5.0));
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(sizes[0], 1u + 3u * 2u) << "DELETEALL + box and id per object";
  EXPECT_EQ(sizes[1], 1u + 3u) << "DELETEALL + box per object";
}

TEST(Reconfigure, OutOfRangeParametersAtStartFailNamingParameterAndRange) {
  RosoutWatcher rosout;
  ros::param::set("/bad_hg/detector/hierarchical_grid/psi_max_m", 500.0);
  ros::param::set("/bad_kd/detector/kdtree/min_cluster_size", 0);
  ros::param::set("/bad_mk/markers/markers/box_alpha", 1.5);
  ros::param::set("/bad_seg/segmentation/queue_size", 0);
  nodelet::Loader manager(false);
  manager.load("/bad_hg/detector", "urban_detection/HierarchicalGridDetector", {}, {});
  manager.load("/bad_kd/detector", "urban_detection/KdTreeDetector", {}, {});
  manager.load("/bad_mk/markers", "urban_detection/ObjectMarkers", {}, {});
  manager.load("/bad_seg/segmentation", "urban_detection/GridSegmentation", {}, {});
  EXPECT_TRUE(waitFor([&] {
    return rosout.contains(rosgraph_msgs::Log::FATAL,
                           "'/bad_hg/detector/hierarchical_grid/psi_max_m' = 500 is out of "
                           "range: accepted [0, 100] m") &&
           rosout.contains(rosgraph_msgs::Log::FATAL,
                           "'/bad_kd/detector/kdtree/min_cluster_size' = 0 is out of range") &&
           rosout.contains(rosgraph_msgs::Log::FATAL,
                           "'/bad_mk/markers/markers/box_alpha' = 1.5 is out of range: "
                           "accepted [0, 1]") &&
           rosout.contains(rosgraph_msgs::Log::FATAL,
                           "'/bad_seg/segmentation/queue_size' = 0 is out of range: "
                           "accepted [1, 100] messages");
  }, 10.0));
  // The manager (this process) keeps running; the nodelets advertise nothing.
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(ros::master::getTopics(topics));
  for (const auto& t : topics) {
    for (const char* ns : {"/bad_hg/", "/bad_kd/", "/bad_mk/", "/bad_seg/"}) {
      EXPECT_NE(t.name.rfind(ns, 0), 0u) << t.name << " advertised by a nodelet that failed";
    }
  }
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_reconfigure");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
