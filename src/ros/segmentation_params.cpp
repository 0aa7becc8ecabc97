#include "urban_detection/ros/segmentation_params.h"

#include <functional>

#include "urban_detection/ros/param_loading.h"

namespace urban_detection {
namespace ros_conv {

namespace {

// The accepted ranges, in one list: the start-up loader, dynamic_reconfigure and the offline
// tools check the same ones. `shown` turns a parameter name into the name shown to the user.
std::string checkRanges(const core::GridSegmenterParams& p,
                        const std::function<std::string(const std::string&)>& shown) {
  std::string error;
  auto c = [&](const char* name, auto value, auto lo, auto hi, const char* unit = "") {
    if (error.empty() && !(value >= lo && value <= hi)) {  // NaN is out of range
      error = outOfRangeMessage(shown(name), value, decltype(value)(lo), decltype(value)(hi),
                                unit);
    }
  };
  c("sensor_height_m", p.sensor_height_m, -10.0, 10.0, "m");
  c("cell_size_m", p.cell_size_m, 0.05, 5.0, "m");
  c("max_range_m", p.max_range_m, 1.0, 250.0, "m");
  c("max_abs_height_m", p.max_abs_height_m, 1.0, 1000.0, "m");
  c("min_points_per_cell", p.min_points_per_cell, 1, 1000, "points");
  c("ground_max_range_m", p.ground_max_range_m, 0.01, 2.0, "m");
  c("ground_tolerance_m", p.ground_tolerance_m, 0.0, 2.0, "m");
  c("ground_max_step_m", p.ground_max_step_m, 0.0, 2.0, "m");
  c("ground_max_gap_m", p.ground_max_gap_m, 0.0, 20.0, "m");
  c("seed_radius_m", p.seed_radius_m, 0.0, 250.0, "m");
  c("seed_max_abs_height_m", p.seed_max_abs_height_m, 0.0, 5.0, "m");
  c("terrain_fill_iterations", p.terrain_fill_iterations, 0, 100, "cells");
  c("terrain_max_offset_m", p.terrain_max_offset_m, 0.0, 5.0, "m");
  c("tall_min_height_m", p.tall_min_height_m, 0.1, 20.0, "m");
  c("tall_min_range_m", p.tall_min_range_m, 0.1, 50.0, "m");
  c("vehicle_max_height_m", p.vehicle_max_height_m, 0.0, 20.0, "m");
  c("vehicle_max_length_m", p.vehicle_max_length_m, 0.5, 100.0, "m");
  c("vehicle_max_width_m", p.vehicle_max_width_m, 0.5, 100.0, "m");
  c("fov_top_elevation_deg", p.fov_top_elevation_deg, -30.0, 30.0, "deg");
  c("hough/max_range_m", p.hough.max_range_m, 1.0, 250.0, "m");
  c("hough/votes", p.hough.votes, 1, 10000);
  c("hough/min_line_length_m", p.hough.min_line_length_m, 0.0, 500.0, "m");
  c("hough/max_line_gap_m", p.hough.max_line_gap_m, 0.0, 100.0, "m");
  c("hough/theta_resolution_deg", p.hough.theta_resolution_deg, 0.1, 45.0, "deg");
  c("hough/min_tall_fraction", p.hough.min_tall_fraction, 0.0, 1.0);
  c("hough/min_mixed_wall_length_m", p.hough.min_mixed_wall_length_m, 0.0, 500.0, "m");
  c("hough/line_half_width_cells", p.hough.line_half_width_cells, 0, 5, "cells");
  return error;
}

}  // namespace

bool validateGridSegmenterParams(const core::GridSegmenterParams& p, std::string* error) {
  *error = checkRanges(p, [](const std::string& name) { return name; });
  return error->empty();
}

std::string checkGridSegmenterParams(const ros::NodeHandle& nh,
                                     const core::GridSegmenterParams& p) {
  return checkRanges(p, [&nh](const std::string& name) { return nh.resolveName(name); });
}

bool loadGridSegmenterParams(const ros::NodeHandle& nh, core::GridSegmenterParams* p,
                             std::string* error) {
  // Every value type-checked (a string where a number belongs is an error, not the default),
  // then the ranges of the whole struct.
  try {
    loadParam(nh, "sensor_height_m", &p->sensor_height_m);
    loadParam(nh, "cell_size_m", &p->cell_size_m);
    loadParam(nh, "max_range_m", &p->max_range_m);
    loadParam(nh, "max_abs_height_m", &p->max_abs_height_m);
    loadParam(nh, "min_points_per_cell", &p->min_points_per_cell);
    loadParam(nh, "ground_in_sparse_cells", &p->ground_in_sparse_cells);
    loadParam(nh, "ground_max_range_m", &p->ground_max_range_m);
    loadParam(nh, "ground_tolerance_m", &p->ground_tolerance_m);
    loadParam(nh, "ground_max_step_m", &p->ground_max_step_m);
    loadParam(nh, "curb_cells_ground", &p->curb_cells_ground);
    loadParam(nh, "ground_max_gap_m", &p->ground_max_gap_m);
    loadParam(nh, "seed_radius_m", &p->seed_radius_m);
    loadParam(nh, "seed_max_abs_height_m", &p->seed_max_abs_height_m);
    loadParam(nh, "terrain_fill_iterations", &p->terrain_fill_iterations);
    loadParam(nh, "terrain_max_offset_m", &p->terrain_max_offset_m);
    loadParam(nh, "tall_min_height_m", &p->tall_min_height_m);
    loadParam(nh, "tall_min_range_m", &p->tall_min_range_m);
    loadParam(nh, "vehicle_max_height_m", &p->vehicle_max_height_m);
    loadParam(nh, "vehicle_max_length_m", &p->vehicle_max_length_m);
    loadParam(nh, "vehicle_max_width_m", &p->vehicle_max_width_m);
    loadParam(nh, "fov_top_elevation_deg", &p->fov_top_elevation_deg);
    core::HoughWallRefinerParams& h = p->hough;
    loadParam(nh, "hough/enabled", &h.enabled);
    loadParam(nh, "hough/max_range_m", &h.max_range_m);
    loadParam(nh, "hough/votes", &h.votes);
    loadParam(nh, "hough/min_line_length_m", &h.min_line_length_m);
    loadParam(nh, "hough/max_line_gap_m", &h.max_line_gap_m);
    loadParam(nh, "hough/theta_resolution_deg", &h.theta_resolution_deg);
    loadParam(nh, "hough/min_tall_fraction", &h.min_tall_fraction);
    loadParam(nh, "hough/min_mixed_wall_length_m", &h.min_mixed_wall_length_m);
    loadParam(nh, "hough/extend_lines", &h.extend_lines);
    loadParam(nh, "hough/line_half_width_cells", &h.line_half_width_cells);
  } catch (const ParamError& e) {
    *error = e.what();
    return false;
  }
  *error = checkGridSegmenterParams(nh, *p);
  return error->empty();
}

}  // namespace ros_conv
}  // namespace urban_detection
