// dynamic_reconfigure of the detector and marker nodelets (loaded into this process):
//  * a valid update takes effect from the next revolution (min_points changes the object count
//    of a scene whose clusters are known by construction);
//  * an invalid combination is refused: the service call fails with the reason naming the
//    parameters, the previous values stay in force;
//  * a value outside the accepted range (the start-up loader's) is not clamped but refused,
//    for every reconfigurable nodelet: the whole set is refused, the call fails with one wording
//    naming the parameter and the range (also logged), the previous values stay in force and
//    are what the service answers next and ~parameter_updates publishes;
//  * `dynparam set` of a refused value exits non-zero and prints the reason;
//  * out-of-range parameters at start fail onInit naming the parameter and its range.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <dynamic_reconfigure/Config.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <urban_detection/DetectedObjectArray.h>
#include <visualization_msgs/MarkerArray.h>
#include "urban_detection/ros/cloud_serialization.h"

#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "rostest_util.h"
#include "urban_detection/core/common/segment_class.h"

namespace urban_detection {
namespace {

using rostest_util::RosoutWatcher;
using rostest_util::waitFor;

// Calls <ns>/set_parameters with the given values: true when the update was accepted, with the
// configuration the server answers in `answer`.
bool trySetParameters(const std::string& ns, const std::vector<std::pair<std::string, int>>& ints,
                      const std::vector<std::pair<std::string, double>>& dbls,
                      dynamic_reconfigure::Config* answer = nullptr) {
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
  const bool ok = ros::service::call(ns + "/set_parameters", srv);
  if (answer) *answer = srv.response.config;
  return ok;
}

// An update that must be accepted; returns the configuration the server answers with.
dynamic_reconfigure::Config setParameters(const std::string& ns,
                                          const std::vector<std::pair<std::string, int>>& ints,
                                          const std::vector<std::pair<std::string, double>>& dbls) {
  dynamic_reconfigure::Config answer;
  EXPECT_TRUE(trySetParameters(ns, ints, dbls, &answer)) << ns << ": update refused";
  return answer;
}

int intOf(const dynamic_reconfigure::Config& c, const std::string& name) {
  for (const auto& p : c.ints) {
    if (p.name == name) return p.value;
  }
  ADD_FAILURE() << "no int " << name;
  return -1;
}

// The configuration a server is using (an empty update changes nothing and answers it).
dynamic_reconfigure::Config current(const std::string& ns) {
  return setParameters(ns, {}, {});
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
      cloud->push_back(makeLabeledPoint(cx + 0.05f * static_cast<float>(i % 3),
                                        5.0f + 0.05f * static_cast<float>(i / 3),
                                        -1.0f + 0.1f * static_cast<float>(i % 4),
                                        static_cast<std::uint32_t>(core::SegmentClass::kShort),
                                        static_cast<std::uint32_t>(cloud->size()), 1.0f));
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
  ros::param::set("/rc_hg/detector/hierarchical_grid/min_weighted_points", 0.0);  // min_points only
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
  const std::string ns = "/rc_hg/detector/hierarchical_grid";
  // A set with a valid min_points and an out-of-range xi is refused as a whole.
  EXPECT_FALSE(trySetParameters(ns, {{"min_points", 3}, {"xi", 20}}, {}));
  dynamic_reconfigure::Config c = current(ns);
  EXPECT_EQ(intOf(c, "min_points"), 10);
  EXPECT_EQ(intOf(c, "xi"), 3);
  pub.publish(twoClusters(2));
  ASSERT_TRUE(waitFor([&] { return received() == 2; }, 5.0));
  c = setParameters(ns, {{"min_points", 3}}, {});
  EXPECT_EQ(intOf(c, "min_points"), 3);
  pub.publish(twoClusters(3));
  ASSERT_TRUE(waitFor([&] { return received() == 3; }, 5.0));
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(counts[0], 1u) << "min_points 10 (the default): the 4-point cluster is dropped";
  EXPECT_EQ(counts[1], 1u) << "refused set: min_points still 10";
  EXPECT_EQ(counts[2], 2u) << "min_points 3: both clusters";
}

TEST(Reconfigure, KdTreeRejectsInvalidSetsAndOutOfRangeValues) {
  RosoutWatcher rosout;
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/rc_kd/detector", "urban_detection/KdTreeDetector", {}, {}));
  const std::string ns = "/rc_kd/detector/kdtree";
  std::mutex mutex;
  std::vector<dynamic_reconfigure::Config> updates;
  ros::Subscriber sub = ros::NodeHandle().subscribe<dynamic_reconfigure::Config>(
      ns + "/parameter_updates", 10, [&](const dynamic_reconfigure::Config::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(mutex);
        updates.push_back(*msg);
      });
  const dynamic_reconfigure::Config before = current(ns);
  const double tolerance = doubleOf(before, "cluster_tolerance_m");
  const int min_size = intOf(before, "min_cluster_size");
  // min_cluster_size > max_cluster_size: refused, previous values kept.
  EXPECT_FALSE(trySetParameters(ns, {{"min_cluster_size", 2000}, {"max_cluster_size", 1000}}, {}));
  dynamic_reconfigure::Config c = current(ns);
  EXPECT_EQ(intOf(c, "min_cluster_size"), min_size);
  EXPECT_EQ(intOf(c, "max_cluster_size"), intOf(before, "max_cluster_size"));
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(rosgraph_msgs::Log::ERROR,
                               "max_cluster_size must be >= "
                               "min_cluster_size");
      },
      5.0));
  // 50 m is outside [0.01, 10] m: not clamped to 10 but refused with the valid value sent with
  // it, each time it is sent; the error names parameter and range.
  for (int i = 0; i < 2; ++i) {
    EXPECT_FALSE(trySetParameters(ns, {{"min_cluster_size", 20}}, {{"cluster_tolerance_m", 50.0}}));
    c = current(ns);
    EXPECT_DOUBLE_EQ(doubleOf(c, "cluster_tolerance_m"), tolerance);
    EXPECT_EQ(intOf(c, "min_cluster_size"), min_size);
  }
  const std::string error =
      "'/rc_kd/detector/kdtree/cluster_tolerance_m' = 50 is out of range: accepted [0.01, 10] m";
  EXPECT_TRUE(waitFor([&] { return rosout.contains(rosgraph_msgs::Log::ERROR, error); }, 5.0));
  // rqt_reconfigure follows ~parameter_updates: it must show the values kept, not the request.
  EXPECT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return !updates.empty() && doubleOf(updates.back(), "cluster_tolerance_m") == tolerance &&
               intOf(updates.back(), "min_cluster_size") == min_size;
      },
      5.0));
  // A valid update is answered as sent.
  c = setParameters(ns, {{"min_cluster_size", 20}}, {{"cluster_tolerance_m", 0.3}});
  EXPECT_EQ(intOf(c, "min_cluster_size"), 20);
  EXPECT_DOUBLE_EQ(doubleOf(c, "cluster_tolerance_m"), 0.3);
}

