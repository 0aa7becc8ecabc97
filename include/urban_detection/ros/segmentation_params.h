/// \file segmentation_params.h
/// Loading of GridSegmenterParams from the ROS parameter server (mirrors
/// config/segmentation.yaml), with range checks.
#pragma once

#include <string>

#include <ros/node_handle.h>

#include "urban_detection/core/grid_segmenter.h"

namespace urban_detection {
namespace ros_conv {

/// Reads every field of `params` present under `nh` (missing ones keep their current value,
/// the Hough fields under `hough/`). Returns false with `error` naming the first parameter out
/// of its accepted range (resolved in `nh`) and the range, in outOfRangeMessage()'s wording.
bool loadGridSegmenterParams(const ros::NodeHandle& nh, core::GridSegmenterParams* params,
                             std::string* error);

/// Checks the ranges only (shared with loadGridSegmenterParams, usable without ROS params);
/// the error names the parameter as in config/segmentation.yaml ("hough/votes").
bool validateGridSegmenterParams(const core::GridSegmenterParams& params, std::string* error);

/// The same check on a complete set for dynamic_reconfigure: "" when accepted, else the error
/// naming the parameter resolved in `nh` (the nodelet's private namespace) and the range.
std::string checkGridSegmenterParams(const ros::NodeHandle& nh,
                                     const core::GridSegmenterParams& params);

}  // namespace ros_conv
}  // namespace urban_detection
