/// \file detection_params.h
/// The classifier's parameters from the ROS parameter server. Every other stage loads its
/// struct with loadFields() (param_loading.h) straight from its field table.
#pragma once

#include <ros/node_handle.h>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/ros/param_loading.h"

namespace urban_detection {
namespace ros_conv {

/// loadFields() of the `classifier:` section; a relative `model` path is then taken relative to
/// this package's config/ folder, as in config/classification.yaml.
void loadObjectClassifierParams(const ros::NodeHandle& nh, core::ObjectClassifierParams* params);

}  // namespace ros_conv
}  // namespace urban_detection
