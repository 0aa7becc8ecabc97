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
#include "urban_detection/ros/lazy_stage.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/object_markers.h"
#include "urban_detection/ros/param_loading.h"
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
      loadFields(getPrivateNodeHandle(), &queue_params_);
    } catch (const ParamError& e) {
      return stage_.refuse(getNodeHandle(), getPrivateNodeHandle(), getName(),
                           "ObjectMarkers: " + std::string(e.what()) + "; the nodelet stays idle");
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
    ros::NodeHandle& nh = getNodeHandle();
    stage_.start(nh, getPrivateNodeHandle(), getName(), "markers", [this, nh]() mutable {
      return nh.subscribe("objects", queue_params_.queue_size, &ObjectMarkersNodelet::objectsCb,
                          this);
    });
    pub_ = stage_.advertise<visualization_msgs::MarkerArray>(nh, "objects/markers", 2);
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& objects) {
    const ros::WallTime start = ros::WallTime::now();
    stage_.diagnostics().input(objects->header.seq);
    auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
    {
      std::lock_guard<std::mutex> lock(params_mutex_);
      ros_conv::buildObjectMarkers(*objects, params_, markers.get());
    }
    pub_.publish(boost::shared_ptr<const visualization_msgs::MarkerArray>(markers));
    stage_.published(start, objects->header.stamp);
  }

  using Reconfigure = ros_conv::ValidatedReconfigure<ObjectMarkersConfig>;
  ros_conv::ObjectMarkerParams params_;
  std::mutex params_mutex_;  // params_ between messages and reconfigure
  ObjectQueueParams queue_params_;
  std::unique_ptr<Reconfigure> reconfigure_;
  ros::Publisher pub_;
  LazyStage stage_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ObjectMarkersNodelet, nodelet::Nodelet)
