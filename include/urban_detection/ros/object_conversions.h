/// \file object_conversions.h
/// Detected objects: core -> urban_detection/DetectedObjectArray, and the per-object point
/// cloud of `objects/points`. No ROS master needed.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include <std_msgs/Header.h>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace ros_conv {

/// Label of objects no classifier has looked at.
constexpr const char* kUnknownClass = "unknown";

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
