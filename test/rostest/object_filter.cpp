// The object filter as the detector nodelets apply it (nodelets loaded into this process):
// rejected (vegetation) objects are not published on `objects` nor in `objects/points`, kept
// ones are; `object_filter/enabled: false` publishes everything; a bad parameter fails onInit.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <urban_detection/DetectedObjectArray.h>
#include "urban_detection/ros/cloud_serialization.h"

#include <chrono>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "../core/synthetic_scans.h"
#include "rostest_util.h"

namespace urban_detection {
namespace {

using rostest_util::waitFor;

// A car-like box and a porous bush 10 m apart; `car` and `bush` get their point indices.
boost::shared_ptr<LabeledCloud> carAndBush(std::set<std::uint32_t>* car,
                                           std::set<std::uint32_t>* bush) {
  auto cloud = boost::make_shared<LabeledCloud>();
  std::mt19937 rng(5);
  const core::DetectedObject c =
      test::scan(test::box({8.0, 1.2, -1.6}, {12.2, 3.0, -0.3}), 0, 25, -14, 0, cloud.get());
  const core::DetectedObject b =
      test::scan(test::bush({9.0, -8.0, -1.0}, 1.0, &rng), -50, -30, -14, 2, cloud.get());
  car->insert(c.indices.begin(), c.indices.end());
  bush->insert(b.indices.begin(), b.indices.end());
  cloud->header.frame_id = "velodyne";
  cloud->header.seq = 1;
  return cloud;
}

struct Outputs {
  std::mutex mutex;
  std::vector<DetectedObjectArray> objects;
  std::vector<LabeledCloud> points;
};

// Loads `type` as `ns`/detector, publishes the scene once, collects both outputs.
void runDetector(const std::string& ns, const std::string& type, nodelet::Loader* manager,
                 Outputs* out) {
  ASSERT_TRUE(manager->load(ns + "/detector", type, {}, {}));
  ros::NodeHandle nh(ns);
  ros::Publisher pub = nh.advertise<LabeledCloud>("segmentation/foreground", 10);
  ros::Subscriber s1 = nh.subscribe<DetectedObjectArray>(
      "objects", 10, [out](const DetectedObjectArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(out->mutex);
        out->objects.push_back(*m);
      });
  ros::Subscriber s2 = nh.subscribe<LabeledCloud>(
      "objects/points", 10, [out](const boost::shared_ptr<const LabeledCloud>& m) {
        std::lock_guard<std::mutex> lock(out->mutex);
        out->points.push_back(*m);
      });
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() == 1; }, 10.0));
  std::set<std::uint32_t> car, bush;
  pub.publish(carAndBush(&car, &bush));
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(out->mutex);
        return !out->objects.empty() && !out->points.empty();
      },
      10.0));
}

std::set<std::uint32_t> objectIndices(const DetectedObject& o) {
  return {o.indices.begin(), o.indices.end()};
}

TEST(ObjectFilterNodelets, VegetationIsNotPublishedByEitherDetector) {
  std::set<std::uint32_t> car, bush;
  carAndBush(&car, &bush);
  for (const std::string& type : {std::string("urban_detection/HierarchicalGridDetector"),
                                  std::string("urban_detection/KdTreeDetector")}) {
    SCOPED_TRACE(type);
    const std::string ns = type.find("Kd") != std::string::npos ? "/of_kd" : "/of_hg";
    ros::param::set(ns + "/detector/object_filter/enabled", true);  // off by default
    nodelet::Loader manager(false);
    Outputs out;
    runDetector(ns, type, &manager, &out);
    std::lock_guard<std::mutex> lock(out.mutex);
    ASSERT_EQ(out.objects[0].objects.size(), 1u) << "the bush is rejected, the car kept";
    EXPECT_EQ(objectIndices(out.objects[0].objects[0]), car);
    EXPECT_EQ(out.objects[0].objects[0].id, 1u);
    for (const auto& p : out.points[0]) {
      EXPECT_EQ(bush.count(p.index), 0u) << "bush point " << p.index << " published";
      EXPECT_EQ(p.label, 1u);
    }
    EXPECT_EQ(out.points[0].size(), car.size());
  }
}

TEST(ObjectFilterNodelets, DisabledPublishesEveryObject) {
  ros::param::set("/of_off/detector/object_filter/enabled", false);
  nodelet::Loader manager(false);
  Outputs out;
  runDetector("/of_off", "urban_detection/KdTreeDetector", &manager, &out);
  std::lock_guard<std::mutex> lock(out.mutex);
  EXPECT_EQ(out.objects[0].objects.size(), 2u);
}

TEST(ObjectFilterNodelets, BadParameterFailsInitNamingIt) {
  std::mutex mutex;
  bool seen = false;
  ros::Subscriber sub = ros::NodeHandle().subscribe<rosgraph_msgs::Log>(
      "/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        if (m->level == rosgraph_msgs::Log::FATAL &&
            m->msg.find("'/of_bad/detector/object_filter/max_jump_fraction' = 2 is out of "
                        "range") != std::string::npos) {
          seen = true;
        }
      });
  ros::param::set("/of_bad/detector/object_filter/max_jump_fraction", 2.0);
  nodelet::Loader manager(false);
  manager.load("/of_bad/detector", "urban_detection/HierarchicalGridDetector", {}, {});
  EXPECT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return seen;
      },
      10.0));
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_object_filter");
}
