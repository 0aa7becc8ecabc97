#include "urban_detection/ros/detection_params.h"

#include <ros/package.h>

namespace urban_detection {
namespace ros_conv {

void loadObjectClassifierParams(const ros::NodeHandle& nh, core::ObjectClassifierParams* p) {
  loadFields(nh, p);
  if (!p->model_path.empty() && p->model_path.front() != '/') {
    p->model_path = ros::package::getPath("urban_detection") + "/config/" + p->model_path;
  }
}

}  // namespace ros_conv
}  // namespace urban_detection
