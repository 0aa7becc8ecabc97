// urban_detection/HierarchicalGridDetector: segmentation/foreground -> objects, objects/points
// with the hierarchical grid model (paper Sec. 3.2). Parameters: ~hierarchical_grid/*
// (config/hierarchical_grid.yaml, config/classification.yaml), tunable in ~hierarchical_grid
// (cfg/HierarchicalGridDetector.cfg).
#include "urban_detection/core/common/point_types.h"

#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/HierarchicalGridDetectorConfig.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/ros/tunable_detector_nodelet.h"

namespace urban_detection {
namespace ros_conv {

struct HierarchicalGridTraits {
  using Params = core::HierarchicalGridDetectorParams;
  using Config = HierarchicalGridDetectorConfig;
  using Detector = core::HierarchicalGridDetector;
  static constexpr const char* kNamespace = "hierarchical_grid";
};

class HierarchicalGridDetectorNodelet : public TunableDetectorNodelet<HierarchicalGridTraits> {};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::HierarchicalGridDetectorNodelet, nodelet::Nodelet)
