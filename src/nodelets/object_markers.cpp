// urban_detection/ObjectMarkers: objects -> objects/markers (MarkerArray) for rviz: DELETEALL,
// then a yaw-oriented box and an id text per object. Lazy. Parameters: ~markers/*
// (config/markers.yaml), tunable in ~markers (cfg/ObjectMarkers.cfg).
#include <memory>
#include <mutex>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/ObjectMarkersConfig.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/object_markers.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/tunable_fields.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {
namespace ros_conv {

class ObjectMarkersNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    const ros::NodeHandle pnh(getPrivateNodeHandle(), "markers");
    try {
      loadFields(pnh, &params_);
      loadParam(getPrivateNodeHandle(), "queue_size", &queue_size_, 1, 100, "messages");
    } catch (const ParamError& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "ObjectMarkers: " + std::string(e.what()) + "; the nodelet stays idle");
      return;
    }
    const ObjectMarkersConfig initial = ros_conv::toConfig<ObjectMarkersConfig>(params_);
    auto apply = [this, pnh](const ObjectMarkersConfig& n) {
      std::lock_guard<std::mutex> lock(params_mutex_);  // applied from the next message on
      const ros_conv::ObjectMarkerParams p = ros_conv::fromConfig(n, params_);
      const std::string error = checkFields(pnh, p);
      if (error.empty()) params_ = p;
      return error;
    };
    reconfigure_ = std::make_unique<Reconfigure>(pnh, initial, apply);
    diagnostics_ = std::make_unique<ros_conv::StageDiagnostics>(
        getNodeHandle(), getPrivateNodeHandle(), getName(), "markers");
    diagnostics_->setActive(false);
    lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) return sub_.shutdown();
      sub_ =
          getNodeHandle().subscribe("objects", queue_size_, &ObjectMarkersNodelet::objectsCb, this);
    });
    pub_ = lazy_->advertise<visualization_msgs::MarkerArray>(getNodeHandle(), "objects/markers", 2);
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& objects) {
    const ros::WallTime start = ros::WallTime::now();
    diagnostics_->input(objects->header.seq);
    auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
    {
      std::lock_guard<std::mutex> lock(params_mutex_);
      ros_conv::buildObjectMarkers(*objects, params_, markers.get());
    }
    pub_.publish(boost::shared_ptr<const visualization_msgs::MarkerArray>(markers));
    diagnostics_->latency(objects->header.stamp, ros::Time::now());
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
    diagnostics_->output();
  }

  using Reconfigure = ros_conv::ValidatedReconfigure<ObjectMarkersConfig>;
  ros_conv::ObjectMarkerParams params_;
  std::mutex params_mutex_;  // params_ between messages and reconfigure
  int queue_size_ = 2;
  std::unique_ptr<Reconfigure> reconfigure_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ObjectMarkersNodelet, nodelet::Nodelet)
