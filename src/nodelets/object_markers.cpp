// urban_detection/ObjectMarkers: objects -> objects/markers (MarkerArray) for rviz: DELETEALL,
// then a yaw-oriented box and an id text per object. Lazy. Parameters: ~markers/*
// (config/detection.yaml).
#include <mutex>

#include <boost/make_shared.hpp>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/ros/object_markers.h"
#include "urban_detection/ros/param_loading.h"

namespace urban_detection {

class ObjectMarkers : public nodelet::Nodelet {
 private:
  void onInit() override {
    const ros::NodeHandle pnh(getPrivateNodeHandle(), "markers");
    try {
      loadParam(pnh, "show_ids", &params_.show_ids);
      loadParam(pnh, "box_alpha", &params_.box_alpha, 0.0, 1.0);
      loadParam(pnh, "text_size_m", &params_.text_size_m, 0.01, 10.0, "m");
      loadParam(pnh, "min_box_size_m", &params_.min_box_size_m, 0.0, 10.0, "m");
      loadParam(pnh, "colour_by_class", &params_.colour_by_class);
    } catch (const ParamError& e) {
      NODELET_FATAL("ObjectMarkers: %s; the nodelet stays idle", e.what());
      return;
    }
    ros::SubscriberStatusCallback connect = [this](const ros::SingleSubscriberPublisher&) {
      connectCb();
    };
    std::lock_guard<std::mutex> lock(mutex_);
    pub_ = getNodeHandle().advertise<visualization_msgs::MarkerArray>("objects/markers", 2,
                                                                     connect, connect);
  }

  void connectCb() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pub_.getNumSubscribers() > 0 && !sub_) {
      sub_ = getNodeHandle().subscribe("objects", 2, &ObjectMarkers::objectsCb, this);
    } else if (pub_.getNumSubscribers() == 0 && sub_) {
      sub_.shutdown();
    }
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& objects) {
    auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
    ros_conv::buildObjectMarkers(*objects, params_, markers.get());
    pub_.publish(boost::shared_ptr<const visualization_msgs::MarkerArray>(markers));
  }

  ros_conv::ObjectMarkerParams params_;
  std::mutex mutex_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ObjectMarkers, nodelet::Nodelet)
