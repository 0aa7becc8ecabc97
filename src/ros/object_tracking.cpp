#include "urban_detection/ros/object_tracking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "urban_detection/ros/object_conversions.h"
#include "urban_detection/ros/object_markers.h"

namespace urban_detection {
namespace ros_conv {

namespace {

// The class names the detectors publish are core::toString() of the categories.
core::ObjectCategory categoryOf(const std::string& label) {
  for (int c = 0; c <= 4; ++c) {
    const auto category = static_cast<core::ObjectCategory>(c);
    if (label == core::toString(category)) return category;
  }
  return core::ObjectCategory::kUnknown;
}

}  // namespace

void fromMsg(const DetectedObject& msg, core::DetectedObject* o) {
  o->id = msg.id;
  const auto& p = msg.obb_pose.position;
  o->obb_center =
      Eigen::Vector3f(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z));
  const auto& q = msg.obb_pose.orientation;
  const double qn = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
  o->obb_yaw_rad = qn > 1e-12 ? static_cast<float>(std::atan2(2.0 * (q.w * q.z + q.x * q.y),
                                                              1.0 - 2.0 * (q.y * q.y + q.z * q.z)))
                              : std::nanf("");
  o->obb_size = Eigen::Vector3f(static_cast<float>(msg.obb_dimensions.x),
                                static_cast<float>(msg.obb_dimensions.y),
                                static_cast<float>(msg.obb_dimensions.z));
  o->centroid =
      Eigen::Vector3f(static_cast<float>(msg.centroid.x), static_cast<float>(msg.centroid.y),
                      static_cast<float>(msg.centroid.z));
  o->category = categoryOf(msg.class_label);
  o->class_confidence = msg.class_confidence;
}

void toMsg(const core::Track& t, TrackedObject* msg) {
  msg->id = t.id;
  msg->state = static_cast<std::uint8_t>(t.state);
  msg->age = t.age;
  msg->hits = t.hits;
  msg->misses = t.misses;
  msg->detection_id = -1;
  msg->pose = yawPose(t.center, t.yaw_rad);
  msg->dimensions = toVector3(t.size);
  msg->velocity.x = t.velocity.x();
  msg->velocity.y = t.velocity.y();
  msg->velocity.z = 0.0;
  for (int k = 0; k < 4; ++k) msg->velocity_covariance[k] = t.velocity_covariance(k / 2, k % 2);
  msg->class_label = core::toString(t.category);
  msg->class_confidence = t.class_confidence;
}

void buildTrackMarkers(const TrackedObjectArray& tracks, const std::vector<std::uint32_t>& deleted,
                       const TrackMarkerParams& params, double moving_speed_mps,
                       std::set<std::uint32_t>* arrows, visualization_msgs::MarkerArray* markers) {
  markers->markers.clear();
  markers->markers.reserve(3 * tracks.objects.size() + 3 * deleted.size());
  visualization_msgs::Marker m;
  m.header = tracks.header;
  m.action = visualization_msgs::Marker::ADD;
  for (const TrackedObject& t : tracks.objects) {
    const bool tentative = t.state == TrackedObject::TENTATIVE;
    if (tentative && !params.show_tentative) continue;
    const int id = static_cast<int>(t.id);
    // The class colour of the legend when the track has a class, else the id's.
    const bool classified = !t.class_label.empty() && t.class_label != "unknown";
    std_msgs::ColorRGBA colour = classified ? colourForClass(t.class_label, params.box_alpha)
                                            : colourForId(t.id, params.box_alpha);
    if (tentative) colour.r = colour.g = colour.b = 0.6f;
    if (t.state == TrackedObject::LOST) colour.a *= 0.5f;
    m.ns = "tracks";
    m.id = id;
    m.type = visualization_msgs::Marker::CUBE;
    m.pose = t.pose;
    m.scale.x = std::max(t.dimensions.x, 0.05);
    m.scale.y = std::max(t.dimensions.y, 0.05);
    m.scale.z = std::max(t.dimensions.z, 0.05);
    m.color = colour;
    m.points.clear();
    m.text.clear();
    markers->markers.push_back(m);

    const double speed = std::hypot(t.velocity.x, t.velocity.y);
    // Relative velocities (no odometry) say nothing about what moves over ground: no arrows.
    const bool moving = !tracks.velocities_relative && speed > moving_speed_mps;
    m.ns = "track_velocities";
    m.type = visualization_msgs::Marker::ARROW;
    if (moving) {
      m.pose = geometry_msgs::Pose();
      m.pose.orientation.w = 1.0;
      geometry_msgs::Point a = t.pose.position, b = t.pose.position;
      b.x += t.velocity.x * params.arrow_time_s;
      b.y += t.velocity.y * params.arrow_time_s;
      m.points = {a, b};
      m.scale.x = 0.15;  // shaft diameter
      m.scale.y = 0.35;  // head diameter
      m.scale.z = 0.4;   // head length
      m.color = colour;
      m.color.a = 1.0f;
      markers->markers.push_back(m);
      arrows->insert(t.id);
    } else if (arrows->erase(t.id)) {
      visualization_msgs::Marker del;
      del.header = tracks.header;
      del.ns = m.ns;
      del.id = id;
      del.action = visualization_msgs::Marker::DELETE;
      markers->markers.push_back(del);
    }
    m.points.clear();

    m.ns = "track_labels";
    m.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    m.pose = geometry_msgs::Pose();
    m.pose.position = t.pose.position;
    m.pose.position.z += 0.5 * std::max(t.dimensions.z, 0.05) + 0.6 * params.text_size_m;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = 0.0;
    m.scale.z = params.text_size_m;
    m.color.r = m.color.g = m.color.b = m.color.a = 1.0f;
    char buf[96];
    if (tracks.velocities_relative) {
      std::snprintf(buf, sizeof buf, "%u %s (%.1f m/s rel.)", t.id, t.class_label.c_str(), speed);
    } else if (moving) {
      std::snprintf(buf, sizeof buf, "%u %s %.1f m/s", t.id, t.class_label.c_str(), speed);
    } else {
      std::snprintf(buf, sizeof buf, "%u %s", t.id, t.class_label.c_str());
    }
    m.text = buf;
    markers->markers.push_back(m);
    m.text.clear();
  }
  for (const std::uint32_t id : deleted) {
    arrows->erase(id);
    for (const char* ns : {"tracks", "track_velocities", "track_labels"}) {
      visualization_msgs::Marker del;
      del.header = tracks.header;
      del.ns = ns;
      del.id = static_cast<int>(id);
      del.action = visualization_msgs::Marker::DELETE;
      markers->markers.push_back(del);
    }
  }
}

std::string validate(const TrackMarkerParams& params) {
  return core::checkFieldRanges(params);
}

}  // namespace ros_conv
}  // namespace urban_detection
