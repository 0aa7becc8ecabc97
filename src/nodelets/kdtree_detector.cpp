// urban_detection/KdTreeDetector: segmentation/foreground -> objects, objects/points with the
// kd-tree Euclidean clustering baseline (paper Sec. 5). Parameters: ~kdtree/*
// (config/detection.yaml), tunable in ~kdtree (config/KdTreeDetector.cfg).
#include "urban_detection/core/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/KdTreeDetectorConfig.h"
#include "urban_detection/core/kdtree_detector.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/detector_nodelet.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {

class KdTreeDetector : public DetectorNodelet {
 protected:
  std::unique_ptr<core::ObjectDetector> createDetector(const ros::NodeHandle& pnh) override {
    ros_conv::loadKdTreeParams(ros::NodeHandle(pnh, "kdtree"), &params_);
    return std::make_unique<core::KdTreeDetector>(params_);
  }

  void startReconfigure(const ros::NodeHandle& pnh) override {
    KdTreeDetectorConfig c;
    c.cluster_tolerance_m = params_.cluster_tolerance_m;
    c.min_cluster_size = params_.min_cluster_size;
    c.max_cluster_size = params_.max_cluster_size;
    c.max_extent_m = params_.max_extent_m;
    reconfigure_nh_ = ros::NodeHandle(pnh, "kdtree");
    reconfigure_ = std::make_unique<Reconfigure>(
        reconfigure_nh_, c, [this](const auto& config) { return apply(config); });
  }

  // The whole set is validated (the loader's ranges and cross-field checks), then a new detector
  // replaces the old between two revolutions.
  std::string apply(const KdTreeDetectorConfig& c) {
    core::KdTreeDetectorParams p = params_;
    p.cluster_tolerance_m = c.cluster_tolerance_m;
    p.min_cluster_size = c.min_cluster_size;
    p.max_cluster_size = c.max_cluster_size;
    p.max_extent_m = c.max_extent_m;
    const std::string error = ros_conv::checkKdTreeParams(reconfigure_nh_, p);
    if (!error.empty()) return error;
    replaceDetector(std::make_unique<core::KdTreeDetector>(p));
    params_ = p;
    return "";
  }

  using Reconfigure = ros_conv::ValidatedReconfigure<KdTreeDetectorConfig>;
  core::KdTreeDetectorParams params_;  // in force
  ros::NodeHandle reconfigure_nh_;     // ~kdtree
  std::unique_ptr<Reconfigure> reconfigure_;
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::KdTreeDetector, nodelet::Nodelet)
