// urban_detection/KdTreeDetector: segmentation/foreground -> objects, objects/points with the
// paper's baseline, Euclidean clustering over a kd-tree. Parameters: ~kdtree/*
// (config/detection.yaml).
#include "urban_detection/core/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/core/kdtree_detector.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/detector_nodelet.h"

namespace urban_detection {

class KdTreeDetector : public DetectorNodelet {
 protected:
  std::unique_ptr<core::ObjectDetector> createDetector(const ros::NodeHandle& pnh) override {
    core::KdTreeDetectorParams params;
    ros_conv::loadKdTreeParams(ros::NodeHandle(pnh, "kdtree"), &params);
    return std::make_unique<core::KdTreeDetector>(params);
  }
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::KdTreeDetector, nodelet::Nodelet)
