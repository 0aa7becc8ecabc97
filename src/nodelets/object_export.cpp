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
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/standard_outputs.h"

namespace urban_detection {
namespace ros_conv {

class ObjectExportNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      loadParam(getPrivateNodeHandle(), "queue_size", &queue_size_, 1, 100, "messages");
    } catch (const ParamError& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "ObjectExport: " + std::string(e.what()) + "; the nodelet stays idle");
      return;
    }
    diagnostics_ = std::make_unique<ros_conv::StageDiagnostics>(
        getNodeHandle(), getPrivateNodeHandle(), getName(), "export");
    diagnostics_->setActive(false);
    lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) return sub_.shutdown();
      sub_ =
          getNodeHandle().subscribe("objects", queue_size_, &ObjectExportNodelet::objectsCb, this);
    });
    pub_ = lazy_->advertise<Detection3DArray>(getNodeHandle(), "objects/detections3d", 2);
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& objects) {
    const ros::WallTime start = ros::WallTime::now();
    diagnostics_->input(objects->header.seq);
    auto out = boost::make_shared<Detection3DArray>();
    ros_conv::toDetection3DArray(*objects, out.get());
    pub_.publish(boost::shared_ptr<const Detection3DArray>(out));
    diagnostics_->latency(objects->header.stamp, ros::Time::now());
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
    diagnostics_->output();
  }

  int queue_size_ = 2;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ObjectExportNodelet, nodelet::Nodelet)
