/// \file detection_params.h
/// Loading of the detector parameter structs from the ROS parameter server, mirroring
/// config/hierarchical_grid.yaml and config/kdtree.yaml, with range checks.
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "urban_detection/core/hierarchical_grid_detector.h"
#include "urban_detection/core/kdtree_detector.h"
#include "urban_detection/core/object_classifier.h"
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

/// The checks of the loaders on a complete set (dynamic_reconfigure): "" when `params` is
/// accepted, else the reason naming the first bad parameter (resolved in `nh`) and its range,
/// or the violated cross-field condition. The same ranges as the loaders, from one table.
std::string checkHierarchicalGridParams(const ros::NodeHandle& nh,
                                        core::HierarchicalGridDetectorParams params);
std::string checkKdTreeParams(const ros::NodeHandle& nh, core::KdTreeDetectorParams params);

/// Same for the object filter run after either detector (`object_filter:` section).
void loadObjectFilterParams(const ros::NodeHandle& nh, core::ObjectFilterParams* params);

/// Same for the object classifier run after either detector (`classifier:` section). A
/// relative `model` path is taken relative to this package's config/ folder, as in
/// config/classification.yaml.
void loadObjectClassifierParams(const ros::NodeHandle& nh, core::ObjectClassifierParams* params);

}  // namespace ros_conv
}  // namespace urban_detection
