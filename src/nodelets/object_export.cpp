// urban_detection/ObjectExport: objects -> objects/detections3d (urban_detection/
// Detection3DArray, wire-compatible with vision_msgs/Detection3DArray: same MD5), so tools
// written for the standard type take this package's objects. Lazy. Parameter: ~queue_size.
#include <memory>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/Detection3DArray.h"
#include "urban_detection/ros/lazy_stage.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/standard_outputs.h"

namespace urban_detection {
namespace ros_conv {

class ObjectExportNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    if (!stage_.load(nh, getPrivateNodeHandle(), getName(), "ObjectExport", &params_)) return;
    stage_.start(nh, getPrivateNodeHandle(), getName(), "export", [this, nh]() mutable {
      return nh.subscribe("objects", params_.queue_size, &ObjectExportNodelet::objectsCb, this);
    });
    pub_ = stage_.advertise<Detection3DArray>(nh, "objects/detections3d", 2);
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& objects) {
    const ros::WallTime start = ros::WallTime::now();
    stage_.diagnostics().input(objects->header.seq);
    auto out = boost::make_shared<Detection3DArray>();
    ros_conv::toDetection3DArray(*objects, out.get());
    pub_.publish(boost::shared_ptr<const Detection3DArray>(out));
    stage_.published(start, objects->header.stamp);
  }

  ObjectQueueParams params_;
  ros::Publisher pub_;
  LazyStage stage_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ObjectExportNodelet, nodelet::Nodelet)
