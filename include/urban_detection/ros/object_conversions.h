/// \file object_conversions.h
/// Detected objects: core -> urban_detection/DetectedObjectArray, and the per-object point
/// cloud of `objects/points`. No ROS master needed.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include <cmath>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Vector3.h>
#include <std_msgs/Header.h>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace ros_conv {

/// Label of objects no classifier has looked at.
constexpr const char* kUnknownClass = "unknown";

/// A box pose: centre `c` (any Eigen 3-vector) rotated about z by `yaw_rad`,
/// q = (0, 0, sin(yaw/2), cos(yaw/2)).
template <class Vec3>
geometry_msgs::Pose yawPose(const Vec3& c, double yaw_rad) {
  geometry_msgs::Pose pose;
  pose.position.x = c.x();
  pose.position.y = c.y();
  pose.position.z = c.z();
  pose.orientation.x = pose.orientation.y = 0.0;
  pose.orientation.z = std::sin(0.5 * yaw_rad);
  pose.orientation.w = std::cos(0.5 * yaw_rad);
  return pose;
}

/// An Eigen 3-vector as a message vector.
template <class Vec3>
geometry_msgs::Vector3 toVector3(const Vec3& v) {
  geometry_msgs::Vector3 out;
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
  return out;
}

/// Fills `msg` from `object` (class_label "unknown", confidence 0).
void toMsg(const core::DetectedObject& object, DetectedObject* msg);

/// Fills `msg` with `objects`; `header` is the input cloud's (stamp and frame).
void toMsg(const std::vector<core::DetectedObject>& objects, const std::string& detector,
           const std_msgs::Header& header, DetectedObjectArray* msg);

/// Builds `objects/points`: the foreground points that belong to an object, label = object id,
/// index kept, header copied from `foreground`. `scratch` maps index -> object id and is reused
/// between calls.
void buildObjectPoints(const LabeledCloud& foreground,
                       const std::vector<core::DetectedObject>& objects, LabeledCloud* out,
                       std::unordered_map<std::uint32_t, std::uint32_t>* scratch);

}  // namespace ros_conv
}  // namespace urban_detection
