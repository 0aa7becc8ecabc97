/// \file object_markers.h
/// rviz markers of detected objects: a DELETEALL first (so boxes of the previous frame never
/// linger), then per object a yaw-oriented box and, optionally, its id as text. No ROS master
/// needed.
#pragma once

#include <std_msgs/ColorRGBA.h>
#include <visualization_msgs/MarkerArray.h>

#include "urban_detection/DetectedObjectArray.h"

namespace urban_detection {
namespace ros_conv {

/// Marker options, mirrored in config/detection.yaml (`markers:`).
struct ObjectMarkerParams {
  bool show_ids = true;     // [-] add a text marker with the object id (and class if known)
  double box_alpha = 0.45;  // [0..1] box opacity
  double text_size_m = 0.6; // [m] height of the id text
  double min_box_size_m = 0.05;  // [m] box dimensions are at least this (flat objects stay visible)
};

/// Colour of object `id`: hue from the golden-ratio sequence, so an id always gets the same
/// colour and consecutive ids contrast.
std_msgs::ColorRGBA colourForId(std::uint32_t id, double alpha);

/// Builds the markers of `objects` (header copied): marker 0 is DELETEALL, then one CUBE per
/// object (namespace "objects", id = object id) and, with show_ids, one TEXT_VIEW_FACING (ns
/// "object_ids"). Size: 1 + N * (1 + show_ids).
void buildObjectMarkers(const DetectedObjectArray& objects, const ObjectMarkerParams& params,
                        visualization_msgs::MarkerArray* markers);

}  // namespace ros_conv
}  // namespace urban_detection
