/// \file segmentation_config.h
/// GridSegmenterParams <-> GridSegmentationConfig (config/GridSegmentation.cfg). Header-only:
/// the generated Config header exists only for the nodelet library (built after gencfg).
#pragma once

#include "urban_detection/GridSegmentationConfig.h"
#include "urban_detection/core/grid_segmenter.h"

namespace urban_detection {
namespace ros_conv {

inline GridSegmentationConfig toConfig(const core::GridSegmenterParams& p) {
  GridSegmentationConfig c;
  c.sensor_height_m = p.sensor_height_m;
  c.min_points_per_cell = p.min_points_per_cell;
  c.ground_max_range_m = p.ground_max_range_m;
  c.ground_tolerance_m = p.ground_tolerance_m;
  c.ground_max_step_m = p.ground_max_step_m;
  c.tall_min_height_m = p.tall_min_height_m;
  c.tall_min_range_m = p.tall_min_range_m;
  c.hough_enabled = p.hough.enabled;
  c.hough_votes = p.hough.votes;
  c.hough_min_line_length_m = p.hough.min_line_length_m;
  c.hough_max_line_gap_m = p.hough.max_line_gap_m;
  c.hough_min_tall_fraction = p.hough.min_tall_fraction;
  c.hough_min_mixed_wall_length_m = p.hough.min_mixed_wall_length_m;
  return c;
}

/// `base` with the tunable fields replaced by those of `c` (the others are not in the cfg).
inline core::GridSegmenterParams fromConfig(const GridSegmentationConfig& c,
                                            core::GridSegmenterParams base) {
  base.sensor_height_m = c.sensor_height_m;
  base.min_points_per_cell = c.min_points_per_cell;
  base.ground_max_range_m = c.ground_max_range_m;
  base.ground_tolerance_m = c.ground_tolerance_m;
  base.ground_max_step_m = c.ground_max_step_m;
  base.tall_min_height_m = c.tall_min_height_m;
  base.tall_min_range_m = c.tall_min_range_m;
  base.hough.enabled = c.hough_enabled;
  base.hough.votes = c.hough_votes;
  base.hough.min_line_length_m = c.hough_min_line_length_m;
  base.hough.max_line_gap_m = c.hough_max_line_gap_m;
  base.hough.min_tall_fraction = c.hough_min_tall_fraction;
  base.hough.min_mixed_wall_length_m = c.hough_min_mixed_wall_length_m;
  return base;
}

}  // namespace ros_conv
}  // namespace urban_detection
