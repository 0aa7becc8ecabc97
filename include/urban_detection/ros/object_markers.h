/// \file object_markers.h
/// rviz markers of detected objects: a DELETEALL first (so boxes of the previous frame never
/// linger), then per object a yaw-oriented box and, optionally, its id as text. No ROS master
/// needed.
#pragma once

#include <string>

#include <ros/node_handle.h>
#include <std_msgs/ColorRGBA.h>
#include <visualization_msgs/MarkerArray.h>

#include "urban_detection/DetectedObjectArray.h"

namespace urban_detection {
namespace ros_conv {

/// Marker options, mirrored in config/markers.yaml.
struct ObjectMarkerParams {
  bool show_ids = true;     // [-] add a text marker with the object id (and class if known)
  double box_alpha = 0.45;  // [0..1] box opacity
  double text_size_m = 0.6; // [m] height of the id text
  double min_box_size_m = 0.05;  // [m] box dimensions are at least this (flat objects stay visible)
  bool colour_by_class = true;   // [-] classified objects take their class colour, others the id's
};

/// Colour of object `id`: hue from the golden-ratio sequence, so an id always gets the same
/// colour and consecutive ids contrast.
std_msgs::ColorRGBA colourForId(std::uint32_t id, double alpha);

/// Colour of an object class (issue 9): a fixed Cityscapes-like colour for the common urban
/// class names (car, truck, bus, person, rider, bicycle, motorcycle, pole, traffic sign,
/// traffic light, vegetation, ... case-insensitive, KITTI names included), otherwise a colour
/// derived from the name, so a class keeps its colour across frames and runs.
std_msgs::ColorRGBA colourForClass(const std::string& class_label, double alpha);

/// Builds the markers of `objects` (header copied): marker 0 is DELETEALL, then one CUBE per
/// object (namespace "objects", id = object id) and, with show_ids, one TEXT_VIEW_FACING (ns
/// "object_ids": the id, and for a classified object its class name and confidence, e.g.
/// "3 car 0.87"). Size: 1 + N * (1 + show_ids).
void buildObjectMarkers(const DetectedObjectArray& objects, const ObjectMarkerParams& params,
                        visualization_msgs::MarkerArray* markers);

/// Reads the options set under `nh` (the nodelet's ~markers); throws ParamError naming the
/// first parameter out of its accepted range.
void loadObjectMarkerParams(const ros::NodeHandle& nh, ObjectMarkerParams* params);
/// The loader's range checks on a complete set (dynamic_reconfigure): "" when accepted, else
/// the reason naming the parameter (resolved in `nh`) and its range.
std::string checkObjectMarkerParams(const ros::NodeHandle& nh, ObjectMarkerParams params);

}  // namespace ros_conv
}  // namespace urban_detection
