// urban_detection/HierarchicalGridDetector: segmentation/foreground -> objects, objects/points
// with the hierarchical grid model (paper Sec. 3.2). Parameters: ~hierarchical_grid/*
// (config/detection.yaml), tunable in ~hierarchical_grid (config/HierarchicalGridDetector.cfg).
#include "urban_detection/core/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/HierarchicalGridDetectorConfig.h"
#include "urban_detection/core/hierarchical_grid_detector.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/detector_nodelet.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {

class HierarchicalGridDetector : public DetectorNodelet {
 protected:
  std::unique_ptr<core::ObjectDetector> createDetector(const ros::NodeHandle& pnh) override {
    ros_conv::loadHierarchicalGridParams(ros::NodeHandle(pnh, "hierarchical_grid"), &params_);
    return std::make_unique<core::HierarchicalGridDetector>(params_);
  }

  void startReconfigure(const ros::NodeHandle& pnh) override {
    HierarchicalGridDetectorConfig c;
    c.coarse_cell_m = params_.coarse_cell_m;
    c.xi = params_.xi;
    c.psi_max_m = params_.psi_max_m;
    c.dense_refinement = params_.dense_refinement;
    c.dense_min_weighted_points = params_.dense_min_weighted_points;
    c.weight_enabled = params_.weight.enabled;
    c.radial_bridge_subcells = params_.radial_bridge_subcells;
    c.far_radial_bridge_subcells = params_.far_radial_bridge_subcells;
    c.bridge_range_m = params_.bridge_range_m;
    c.gap_bridge_range_m = params_.gap_bridge_range_m;
    c.roof_bridge_subcells = params_.roof_bridge_subcells;
    c.roof_max_step_m = params_.roof_max_step_m;
    c.roof_bridge_range_m = params_.roof_bridge_range_m;
    c.ring_spacing_deg = params_.ring_spacing_deg;
    c.min_points = params_.min_points;
    c.min_weighted_points = params_.min_weighted_points;
    c.max_extent_m = params_.max_extent_m;
    c.far_merge_max_gap_m = params_.far_merge.max_gap_m;
    c.far_merge_min_range_m = params_.far_merge.min_range_m;
    reconfigure_nh_ = ros::NodeHandle(pnh, "hierarchical_grid");
    reconfigure_ = std::make_unique<Reconfigure>(
        reconfigure_nh_, c, [this](const auto& config) { return apply(config); });
  }

  // The whole set is validated (the loader's ranges and cross-field checks), then a new detector
  // replaces the old between two revolutions.
  std::string apply(const HierarchicalGridDetectorConfig& c) {
    core::HierarchicalGridDetectorParams p = params_;
    p.coarse_cell_m = c.coarse_cell_m;
    p.xi = c.xi;
    p.psi_max_m = c.psi_max_m;
    p.dense_refinement = c.dense_refinement;
    p.dense_min_weighted_points = c.dense_min_weighted_points;
    p.weight.enabled = c.weight_enabled;
    p.radial_bridge_subcells = c.radial_bridge_subcells;
    p.far_radial_bridge_subcells = c.far_radial_bridge_subcells;
    p.bridge_range_m = c.bridge_range_m;
    p.gap_bridge_range_m = c.gap_bridge_range_m;
    p.roof_bridge_subcells = c.roof_bridge_subcells;
    p.roof_max_step_m = c.roof_max_step_m;
    p.roof_bridge_range_m = c.roof_bridge_range_m;
    p.ring_spacing_deg = c.ring_spacing_deg;
    p.min_points = c.min_points;
    p.min_weighted_points = c.min_weighted_points;
    p.max_extent_m = c.max_extent_m;
    p.far_merge.max_gap_m = c.far_merge_max_gap_m;
    p.far_merge.min_range_m = c.far_merge_min_range_m;
    const std::string error = ros_conv::checkHierarchicalGridParams(reconfigure_nh_, p);
    if (!error.empty()) return error;
    replaceDetector(std::make_unique<core::HierarchicalGridDetector>(p));
    params_ = p;
    return "";
  }

  using Reconfigure = ros_conv::ValidatedReconfigure<HierarchicalGridDetectorConfig>;
  core::HierarchicalGridDetectorParams params_;  // in force
  ros::NodeHandle reconfigure_nh_;               // ~hierarchical_grid
  std::unique_ptr<Reconfigure> reconfigure_;
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::HierarchicalGridDetector, nodelet::Nodelet)
