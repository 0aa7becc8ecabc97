/// \file detection_params.h
/// Loading of the detector parameter structs from the ROS parameter server, mirroring
/// config/detection.yaml (`hierarchical_grid:` and `kdtree:` sections), with range checks.
#pragma once

#include <ros/node_handle.h>

#include "urban_detection/core/hierarchical_grid_detector.h"
#include "urban_detection/core/kdtree_detector.h"
#include "urban_detection/core/object_filter.h"
#include "urban_detection/ros/param_loading.h"

namespace urban_detection {
namespace ros_conv {

/// Reads every field of `params` set under `nh` (unset ones keep their value; the distance
/// weight under `weight/`), then the cross-field checks of core::validate(). Throws ParamError
/// naming the first bad parameter and its accepted range.
void loadHierarchicalGridParams(const ros::NodeHandle& nh,
                                core::HierarchicalGridDetectorParams* params);

/// Same for the kd-tree baseline.
void loadKdTreeParams(const ros::NodeHandle& nh, core::KdTreeDetectorParams* params);

/// Same for the object filter run after either detector (`object_filter:` section).
void loadObjectFilterParams(const ros::NodeHandle& nh, core::ObjectFilterParams* params);

}  // namespace ros_conv
}  // namespace urban_detection
