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
#include "urban_detection/core/common/param_fields.h"

namespace urban_detection {
namespace ros_conv {

/// Marker options, mirrored in config/markers.yaml.
struct ObjectMarkerParams {
  bool show_ids = true;          // [-] add a text marker with the object id (and class if known)
  double box_alpha = 0.45;       // [0..1] box opacity
  double text_size_m = 0.6;      // [m] height of the id text
  double min_box_size_m = 0.05;  // [m] box dimensions are at least this (flat objects stay visible)
  bool colour_by_class = true;   // [-] classified objects take their class colour, others the id's
  bool show_legend = true;       // [-] the LiDAR classes' names in their colours (ns "legend")
  double legend_x_m = -26.0;     // [m] left end of the legend's first line in the objects'
  double legend_y_m = 25.0;      // [m]   frame (the shipped rviz view's upper left corner)
  double legend_text_size_m = 1.6;  // [m] legend text height
};

/// "" when every field is in its table range (ParamFields<ObjectMarkerParams> below).
std::string validate(const ObjectMarkerParams& params);

/// Colour of object `id`: hue from the golden-ratio sequence, so an id always gets the same
/// colour and consecutive ids contrast.
std_msgs::ColorRGBA colourForId(std::uint32_t id, double alpha);

/// Colour of an object class: for the LiDAR classifier's classes (vehicle, pedestrian, cyclist,
/// other_object, non_object) bright colours that stand out on rviz's dark background
/// (kLegendClasses); for the other common urban class names (car, truck, bus, person, rider,
/// bicycle, motorcycle, pole, traffic sign, traffic light, vegetation, ... case-insensitive,
/// KITTI names included) the Cityscapes colours; otherwise a colour derived from the name, so
/// a class keeps its colour across frames and runs.
std_msgs::ColorRGBA colourForClass(const std::string& class_label, double alpha);

/// The classes the legend lists, in its order.
constexpr const char* kLegendClasses[] = {"vehicle", "pedestrian", "cyclist", "other_object"};

/// Builds the markers of `objects` (header copied): marker 0 is DELETEALL, then one CUBE per
/// object (namespace "objects", id = object id) and, with show_ids, one TEXT_VIEW_FACING (ns
/// "object_ids": the id, and for a classified object its class name and confidence, e.g.
/// "3 car 0.87"); with show_legend and colour_by_class, one TEXT_VIEW_FACING per legend class
/// (ns "legend", its name in its colour, one line below the other from legend_x_m,
/// legend_y_m). Size: 1 + N * (1 + show_ids) + 4 * show_legend.
void buildObjectMarkers(const DetectedObjectArray& objects, const ObjectMarkerParams& params,
                        visualization_msgs::MarkerArray* markers);

}  // namespace ros_conv

/// ObjectMarkerParams' field table (core/common/param_fields.h); loaded from ~markers.
template <>
struct core::ParamFields<ros_conv::ObjectMarkerParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"show_ids", "a text marker with the object id (and class if known)"}, p.show_ids);
    f({"box_alpha", "", 0.0, 1.0, "box opacity"}, p.box_alpha);
    f({"text_size_m", "m", 0.01, 10.0, "height of the id text"}, p.text_size_m);
    f({"min_box_size_m", "m", 0.0, 10.0, "box dimensions are at least this"}, p.min_box_size_m);
    f({"colour_by_class", "classified objects take their class colour, others the id's"},
      p.colour_by_class);
    f({"show_legend", "the LiDAR classes' names in their colours (ns legend)"}, p.show_legend);
    f({"legend_x_m", "m", -1000.0, 1000.0, "legend position x in the objects' frame"},
      p.legend_x_m);
    f({"legend_y_m", "m", -1000.0, 1000.0, "legend position y in the objects' frame"},
      p.legend_y_m);
    f({"legend_text_size_m", "m", 0.01, 20.0, "legend text height"}, p.legend_text_size_m);
  }
};

}  // namespace urban_detection
