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
/// of its accepted range (and the range).
bool loadGridSegmenterParams(const ros::NodeHandle& nh, core::GridSegmenterParams* params,
                             std::string* error);

/// Checks the ranges only (shared with loadGridSegmenterParams, usable without ROS params).
bool validateGridSegmenterParams(const core::GridSegmenterParams& params, std::string* error);

}  // namespace ros_conv
}  // namespace urban_detection