// Every reconfigurable nodelet: an out-of-range value is refused (not clamped), the error names
// the parameter and the accepted range in one wording, and the previous value stays.
TEST(Reconfigure, OutOfRangeValuesAreRejectedByEveryNodelet) {
  RosoutWatcher rosout;
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/rr_seg/segmentation", "urban_detection/GridSegmentation", {}, {}));
  ASSERT_TRUE(manager.load("/rr_hg/detector", "urban_detection/HierarchicalGridDetector", {}, {}));
  ASSERT_TRUE(manager.load("/rr_mk/markers", "urban_detection/ObjectMarkers", {}, {}));
  struct Case {
    std::string ns, name;
    double value;
    std::string error;  // expected in the ERROR
  };
  const std::vector<Case> cases = {
      {"/rr_seg/segmentation", "sensor_height_m", 50.0,
       "parameter '/rr_seg/segmentation/sensor_height_m' = 50 is out of range: accepted "
       "[-10, 10] m"},
      {"/rr_seg/segmentation", "hough_min_tall_fraction", -0.5,
       "parameter '/rr_seg/segmentation/hough/min_tall_fraction' = -0.5 is out of range: "
       "accepted [0, 1]"},
      {"/rr_seg/segmentation", "hough_min_mixed_wall_length_m", 600.0,
       "parameter '/rr_seg/segmentation/hough/min_mixed_wall_length_m' = 600 is out of range: "
       "accepted [0, 500] m"},
      {"/rr_hg/detector/hierarchical_grid", "psi_max_m", 500.0,
       "'/rr_hg/detector/hierarchical_grid/psi_max_m' = 500 is out of range: accepted [0, 100] m"},
      {"/rr_hg/detector/hierarchical_grid", "bridge_range_m", 5000.0,
       "'/rr_hg/detector/hierarchical_grid/bridge_range_m' = 5000 is out of range: accepted "
       "[0, 1000] m"},
      {"/rr_mk/markers/markers", "box_alpha", 1.5,
       "'/rr_mk/markers/markers/box_alpha' = 1.5 is out of range: accepted [0, 1]"},
  };
  for (const Case& k : cases) {
    const double before = doubleOf(current(k.ns), k.name);
    EXPECT_FALSE(trySetParameters(k.ns, {}, {{k.name, k.value}})) << k.ns << " " << k.name;
    EXPECT_DOUBLE_EQ(doubleOf(current(k.ns), k.name), before) << k.ns << " " << k.name;
    EXPECT_TRUE(waitFor(
        [&] {
          return rosout.contains(rosgraph_msgs::Log::ERROR, k.ns) &&
                 rosout.contains(rosgraph_msgs::Log::ERROR, k.error);
        },
        5.0))
        << k.error;
  }
  // Integers too (no clamping to an int range either).
  const int xi = intOf(current("/rr_hg/detector/hierarchical_grid"), "xi");
  EXPECT_FALSE(trySetParameters("/rr_hg/detector/hierarchical_grid", {{"xi", 0}}, {}));
  EXPECT_EQ(intOf(current("/rr_hg/detector/hierarchical_grid"), "xi"), xi);
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(rosgraph_msgs::Log::ERROR,
                               "'/rr_hg/detector/hierarchical_grid/xi' = 0 is out of range: "
                               "accepted [1, 8]");
      },
      5.0));
}

