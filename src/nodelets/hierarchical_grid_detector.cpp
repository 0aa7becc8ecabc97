// urban_detection/HierarchicalGridDetector: segmentation/foreground -> objects, objects/points
// with the hierarchical grid model (paper Sec. 3.2). Parameters: ~hierarchical_grid/*
// (config/hierarchical_grid.yaml, config/classification.yaml), tunable in ~hierarchical_grid (cfg/HierarchicalGridDetector.cfg).
#include "urban_detection/core/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/HierarchicalGridDetectorConfig.h"
#include "urban_detection/core/hierarchical_grid_detector.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/tunable_detector_nodelet.h"

namespace urban_detection {

struct HierarchicalGridTraits {
  using Params = core::HierarchicalGridDetectorParams;
  using Config = HierarchicalGridDetectorConfig;
  using Detector = core::HierarchicalGridDetector;
  using Fields = ros_conv::HierarchicalGridTunables;
  static constexpr const char* kNamespace = "hierarchical_grid";
  static void load(const ros::NodeHandle& nh, Params* p) {
    ros_conv::loadHierarchicalGridParams(nh, p);
  }
  static std::string check(const ros::NodeHandle& nh, const Params& p) {
    return ros_conv::checkHierarchicalGridParams(nh, p);
  }
};

class HierarchicalGridDetector : public TunableDetectorNodelet<HierarchicalGridTraits> {};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::HierarchicalGridDetector, nodelet::Nodelet)
