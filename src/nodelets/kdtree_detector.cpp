// urban_detection/KdTreeDetector: segmentation/foreground -> objects, objects/points with the
// kd-tree Euclidean clustering baseline (paper Sec. 5). Parameters: ~kdtree/*
// (config/kdtree.yaml, config/classification.yaml), tunable in ~kdtree (cfg/KdTreeDetector.cfg).
#include "urban_detection/core/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/KdTreeDetectorConfig.h"
#include "urban_detection/core/kdtree_detector.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/tunable_detector_nodelet.h"

namespace urban_detection {

struct KdTreeTraits {
  using Params = core::KdTreeDetectorParams;
  using Config = KdTreeDetectorConfig;
  using Detector = core::KdTreeDetector;
  using Fields = ros_conv::KdTreeTunables;
  static constexpr const char* kNamespace = "kdtree";
  static void load(const ros::NodeHandle& nh, Params* p) { ros_conv::loadKdTreeParams(nh, p); }
  static std::string check(const ros::NodeHandle& nh, const Params& p) {
    return ros_conv::checkKdTreeParams(nh, p);
  }
};

class KdTreeDetector : public TunableDetectorNodelet<KdTreeTraits> {};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::KdTreeDetector, nodelet::Nodelet)