TEST(Reconfigure, ClassifierThresholdIsTunableAndOutOfRangeIsRefused) {
  RosoutWatcher rosout;
  ros::param::set("/rcl/detector/classifier/enabled", true);
  ros::param::set("/rcl/detector/classifier/model",
                  std::string(UD_SOURCE_DIR) + "/config/object_classifier.yml.gz");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/rcl/detector", "urban_detection/HierarchicalGridDetector", {}, {}));
  const std::string ns = "/rcl/detector/classifier";
  EXPECT_DOUBLE_EQ(doubleOf(current(ns), "min_object_probability"), -1.0);
  dynamic_reconfigure::Config c = setParameters(ns, {}, {{"min_object_probability", 0.8}});
  EXPECT_DOUBLE_EQ(doubleOf(c, "min_object_probability"), 0.8);
  EXPECT_FALSE(trySetParameters(ns, {}, {{"min_object_probability", 1.5}}));
  EXPECT_DOUBLE_EQ(doubleOf(current(ns), "min_object_probability"), 0.8);
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(rosgraph_msgs::Log::ERROR,
                               "'" + ns +
                                   "/min_object_probability' = 1.5 is out of range: "
                                   "accepted [-1, 1]");
      },
      5.0));
}

// Runs a shell command (stderr joined to stdout): its exit status (-1 when it did not exit) and
// its output.
std::pair<int, std::string> runCommand(const std::string& command) {
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return {-1, ""};
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

// What a user types. A refused value fails the command (non-zero exit) for both stages that
// validate updates, segmentation and detector (detector parameters and classifier), and the
// service error carries the reason in the one wording, which `rosservice call` prints.
// dynparam itself (dynamic_reconfigure 1.7) turns any failed call into a traceback ending in
// "service call failed" without the server's text: only its exit status is checked.
TEST(Reconfigure, CommandLineToolsFailOnARefusedValueAndShowTheReason) {
  ros::param::set("/dp_hg/detector/classifier/enabled", true);
  ros::param::set("/dp_hg/detector/classifier/model",
                  std::string(UD_SOURCE_DIR) + "/config/object_classifier.yml.gz");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/dp_seg/segmentation", "urban_detection/GridSegmentation", {}, {}));
  ASSERT_TRUE(manager.load("/dp_hg/detector", "urban_detection/HierarchicalGridDetector", {}, {}));
  struct Case {
    std::string ns, name, value, error;
  };
  const std::vector<Case> cases = {
      {"/dp_seg/segmentation", "sensor_height_m", "50",
       "/dp_seg/segmentation: dynamic_reconfigure update refused, previous values kept: "
       "parameter '/dp_seg/segmentation/sensor_height_m' = 50 is out of range: accepted "
       "[-10, 10] m"},
      {"/dp_hg/detector/hierarchical_grid", "psi_max_m", "500",
       "/dp_hg/detector/hierarchical_grid: dynamic_reconfigure update refused, previous values "
       "kept: parameter '/dp_hg/detector/hierarchical_grid/psi_max_m' = 500 is out of range: "
       "accepted [0, 100] m"},
      {"/dp_hg/detector/classifier", "min_object_probability", "1.5",
       "/dp_hg/detector/classifier: dynamic_reconfigure update refused, previous values kept: "
       "parameter '/dp_hg/detector/classifier/min_object_probability' = 1.5 is out of range: "
       "accepted [-1, 1]"},
  };
  for (const Case& k : cases) {
    ASSERT_TRUE(ros::service::waitForService(k.ns + "/set_parameters", 10000)) << k.ns;
    const double before = doubleOf(current(k.ns), k.name);
    const auto [dynparam_status, dynparam_output] =
        runCommand("timeout 60 rosrun dynamic_reconfigure dynparam set " + k.ns + " " + k.name +
                   " " + k.value);
    EXPECT_NE(dynparam_status, 0) << "dynparam set " << k.ns << " " << k.name << " " << k.value
                                  << ":\n"
                                  << dynparam_output;
    EXPECT_NE(dynparam_output.find("service call failed"), std::string::npos) << dynparam_output;
    const auto [service_status, service_output] =
        runCommand("timeout 60 rosservice call " + k.ns +
                   "/set_parameters \"{config: {doubles: [{name: " + k.name +
                   ", value: " + k.value + "}]}}\"");
    EXPECT_NE(service_status, 0) << service_output;
    EXPECT_NE(service_output.find(k.error), std::string::npos) << "rosservice call output:\n"
                                                               << service_output << "\nexpected:\n"
                                                               << k.error;
    EXPECT_DOUBLE_EQ(doubleOf(current(k.ns), k.name), before) << k.ns << " " << k.name;
  }
  // An accepted value: exit 0, in force.
  const auto [status, output] = runCommand(
      "timeout 60 rosrun dynamic_reconfigure dynparam set /dp_seg/segmentation "
      "sensor_height_m 1.8");
  EXPECT_EQ(status, 0) << output;
  EXPECT_DOUBLE_EQ(doubleOf(current("/dp_seg/segmentation"), "sensor_height_m"), 1.8);
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
  EXPECT_EQ(sizes[0], 1u + 3u * 2u + 4u) << "DELETEALL + box and id per object + legend";
  EXPECT_EQ(sizes[1], 1u + 3u + 4u) << "DELETEALL + box per object + legend";
}

TEST(Reconfigure, OutOfRangeParametersAtStartFailNamingParameterAndRange) {
  RosoutWatcher rosout;
  ros::param::set("/bad_hg/detector/hierarchical_grid/psi_max_m", 500.0);
  ros::param::set("/bad_kd/detector/kdtree/min_cluster_size", 0);
  ros::param::set("/bad_mk/markers/markers/box_alpha", 1.5);
  ros::param::set("/bad_seg/segmentation/queue_size", 0);
  // The nodelets' own settings come from their tables too (nodelet_params.h): range and type.
  ros::param::set("/bad_ex/export/queue_size", 0);
  ros::param::set("/bad_idle/detector/thread_idle", std::string("yes"));
  nodelet::Loader manager(false);
  manager.load("/bad_hg/detector", "urban_detection/HierarchicalGridDetector", {}, {});
  manager.load("/bad_kd/detector", "urban_detection/KdTreeDetector", {}, {});
  manager.load("/bad_mk/markers", "urban_detection/ObjectMarkers", {}, {});
  manager.load("/bad_seg/segmentation", "urban_detection/GridSegmentation", {}, {});
  manager.load("/bad_ex/export", "urban_detection/ObjectExport", {}, {});
  manager.load("/bad_idle/detector", "urban_detection/HierarchicalGridDetector", {}, {});
  EXPECT_TRUE(waitFor(
      [&] {
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
                               "accepted [1, 100] messages") &&
               rosout.contains(rosgraph_msgs::Log::FATAL,
                               "'/bad_ex/export/queue_size' = 0 is out of range: "
                               "accepted [1, 100] messages") &&
               rosout.contains(rosgraph_msgs::Log::FATAL,
                               "parameter '/bad_idle/detector/thread_idle' must be");
      },
      10.0));
  // The manager (this process) keeps running; the nodelets advertise nothing.
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(ros::master::getTopics(topics));
  for (const auto& t : topics) {
    for (const char* ns :
         {"/bad_hg/", "/bad_kd/", "/bad_mk/", "/bad_seg/", "/bad_ex/", "/bad_idle/"}) {
      EXPECT_NE(t.name.rfind(ns, 0), 0u) << t.name << " advertised by a nodelet that failed";
    }
  }
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_reconfigure");
}
