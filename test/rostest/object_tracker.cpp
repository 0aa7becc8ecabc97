// ObjectTracker nodelet, loaded into this process, fed DetectedObjectArray
// revolutions:
//  * ids stay the same over revolutions, a moving object gets its velocity, the markers carry
//    box, arrow and "id class speed" per confirmed track;
//  * a track whose object disappears gets DELETE markers once it dies (death_misses);
//  * with tf odom -> velodyne of a moving sensor, a parked object is still in odom; the first
//    revolutions, older than any transform the listener got, are skipped, not tracked in the
//    sensor frame;
//  * without that transform the tracks stay in the sensor frame with one warning, velocities
//    marked relative, no velocity arrows; stamps going back reset the tracks with one INFO;
//  * NaN boxes are skipped with an error and nothing crashes; empty arrays are fine;
//  * a reconfigure with an out-of-range gate is refused; a bad start parameter idles the
//    nodelet with one FATAL naming it.
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <tf2_ros/transform_broadcaster.h>
#include <urban_detection/DetectedObjectArray.h>
#include <urban_detection/TrackedObjectArray.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "rostest_util.h"

namespace urban_detection {
namespace {

using rostest_util::RosoutWatcher;
using rostest_util::waitFor;

DetectedObject object(std::uint32_t id, double x, double y, const std::string& label) {
  DetectedObject o;
  o.id = id;
  o.obb_pose.position.x = x;
  o.obb_pose.position.y = y;
  o.obb_pose.position.z = -0.9;
  o.obb_pose.orientation.w = 1.0;
  o.obb_dimensions.x = 4.2;
  o.obb_dimensions.y = 1.8;
  o.obb_dimensions.z = 1.5;
  o.centroid = o.obb_pose.position;
  o.class_label = label;
  o.class_confidence = 0.9f;
  return o;
}

struct Harness {
  explicit Harness(const std::string& ns) : nh(ns) {
    pub = nh.advertise<DetectedObjectArray>("objects", 20);
    tracks_sub = nh.subscribe<TrackedObjectArray>("objects/tracked", 50,
                                                  [this](const TrackedObjectArray::ConstPtr& m) {
                                                    std::lock_guard<std::mutex> lock(mutex);
                                                    tracks.push_back(*m);
                                                  });
    markers_sub = nh.subscribe<visualization_msgs::MarkerArray>(
        "objects/tracked/markers", 50, [this](const visualization_msgs::MarkerArray::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex);
          markers.push_back(*m);
        });
  }
  std::size_t received() {
    std::lock_guard<std::mutex> lock(mutex);
    return std::min(tracks.size(), markers.size());
  }
  // Publishes one revolution and waits for both outputs of it.
  bool send(const std::vector<DetectedObject>& objects, double stamp_s, std::uint32_t seq,
            double timeout_s = 5.0) {
    auto msg = boost::make_shared<DetectedObjectArray>();
    msg->header.frame_id = "velodyne";
    msg->header.stamp = ros::Time(stamp_s);
    msg->header.seq = seq;
    msg->detector = "hierarchical_grid";
    msg->objects = objects;
    const std::size_t before = received();
    pub.publish(boost::shared_ptr<const DetectedObjectArray>(msg));
    return waitFor([&] { return received() > before; }, timeout_s);
  }
  TrackedObjectArray lastTracks() {
    std::lock_guard<std::mutex> lock(mutex);
    return tracks.back();
  }
  visualization_msgs::MarkerArray lastMarkers() {
    std::lock_guard<std::mutex> lock(mutex);
    return markers.back();
  }

