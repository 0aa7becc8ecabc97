#include "urban_detection/ros/object_markers.h"

#include "urban_detection/ros/param_loading.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

namespace urban_detection {
namespace ros_conv {

std_msgs::ColorRGBA colourForId(std::uint32_t id, double alpha) {
  const double h = std::fmod(id * 0.6180339887498949, 1.0) * 6.0;  // hue sector [0, 6)
  const double s = 0.85, v = 0.95;
  const double c = v * s, x = c * (1.0 - std::fabs(std::fmod(h, 2.0) - 1.0)), m = v - c;
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(h)) {
    case 0:
      r = c;
      g = x;
      break;
    case 1:
      r = x;
      g = c;
      break;
    case 2:
      g = c;
      b = x;
      break;
    case 3:
      g = x;
      b = c;
      break;
    case 4:
      r = x;
      b = c;
      break;
    default:
      r = c;
      b = x;
      break;
  }
  std_msgs::ColorRGBA col;
  col.r = static_cast<float>(r + m);
  col.g = static_cast<float>(g + m);
  col.b = static_cast<float>(b + m);
  col.a = static_cast<float>(alpha);
  return col;
}

std_msgs::ColorRGBA colourForClass(const std::string& class_label, double alpha) {
  std::string name;
  for (const char c : class_label) {
    name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  // Cityscapes palette (RGB) for the urban classes a segmentation network typically reports.
  static const std::map<std::string, std::array<int, 3>> palette = {
      {"car", {0, 0, 142}},
      {"van", {0, 60, 100}},
      {"truck", {0, 0, 70}},
      {"bus", {0, 60, 100}},
      {"train", {0, 80, 100}},
      {"tram", {0, 80, 100}},
      {"person", {220, 20, 60}},
      {"pedestrian", {255, 70, 110}},
      {"person_sitting", {220, 20, 60}},
      {"rider", {255, 0, 0}},
      {"cyclist", {255, 210, 0}},
      {"bicycle", {119, 11, 32}},
      {"motorcycle", {0, 0, 230}},
      {"pole", {153, 153, 153}},
      {"traffic sign", {220, 220, 0}},
      {"traffic light", {250, 170, 30}},
      {"vegetation", {107, 142, 35}},
      {"terrain", {152, 251, 152}},
      {"building", {70, 70, 70}},
      {"wall", {102, 102, 156}},
      {"fence", {190, 153, 153}},
      {"road", {128, 64, 128}},
      {"sidewalk", {244, 35, 232}},
      // The LiDAR classifier's classes (object_classifier.h): bright, far apart in hue and
      // well above rviz's dark grey background in luminance.
      {"vehicle", {40, 150, 255}},
      {"other_object", {0, 230, 200}},
      {"non_object", {130, 210, 70}}};
  const auto it = palette.find(name);
  if (it == palette.end()) {
    // FNV-1a of the name picks a golden-ratio hue: stable across runs, unlike std::hash.
    std::uint32_t h = 2166136261u;
    for (const char c : name) h = (h ^ static_cast<unsigned char>(c)) * 16777619u;
    return colourForId(h % 1000u, alpha);
  }
  std_msgs::ColorRGBA col;
  col.r = static_cast<float>(it->second[0] / 255.0);
  col.g = static_cast<float>(it->second[1] / 255.0);
  col.b = static_cast<float>(it->second[2] / 255.0);
  col.a = static_cast<float>(alpha);
  return col;
}

void buildObjectMarkers(const DetectedObjectArray& objects, const ObjectMarkerParams& params,
                        visualization_msgs::MarkerArray* markers) {
  markers->markers.clear();
  markers->markers.reserve(1 + objects.objects.size() * (params.show_ids ? 2 : 1) + 4);
  visualization_msgs::Marker clear;
  clear.header = objects.header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers->markers.push_back(clear);
  for (const DetectedObject& o : objects.objects) {
    visualization_msgs::Marker box;
    box.header = objects.header;
    box.ns = "objects";
    box.id = static_cast<int>(o.id);
    box.type = visualization_msgs::Marker::CUBE;
    box.action = visualization_msgs::Marker::ADD;
    box.pose = o.obb_pose;
    box.scale.x = std::max(o.obb_dimensions.x, params.min_box_size_m);
    box.scale.y = std::max(o.obb_dimensions.y, params.min_box_size_m);
    box.scale.z = std::max(o.obb_dimensions.z, params.min_box_size_m);
    const bool classified = !o.class_label.empty() && o.class_label != "unknown";
    box.color = classified && params.colour_by_class
                    ? colourForClass(o.class_label, params.box_alpha)
                    : colourForId(o.id, params.box_alpha);
    markers->markers.push_back(box);
    if (!params.show_ids) continue;
    visualization_msgs::Marker text;
    text.header = objects.header;
    text.ns = "object_ids";
    text.id = static_cast<int>(o.id);
    text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    text.action = visualization_msgs::Marker::ADD;
    text.pose.position = o.obb_pose.position;
    text.pose.position.z += 0.5 * box.scale.z + 0.6 * params.text_size_m;
    text.pose.orientation.w = 1.0;
    text.scale.z = params.text_size_m;
    text.color.r = text.color.g = text.color.b = text.color.a = 1.0f;
    text.text = std::to_string(o.id);
    if (classified) {
      char conf[16];
      std::snprintf(conf, sizeof conf, " %.2f", o.class_confidence);
      text.text += " " + o.class_label + conf;
    }
    markers->markers.push_back(text);
  }
  if (!params.show_legend || !params.colour_by_class) return;
  int line = 0;
  for (const char* name : kLegendClasses) {
    visualization_msgs::Marker text;
    text.header = objects.header;
    text.ns = "legend";
    text.id = line;
    text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    text.action = visualization_msgs::Marker::ADD;
    // Top-down view (x right, y up): lines go down the view, left-aligned (rviz centres a
    // text on its position: shift each by half its width, about 0.4 x height per letter).
    const std::string label = name;
    text.pose.position.x =
        params.legend_x_m + 0.2 * params.legend_text_size_m * static_cast<double>(label.size());
    text.pose.position.y = params.legend_y_m - 1.4 * params.legend_text_size_m * line;
    text.pose.orientation.w = 1.0;
    text.scale.z = params.legend_text_size_m;
    text.color = colourForClass(label, 1.0);
    text.text = label;
    markers->markers.push_back(text);
    ++line;
  }
}

std::string validate(const ObjectMarkerParams& params) {
  return core::checkFieldRanges(params);
}

}  // namespace ros_conv
}  // namespace urban_detection
