// urban_detection/KdTreeDetector: segmentation/foreground -> objects, objects/points with the
// kd-tree Euclidean clustering baseline (paper Sec. 5). Parameters: ~kdtree/*
// (config/kdtree.yaml, config/classification.yaml), tunable in ~kdtree (cfg/KdTreeDetector.cfg).
#include "urban_detection/core/common/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/KdTreeDetectorConfig.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/ros/tunable_detector_nodelet.h"

namespace urban_detection {
namespace ros_conv {

struct KdTreeTraits {
  using Params = core::KdTreeDetectorParams;
  using Config = KdTreeDetectorConfig;
  using Detector = core::KdTreeDetector;
  static constexpr const char* kNamespace = "kdtree";
};

class KdTreeDetectorNodelet : public TunableDetectorNodelet<KdTreeTraits> {};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::KdTreeDetectorNodelet, nodelet::Nodelet)
