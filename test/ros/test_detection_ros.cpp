// Detection ROS layer without a master: core -> message conversion, objects/points, markers,
// and config/{hierarchical_grid,kdtree,markers}.yaml mirroring the params structs.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <cmath>
#include <set>
#include <string>
#include <unordered_map>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/ros/object_conversions.h"
#include "urban_detection/ros/object_markers.h"

namespace urban_detection {
namespace {

core::DetectedObject makeObject(std::uint32_t id, float yaw) {
  core::DetectedObject o;
  o.id = id;
  o.indices = {7, 3, 11};
  o.centroid = Eigen::Vector3f(1.0f, 2.0f, -1.0f);
  o.min_pt = Eigen::Vector3f(0.0f, 1.0f, -1.7f);
  o.max_pt = Eigen::Vector3f(4.0f, 3.0f, -0.2f);
  o.obb_center = Eigen::Vector3f(2.0f, 2.0f, -0.95f);
  o.obb_size = Eigen::Vector3f(4.2f, 1.7f, 1.5f);
  o.obb_yaw_rad = yaw;
  return o;
}

TEST(DetectionConversions, ObjectFieldsAndHeader) {
  std_msgs::Header h;
  h.stamp = ros::Time(1317000000, 123456000);
  h.frame_id = "velodyne";
  h.seq = 4;
  DetectedObjectArray msg;
  ros_conv::toMsg({makeObject(1, 0.5f), makeObject(2, -1.2f)}, "hierarchical_grid", h, &msg);
  EXPECT_EQ(msg.header.stamp, h.stamp);
  EXPECT_EQ(msg.header.frame_id, "velodyne");
  EXPECT_EQ(msg.detector, "hierarchical_grid");
  ASSERT_EQ(msg.objects.size(), 2u);
  const DetectedObject& o = msg.objects[0];
  EXPECT_EQ(o.id, 1u);
  EXPECT_EQ(o.point_count, 3u);
  EXPECT_EQ(o.indices, (std::vector<std::uint32_t>{7, 3, 11}));
  EXPECT_DOUBLE_EQ(o.centroid.y, 2.0);
  EXPECT_DOUBLE_EQ(o.aabb_pose.position.x, 2.0);    // (0 + 4) / 2
  EXPECT_FLOAT_EQ(o.aabb_pose.position.z, -0.95f);  // (-1.7 - 0.2) / 2
  EXPECT_DOUBLE_EQ(o.aabb_pose.orientation.w, 1.0);
  EXPECT_FLOAT_EQ(o.aabb_dimensions.z, 1.5f);
  EXPECT_FLOAT_EQ(o.obb_dimensions.x, 4.2f);
  // The quaternion rotates x onto the yaw direction: yaw = atan2(2 w z, 1 - 2 z^2).
  const double yaw = std::atan2(2.0 * o.obb_pose.orientation.w * o.obb_pose.orientation.z,
                                1.0 - 2.0 * o.obb_pose.orientation.z * o.obb_pose.orientation.z);
  EXPECT_NEAR(yaw, 0.5, 1e-6);
  EXPECT_EQ(o.class_label, "unknown");
  EXPECT_EQ(o.class_confidence, 0.0f);
}

TEST(DetectionConversions, ObjectPointsCarryTheirObjectId) {
  LabeledCloud fg;
  fg.header.frame_id = "velodyne";
  fg.header.stamp = 1317000000123456ULL;
  for (std::uint32_t i = 0; i < 6; ++i) {
    // label 4: kShort on the foreground; index: in velodyne_points
    fg.push_back(makeLabeledPoint(static_cast<float>(i), 0.0f, 0.0f, 4, 100 + i));
  }
  core::DetectedObject a, b;
  a.id = 1;
  a.indices = {100, 102};
  b.id = 2;
  b.indices = {105};
  LabeledCloud out;
  std::unordered_map<std::uint32_t, std::uint32_t> scratch;
  ros_conv::buildObjectPoints(fg, {a, b}, &out, &scratch);
  ASSERT_EQ(out.size(), 3u);  // 101, 103, 104 are in no object
  EXPECT_EQ(out.header.stamp, fg.header.stamp);
  EXPECT_EQ(out[0].index, 100u);
  EXPECT_EQ(out[0].label, 1u);
  EXPECT_EQ(out[1].index, 102u);
  EXPECT_EQ(out[1].label, 1u);
  EXPECT_EQ(out[2].index, 105u);
  EXPECT_EQ(out[2].label, 2u);
  EXPECT_FLOAT_EQ(out[2].x, 5.0f);
}

TEST(ObjectMarkers, DeleteAllFirstThenABoxAndATextPerObject) {
  DetectedObjectArray objs;
  objs.header.frame_id = "velodyne";
  ros_conv::toMsg({makeObject(3, 0.2f), makeObject(9, 1.0f)}, "kdtree", objs.header, &objs);
  ros_conv::ObjectMarkerParams p;
  p.show_legend = false;
  visualization_msgs::MarkerArray m;
  ros_conv::buildObjectMarkers(objs, p, &m);
  ASSERT_EQ(m.markers.size(), 1u + 2u * 2u);
  EXPECT_EQ(m.markers[0].action, visualization_msgs::Marker::DELETEALL);
  std::set<std::pair<std::string, int>> keys;
  int boxes = 0;
  for (std::size_t i = 1; i < m.markers.size(); ++i) {
    const auto& mk = m.markers[i];
    EXPECT_EQ(mk.action, visualization_msgs::Marker::ADD);
    EXPECT_EQ(mk.header.frame_id, "velodyne");
    EXPECT_TRUE(keys.insert({mk.ns, mk.id}).second) << "duplicate marker " << mk.ns << mk.id;
    if (mk.type == visualization_msgs::Marker::CUBE) {
      ++boxes;
      EXPECT_DOUBLE_EQ(mk.scale.x, objs.objects[0].obb_dimensions.x);
    } else {
      EXPECT_EQ(mk.type, visualization_msgs::Marker::TEXT_VIEW_FACING);
      EXPECT_EQ(mk.text, std::to_string(mk.id));
    }
  }
  EXPECT_EQ(boxes, 2);
  EXPECT_EQ(m.markers[1].pose, objs.objects[0].obb_pose);
  // Without ids: exactly one marker per object after the DELETEALL; none for no object.
  p.show_ids = false;
  ros_conv::buildObjectMarkers(objs, p, &m);
  EXPECT_EQ(m.markers.size(), 1u + 2u);
  objs.objects.clear();
  ros_conv::buildObjectMarkers(objs, p, &m);
  ASSERT_EQ(m.markers.size(), 1u);
  EXPECT_EQ(m.markers[0].action, visualization_msgs::Marker::DELETEALL);
}

// WCAG relative luminance of an sRGB colour (0..1 channels).
double luminance(double r, double g, double b) {
  auto lin = [](double c) { return c <= 0.03928 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  return 0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b);
}

TEST(ObjectMarkers, LegendInReadableClassColours) {
  DetectedObjectArray objs;
  objs.header.frame_id = "velodyne";
  ros_conv::ObjectMarkerParams p;
  visualization_msgs::MarkerArray m;
  ros_conv::buildObjectMarkers(objs, p, &m);
  ASSERT_EQ(m.markers.size(), 1u + 4u);
  // rviz's background in the shipped config (30, 30, 34): every legend colour has a contrast
  // ratio of at least 4.5 (WCAG's for normal text) against it, and the classes differ.
  const double bg = luminance(30 / 255.0, 30 / 255.0, 34 / 255.0);
  std::set<std::string> names;
  for (std::size_t i = 1; i < m.markers.size(); ++i) {
    const auto& mk = m.markers[i];
    EXPECT_EQ(mk.ns, "legend");
    EXPECT_EQ(mk.type, visualization_msgs::Marker::TEXT_VIEW_FACING);
    EXPECT_EQ(mk.header.frame_id, "velodyne");
    names.insert(mk.text);
    const auto c = ros_conv::colourForClass(mk.text, 1.0);
    EXPECT_EQ(mk.color, c);
    const double contrast = (luminance(c.r, c.g, c.b) + 0.05) / (bg + 0.05);
    EXPECT_GE(contrast, 4.5) << mk.text;
    if (i > 1) {
      EXPECT_LT(mk.pose.position.y, m.markers[i - 1].pose.position.y);  // one per line
    }
  }
  EXPECT_EQ(names, (std::set<std::string>{"vehicle", "pedestrian", "cyclist", "other_object"}));
  p.show_legend = false;
  ros_conv::buildObjectMarkers(objs, p, &m);
  EXPECT_EQ(m.markers.size(), 1u);
}

TEST(ObjectMarkers, ColourIsStablePerIdAndDistinctForNeighbours) {
  const auto a = ros_conv::colourForId(5, 0.5), b = ros_conv::colourForId(5, 0.5);
  EXPECT_EQ(a, b);
  EXPECT_FLOAT_EQ(a.a, 0.5f);
  for (std::uint32_t id = 1; id < 50; ++id) {
    const auto c = ros_conv::colourForId(id, 1.0), d = ros_conv::colourForId(id + 1, 1.0);
    const double diff = std::fabs(c.r - d.r) + std::fabs(c.g - d.g) + std::fabs(c.b - d.b);
    EXPECT_GT(diff, 0.2) << id;
    for (const float v : {c.r, c.g, c.b}) {
      EXPECT_GE(v, 0.0f);
      EXPECT_LE(v, 1.0f);
    }
  }
}

TEST(DetectionConfig, YamlMirrorsTheParamsStructs) {
  const std::string dir = std::string(UD_SOURCE_DIR) + "/config/";
  const core::HierarchicalGridDetectorParams h;
  const YAML::Node g = YAML::LoadFile(dir + "hierarchical_grid.yaml")["hierarchical_grid"];
  EXPECT_DOUBLE_EQ(g["coarse_cell_m"].as<double>(), h.coarse_cell_m);
  EXPECT_EQ(g["xi"].as<int>(), h.xi);
  EXPECT_DOUBLE_EQ(g["grid_half_extent_m"].as<double>(), h.grid_half_extent_m);
  EXPECT_DOUBLE_EQ(g["max_abs_z_m"].as<double>(), h.max_abs_z_m);
  EXPECT_DOUBLE_EQ(g["psi_max_m"].as<double>(), h.psi_max_m);
  EXPECT_EQ(g["radial_bridge_subcells"].as<int>(), h.radial_bridge_subcells);
  EXPECT_EQ(g["far_radial_bridge_subcells"].as<int>(), h.far_radial_bridge_subcells);
  EXPECT_DOUBLE_EQ(g["bridge_range_m"].as<double>(), h.bridge_range_m);
  EXPECT_DOUBLE_EQ(g["gap_bridge_range_m"].as<double>(), h.gap_bridge_range_m);
  EXPECT_EQ(g["roof_bridge_subcells"].as<int>(), h.roof_bridge_subcells);
  EXPECT_DOUBLE_EQ(g["roof_max_step_m"].as<double>(), h.roof_max_step_m);
  EXPECT_DOUBLE_EQ(g["roof_bridge_range_m"].as<double>(), h.roof_bridge_range_m);
  EXPECT_DOUBLE_EQ(g["ring_spacing_deg"].as<double>(), h.ring_spacing_deg);
  EXPECT_DOUBLE_EQ(g["dense_min_weighted_points"].as<double>(), h.dense_min_weighted_points);
  EXPECT_EQ(g["dense_refinement"].as<bool>(), h.dense_refinement);
  EXPECT_EQ(g["min_points"].as<int>(), h.min_points);
  EXPECT_DOUBLE_EQ(g["min_weighted_points"].as<double>(), h.min_weighted_points);
  EXPECT_DOUBLE_EQ(g["max_extent_m"].as<double>(), h.max_extent_m);
  const YAML::Node w = g["weight"];
  EXPECT_EQ(w["enabled"].as<bool>(), h.weight.enabled);
  EXPECT_EQ(w["log_fit"].as<bool>(), h.weight.log_fit);
  EXPECT_EQ(w["coefficients"].as<std::vector<double>>(), h.weight.coefficients);
  EXPECT_DOUBLE_EQ(w["full_density_distance_m"].as<double>(), h.weight.full_density_distance_m);
  EXPECT_DOUBLE_EQ(w["max_distance_m"].as<double>(), h.weight.max_distance_m);
  EXPECT_DOUBLE_EQ(w["max_weight"].as<double>(), h.weight.max_weight);
  const YAML::Node fm = g["far_merge"];
  EXPECT_DOUBLE_EQ(fm["max_gap_m"].as<double>(), h.far_merge.max_gap_m);
  EXPECT_DOUBLE_EQ(fm["max_across_gap_m"].as<double>(), h.far_merge.max_across_gap_m);
  EXPECT_DOUBLE_EQ(fm["min_across_overlap"].as<double>(), h.far_merge.min_across_overlap);
  EXPECT_DOUBLE_EQ(fm["max_z_gap_m"].as<double>(), h.far_merge.max_z_gap_m);
  EXPECT_DOUBLE_EQ(fm["min_range_m"].as<double>(), h.far_merge.min_range_m);
  EXPECT_DOUBLE_EQ(fm["max_length_m"].as<double>(), h.far_merge.max_length_m);
  EXPECT_DOUBLE_EQ(fm["max_width_m"].as<double>(), h.far_merge.max_width_m);
  const core::KdTreeDetectorParams k;
  const YAML::Node kd = YAML::LoadFile(dir + "kdtree.yaml")["kdtree"];
  EXPECT_DOUBLE_EQ(kd["cluster_tolerance_m"].as<double>(), k.cluster_tolerance_m);
  EXPECT_EQ(kd["min_cluster_size"].as<int>(), k.min_cluster_size);
  EXPECT_EQ(kd["max_cluster_size"].as<int>(), k.max_cluster_size);
  EXPECT_DOUBLE_EQ(kd["max_extent_m"].as<double>(), k.max_extent_m);
  EXPECT_DOUBLE_EQ(kd["max_abs_coordinate_m"].as<double>(), k.max_abs_coordinate_m);
  EXPECT_EQ(kd["sorted_search"].as<bool>(), k.sorted_search);
  const ros_conv::ObjectMarkerParams mp;
  const YAML::Node m = YAML::LoadFile(dir + "markers.yaml")["markers"];
  EXPECT_EQ(m["show_ids"].as<bool>(), mp.show_ids);
  EXPECT_DOUBLE_EQ(m["box_alpha"].as<double>(), mp.box_alpha);
  EXPECT_DOUBLE_EQ(m["text_size_m"].as<double>(), mp.text_size_m);
  EXPECT_DOUBLE_EQ(m["min_box_size_m"].as<double>(), mp.min_box_size_m);
}

}  // namespace
}  // namespace urban_detection
