/// \file standard_outputs.h
/// Detected objects as the ecosystem's standard message: urban_detection/Detection3DArray,
/// wire-compatible with vision_msgs/Detection3DArray (ROS 1, same MD5), so that its
/// subscribers, recorders and rviz plugins take this package's objects. No ROS master needed.
#pragma once

#include <cstdint>
#include <string>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/Detection3DArray.h"

namespace urban_detection {
namespace ros_conv {

/// The class id of a class label in Detection3D's hypotheses: the numeric value of
/// core::ObjectCategory (0 non_object, 1 vehicle, 2 pedestrian, 3 cyclist, 4 other_object,
/// 255 unknown or any other label).
std::int64_t classId(const std::string& class_label);

/// One Detection3D per object, in the objects' order: header = the array's, one hypothesis
/// (id = classId(class_label), score = class_confidence, pose = the yaw-oriented box's centre
/// and heading, covariance 0), bbox = the yaw-oriented box (centre, heading, size [m]),
/// source_cloud empty.
void toDetection3DArray(const DetectedObjectArray& objects, Detection3DArray* out);

}  // namespace ros_conv
}  // namespace urban_detection
