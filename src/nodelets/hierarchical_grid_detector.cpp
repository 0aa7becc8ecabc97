// urban_detection/HierarchicalGridDetector: segmentation/foreground -> objects, objects/points
// with the hierarchical grid model (paper Sec. 3.2). Parameters: ~hierarchical_grid/*
// (config/detection.yaml).
#include "urban_detection/core/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/core/hierarchical_grid_detector.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/detector_nodelet.h"

namespace urban_detection {

class HierarchicalGridDetector : public DetectorNodelet {
 protected:
  std::unique_ptr<core::ObjectDetector> createDetector(const ros::NodeHandle& pnh) override {
    core::HierarchicalGridDetectorParams params;
    ros_conv::loadHierarchicalGridParams(ros::NodeHandle(pnh, "hierarchical_grid"), &params);
    return std::make_unique<core::HierarchicalGridDetector>(params);
  }
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::HierarchicalGridDetector, nodelet::Nodelet)