  ros::NodeHandle nh;
  ros::Publisher pub;
  ros::Subscriber tracks_sub, markers_sub;
  std::mutex mutex;
  std::vector<TrackedObjectArray> tracks;
  std::vector<visualization_msgs::MarkerArray> markers;
};

const TrackedObject* find(const TrackedObjectArray& a, std::uint32_t id) {
  for (const auto& t : a.objects) {
    if (t.id == id) return &t;
  }
  return nullptr;
}

TEST(ObjectTracker, IdsStableAndDeleteMarkersAfterDeath) {
  ros::param::set("/ot/tracker/fixed_frame", "velodyne");  // the objects' frame is fixed
  ros::param::set("/ot/tracker/tracker/birth_hits", 2);
  ros::param::set("/ot/tracker/tracker/death_misses", 3);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ot/tracker", "urban_detection/ObjectTracker", {}, {}));
  Harness h("/ot");
  ASSERT_TRUE(waitFor([&] { return h.pub.getNumSubscribers() == 1; }, 10.0));
  // A car driving at 8 m/s along x and a parked one, 10 revolutions at 10 Hz.
  std::uint32_t seq = 1;
  double t = 1000.0;
  std::uint32_t moving_id = 0, parked_id = 0;
  for (int k = 0; k < 10; ++k, t += 0.1) {
    // Detection ids restart each revolution and their order changes: the track ids must not.
    std::vector<DetectedObject> objs = {object(1, -10.0 + 0.8 * k, 3.0, "vehicle"),
                                        object(2, 12.0, -4.0, "vehicle")};
    if (k % 2) std::swap(objs[0], objs[1]);
    ASSERT_TRUE(h.send(objs, t, seq++)) << "revolution " << k;
    const TrackedObjectArray a = h.lastTracks();
    EXPECT_EQ(a.header.frame_id, "velodyne");
    EXPECT_FALSE(a.velocities_relative);
    ASSERT_EQ(a.objects.size(), 2u);
    for (const auto& o : a.objects) {
      if (o.pose.position.y > 0) {
        if (!moving_id) moving_id = o.id;
        EXPECT_EQ(o.id, moving_id) << "revolution " << k;
      } else {
        if (!parked_id) parked_id = o.id;
        EXPECT_EQ(o.id, parked_id) << "revolution " << k;
      }
    }
  }
  ASSERT_NE(moving_id, parked_id);
  TrackedObjectArray a = h.lastTracks();
  const TrackedObject* moving = find(a, moving_id);
  const TrackedObject* parked = find(a, parked_id);
  ASSERT_TRUE(moving && parked);
  EXPECT_EQ(moving->state, TrackedObject::CONFIRMED);
  EXPECT_NEAR(moving->velocity.x, 8.0, 1.0);
  EXPECT_LT(std::hypot(parked->velocity.x, parked->velocity.y), 0.3);
  EXPECT_EQ(moving->class_label, "vehicle");
  EXPECT_EQ(moving->hits, 10u);
  EXPECT_GE(moving->detection_id, 1);
  // Markers: box, arrow and text for the moving car (its colour stable), box + text for the
  // parked one (arrow deleted: not moving).
  visualization_msgs::MarkerArray m = h.lastMarkers();
  int boxes = 0, arrows = 0, texts = 0;
  for (const auto& mk : m.markers) {
    if (mk.action != visualization_msgs::Marker::ADD) continue;
    boxes += mk.ns == "tracks";
    arrows += mk.ns == "track_velocities";
    if (mk.ns == "track_labels") {
      ++texts;
      if (mk.id == static_cast<int>(moving_id)) {
        EXPECT_EQ(mk.text.rfind(std::to_string(moving_id) + " vehicle ", 0), 0u) << mk.text;
        EXPECT_NE(mk.text.find("m/s"), std::string::npos) << mk.text;
      }
    }
  }
  EXPECT_EQ(boxes, 2);
  EXPECT_EQ(arrows, 1);
  EXPECT_EQ(texts, 2);

  // The moving car disappears: lost for 2 revolutions, deleted at the 3rd miss with DELETE
  // markers in every namespace; the parked car keeps its id throughout.
  for (int k = 0; k < 3; ++k, t += 0.1) {
    ASSERT_TRUE(h.send({object(1, 12.0, -4.0, "vehicle")}, t, seq++));
    a = h.lastTracks();
    ASSERT_TRUE(find(a, parked_id));
    m = h.lastMarkers();
    std::set<std::string> deleted_ns;
    for (const auto& mk : m.markers) {
      if (mk.action == visualization_msgs::Marker::DELETE && mk.id == static_cast<int>(moving_id)) {
        deleted_ns.insert(mk.ns);
      }
    }
    if (k < 2) {
      ASSERT_TRUE(find(a, moving_id)) << "miss " << k + 1;
      EXPECT_EQ(find(a, moving_id)->state, TrackedObject::LOST);
      EXPECT_EQ(deleted_ns.count("tracks"), 0u);
    } else {
      EXPECT_FALSE(find(a, moving_id));
      EXPECT_EQ(deleted_ns, (std::set<std::string>{"tracks", "track_velocities", "track_labels"}));
    }
  }

  // Hostile input: a NaN box is skipped with a throttled error, an empty array is fine.
  RosoutWatcher rosout;
  DetectedObject bad = object(3, 0, 0, "vehicle");
  bad.obb_pose.position.x = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(h.send({bad, object(1, 12.0, -4.0, "vehicle")}, t += 0.1, seq++));
  EXPECT_TRUE(find(h.lastTracks(), parked_id));
  EXPECT_TRUE(
      waitFor([&] { return rosout.contains(rosgraph_msgs::Log::ERROR, "non-finite"); }, 5.0));
  ASSERT_TRUE(h.send({}, t += 0.1, seq++));

  // A gate out of range is refused as a whole, naming the parameter.
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::DoubleParameter p;
  p.name = "gate_distance_m";
  p.value = 500.0;
  srv.request.config.doubles.push_back(p);
  ASSERT_TRUE(ros::service::waitForService("/ot/tracker/tracker/set_parameters", 10000));
  EXPECT_FALSE(ros::service::call("/ot/tracker/tracker/set_parameters", srv));
  p.value = 3.0;
  srv.request.config.doubles = {p};
  EXPECT_TRUE(ros::service::call("/ot/tracker/tracker/set_parameters", srv));
}

TEST(ObjectTracker, ParkedObjectStillInOdomWhileTheSensorDrives) {
  ros::param::set("/ot_tf/tracker/fixed_frame", "odom");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ot_tf/tracker", "urban_detection/ObjectTracker", {}, {}));
  Harness h("/ot_tf");
  ASSERT_TRUE(waitFor([&] { return h.pub.getNumSubscribers() == 1; }, 10.0));
  tf2_ros::TransformBroadcaster tf;
  const double parked_x = 30.0, parked_y = 4.0;
  std::uint32_t id = 0;
  double t = 2000.0;
  for (int k = 0; k < 12; ++k, t += 0.1) {
    const double sensor_x = 10.0 * 0.1 * k;  // 10 m/s along odom x
    geometry_msgs::TransformStamped tr;
    tr.header.stamp = ros::Time(t);
    tr.header.frame_id = "odom";
    tr.child_frame_id = "velodyne";
    tr.transform.translation.x = sensor_x;
    tr.transform.rotation.w = 1.0;
    tf.sendTransform(tr);
    ros::WallDuration(0.02).sleep();  // let the listener have it before the objects
    ASSERT_TRUE(h.send({object(1, parked_x - sensor_x, parked_y, "vehicle")}, t, k + 1));
    const TrackedObjectArray a = h.lastTracks();
    if (k == 0) continue;  // the first may come before the listener has any transform
    EXPECT_EQ(a.header.frame_id, "odom") << "revolution " << k;
    ASSERT_EQ(a.objects.size(), 1u);
    if (!id) id = a.objects[0].id;
    EXPECT_EQ(a.objects[0].id, id);
    EXPECT_NEAR(a.objects[0].pose.position.x, parked_x, 0.05);
  }
  const TrackedObject& o = h.lastTracks().objects.at(0);
  EXPECT_LT(std::hypot(o.velocity.x, o.velocity.y), 0.1);
}

TEST(ObjectTracker, FirstRevolutionsBeforeTheirTransformAreSkippedNotTrackedInTheSensorFrame) {
  RosoutWatcher rosout;
  ros::param::set("/ot_late/tracker/fixed_frame", "odom");
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ot_late/tracker", "urban_detection/ObjectTracker", {}, {}));
  Harness h("/ot_late");
  ASSERT_TRUE(waitFor([&] { return h.pub.getNumSubscribers() == 1; }, 10.0));
  tf2_ros::TransformBroadcaster tf;
  auto send_tf = [&](double t) {
    geometry_msgs::TransformStamped tr;
    tr.header.stamp = ros::Time(t);
    tr.header.frame_id = "odom";
    tr.child_frame_id = "velodyne";
    tr.transform.translation.x = 10.0 * (t - 4000.0);
    tr.transform.rotation.w = 1.0;
    tf.sendTransform(tr);
  };
  // The listener joined after the first two revolutions' transforms went out (a bag starting,
  // a manager loading): tf knows odom, but nothing as early as those revolutions.
  send_tf(4000.2);
  ASSERT_TRUE(waitFor([&] { return h.pub.getNumSubscribers() == 1; }, 1.0));
  ros::WallDuration(0.3).sleep();
  std::uint32_t seq = 1;
  for (int k = 0; k < 8; ++k) {
    const double t = 4000.0 + 0.1 * k;
    if (k > 2) send_tf(t);
    ros::WallDuration(0.02).sleep();
    const bool answered =
        h.send({object(1, 30.0 - 1.0 * k, 4.0, "vehicle")}, t, seq++, k < 2 ? 2.0 : 5.0);
    EXPECT_EQ(answered, k >= 2) << "revolution " << k;  // 0 and 1 wait for tf, then skip
    if (answered) EXPECT_EQ(h.lastTracks().header.frame_id, "odom") << "revolution " << k;
  }
  ros::WallDuration(0.5).sleep();  // rosout is asynchronous
  EXPECT_EQ(rosout.count(rosgraph_msgs::Log::WARN, "tracking in the sensor frame"), 0);
  EXPECT_EQ(rosout.count(rosgraph_msgs::Log::INFO, "tracks restarted"), 0);
}

TEST(ObjectTracker, WithoutOdometryRelativeVelocitiesAndLoopingStampsResetOnce) {
  RosoutWatcher rosout;
  ros::param::set("/ot_rel/tracker/fixed_frame", "odom_nobody_publishes");
  ros::param::set("/ot_rel/tracker/tracker/birth_hits", 2);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ot_rel/tracker", "urban_detection/ObjectTracker", {}, {}));
  Harness h("/ot_rel");
  ASSERT_TRUE(waitFor([&] { return h.pub.getNumSubscribers() == 1; }, 10.0));
  // The sensor drives at 8 m/s past a parked car; two passes of the same 1 s (a looping bag).
  std::uint32_t seq = 1;
  std::set<std::uint32_t> ids_first, ids_second;
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 0; k < 10; ++k) {
      ASSERT_TRUE(h.send({object(1, 20.0 - 0.8 * k, 4.0, "vehicle")}, 3000.0 + 0.1 * k, seq++));
      const TrackedObjectArray a = h.lastTracks();
      EXPECT_EQ(a.header.frame_id, "velodyne");
      EXPECT_TRUE(a.velocities_relative);
      for (const auto& o : a.objects) (pass ? ids_second : ids_first).insert(o.id);
    }
    const TrackedObjectArray a = h.lastTracks();
    ASSERT_EQ(a.objects.size(), 1u);
    EXPECT_NEAR(a.objects[0].velocity.x, -8.0, 1.0);  // the sensor's own speed, relative
    int arrows = 0, relative_labels = 0;
    for (const auto& mk : h.lastMarkers().markers) {
      if (mk.action != visualization_msgs::Marker::ADD) continue;
      arrows += mk.ns == "track_velocities";
      relative_labels += mk.ns == "track_labels" && mk.text.find("m/s rel.") != std::string::npos;
    }
    EXPECT_EQ(arrows, 0) << "a relative velocity drawn as motion";
    EXPECT_EQ(relative_labels, 1);
  }
  // The second pass started over: new ids, none of the first pass's.
  ASSERT_EQ(ids_first.size(), 1u);
  ASSERT_EQ(ids_second.size(), 1u);
  EXPECT_NE(*ids_first.begin(), *ids_second.begin());
  ros::WallDuration(0.5).sleep();  // rosout is asynchronous
  EXPECT_EQ(rosout.count(rosgraph_msgs::Log::WARN, "tracking in the sensor frame"), 1);
  EXPECT_EQ(rosout.count(rosgraph_msgs::Log::INFO, "stamp went back"), 1);
  EXPECT_EQ(rosout.count(rosgraph_msgs::Log::WARN, "restarted"), 0);
  EXPECT_EQ(rosout.count(rosgraph_msgs::Log::INFO, "tracks restarted"), 0);
}

TEST(ObjectTracker, BadStartParameterIdlesWithOneFatal) {
  RosoutWatcher rosout;
  ros::param::set("/ot_bad/tracker/tracker/birth_hits", 0);
  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ot_bad/tracker", "urban_detection/ObjectTracker", {}, {}));
  EXPECT_TRUE(waitFor(
      [&] {
        return rosout.contains(
            rosgraph_msgs::Log::FATAL,
            "parameter '/ot_bad/tracker/tracker/birth_hits' = 0 is out of range");
      },
      10.0));
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_object_tracker");
}
