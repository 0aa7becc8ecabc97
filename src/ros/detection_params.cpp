#include "urban_detection/ros/detection_params.h"

#include <ros/package.h>

#include <cmath>
#include <string>
#include <vector>

namespace urban_detection {
namespace ros_conv {
namespace {

void throwIfInvalid(const ros::NodeHandle& nh, const std::string& error) {
  if (!error.empty()) throw ParamError("in " + nh.getNamespace() + ": " + error);
}

// The numeric ranges, shared by the loaders and by dynamic_reconfigure (check*Params).
ParamTable hierarchicalGridTable(core::HierarchicalGridDetectorParams* p) {
  ParamTable t;
  t.add("coarse_cell_m", &p->coarse_cell_m, 0.05, 10.0, "m")
      .add("xi", &p->xi, 1, 8)
      .add("grid_half_extent_m", &p->grid_half_extent_m, 1.0, 500.0, "m")
      .add("max_abs_z_m", &p->max_abs_z_m, 0.1, 1000.0, "m")
      .add("psi_max_m", &p->psi_max_m, 0.0, 100.0, "m")
      .add("radial_bridge_subcells", &p->radial_bridge_subcells, 0, 8)
      .add("far_radial_bridge_subcells", &p->far_radial_bridge_subcells, 0, 8)
      .add("bridge_range_m", &p->bridge_range_m, 0.0, 1000.0, "m")
      .add("gap_bridge_range_m", &p->gap_bridge_range_m, 0.0, 1000.0, "m")
      .add("roof_bridge_subcells", &p->roof_bridge_subcells, 0, 8)
      .add("roof_max_step_m", &p->roof_max_step_m, 0.0, 10.0, "m")
      .add("roof_bridge_range_m", &p->roof_bridge_range_m, 0.0, 1000.0, "m")
      .add("ring_spacing_deg", &p->ring_spacing_deg, 0.01, 10.0, "deg")
      .add("dense_min_weighted_points", &p->dense_min_weighted_points, 0.0, 1e6)
      .add("min_points", &p->min_points, 1, 1000000)
      .add("min_weighted_points", &p->min_weighted_points, 0.0, 1e6)
      .add("max_extent_m", &p->max_extent_m, 0.1, 1000.0, "m")
      .add("weight/full_density_distance_m", &p->weight.full_density_distance_m, 0.0, 1000.0, "m")
      .add("weight/max_distance_m", &p->weight.max_distance_m, 0.1, 1000.0, "m")
      .add("weight/max_weight", &p->weight.max_weight, 1.0, 1e6)
      .add("far_merge/max_gap_m", &p->far_merge.max_gap_m, 0.0, 10.0, "m")
      .add("far_merge/max_across_gap_m", &p->far_merge.max_across_gap_m, 0.0, 10.0, "m")
      .add("far_merge/min_across_overlap", &p->far_merge.min_across_overlap, 0.0, 1.0)
      .add("far_merge/max_z_gap_m", &p->far_merge.max_z_gap_m, 0.0, 10.0, "m")
      .add("far_merge/min_range_m", &p->far_merge.min_range_m, 0.0, 1000.0, "m")
      .add("far_merge/max_length_m", &p->far_merge.max_length_m, 0.01, 100.0, "m")
      .add("far_merge/max_width_m", &p->far_merge.max_width_m, 0.01, 100.0, "m");
  return t;
}

ParamTable kdTreeTable(core::KdTreeDetectorParams* p) {
  ParamTable t;
  t.add("cluster_tolerance_m", &p->cluster_tolerance_m, 0.01, 10.0, "m")
      .add("min_cluster_size", &p->min_cluster_size, 1, 100000000)
      .add("max_cluster_size", &p->max_cluster_size, 1, 100000000)
      .add("max_extent_m", &p->max_extent_m, 0.1, 1000.0, "m")
      .add("max_abs_coordinate_m", &p->max_abs_coordinate_m, 1.0, 1e5, "m");
  return t;
}

}  // namespace

void loadHierarchicalGridParams(const ros::NodeHandle& nh,
                                core::HierarchicalGridDetectorParams* p) {
  hierarchicalGridTable(p).load(nh);
  loadParam(nh, "dense_refinement", &p->dense_refinement);
  const ros::NodeHandle w(nh, "weight");
  loadParam(w, "enabled", &p->weight.enabled);
  loadParam(w, "log_fit", &p->weight.log_fit);
  if (w.hasParam("coefficients")) {
    std::vector<double> c;
    if (!w.getParam("coefficients", c) || c.empty() || c.size() > 16) {
      throw ParamError("parameter '" + w.resolveName("coefficients") +
                       "' must be a list of 1..16 numbers");
    }
    for (const double v : c) checkRange(w.resolveName("coefficients"), v, -1e12, 1e12);
    p->weight.coefficients = c;
  }
  throwIfInvalid(nh, core::validate(*p));
}

void loadKdTreeParams(const ros::NodeHandle& nh, core::KdTreeDetectorParams* p) {
  kdTreeTable(p).load(nh);
  loadParam(nh, "sorted_search", &p->sorted_search);
  throwIfInvalid(nh, core::validate(*p));
}

std::string checkHierarchicalGridParams(const ros::NodeHandle& nh,
                                        core::HierarchicalGridDetectorParams p) {
  const std::string error = hierarchicalGridTable(&p).check(nh);
  return error.empty() ? core::validate(p) : error;
}

std::string checkKdTreeParams(const ros::NodeHandle& nh, core::KdTreeDetectorParams p) {
  const std::string error = kdTreeTable(&p).check(nh);
  return error.empty() ? core::validate(p) : error;
}

void loadObjectFilterParams(const ros::NodeHandle& nh, core::ObjectFilterParams* p) {
  loadParam(nh, "enabled", &p->enabled);
  loadParam(nh, "min_points", &p->min_points, 3, 1000000);
  loadParam(nh, "max_range_m", &p->max_range_m, 0.001, 1000.0, "m");
  loadParam(nh, "row_gap_deg", &p->row_gap_deg, 0.001, 5.0, "deg");
  loadParam(nh, "max_azimuth_gap_deg", &p->max_azimuth_gap_deg, 0.001, 10.0, "deg");
  loadParam(nh, "jump_m", &p->jump_m, 0.001, 10.0, "m");
  loadParam(nh, "min_triplets", &p->min_triplets, 1, 1000000);
  loadParam(nh, "max_jump_fraction", &p->max_jump_fraction, 0.0, 1.0);
  loadParam(nh, "hedge_min_intensity", &p->hedge_min_intensity, 0.0, 1e6);
  loadParam(nh, "hedge_min_length_m", &p->hedge_min_length_m, 0.0, 100.0, "m");
  loadParam(nh, "uniform_max_intensity_std", &p->uniform_max_intensity_std, 0.0, 1e6);
  loadParam(nh, "uniform_min_points", &p->uniform_min_points, 2, 1000000);
  throwIfInvalid(nh, core::validate(*p));
}

void loadObjectClassifierParams(const ros::NodeHandle& nh, core::ObjectClassifierParams* p) {
  loadParam(nh, "enabled", &p->enabled);
  loadParam(nh, "model", &p->model_path);
  loadParam(nh, "min_object_probability", &p->min_object_probability, -1.0, 1.0);
  loadParam(nh, "reject_non_objects", &p->reject_non_objects);
  if (!p->model_path.empty() && p->model_path.front() != '/') {
    p->model_path = ros::package::getPath("urban_detection") + "/config/" + p->model_path;
  }
  throwIfInvalid(nh, core::validate(*p));
}

}  // namespace ros_conv
}  // namespace urban_detection
