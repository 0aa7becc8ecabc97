// urban_detection/CloudInput: points_in (sensor_msgs/PointCloud2 from a bag or another driver)
// -> velodyne_points (CloudXYZIRT), the pipeline's cloud type. Fields by name (x y z required;
// intensity, ring, time optional, any numeric type: KITTI clouds carry x y z intensity only);
// non-finite points kept and counted (the segmenter labels them unknown); a malformed message
// is dropped with one error per kind of fault and counted on /diagnostics. The only copy in the
// chain: a PointCloud2 subscriber gets a serialised message whatever the publisher.
// Lazy: subscribed to points_in only while someone listens to velodyne_points. A cloud of more
// than ~max_points points (default: three HDL-64E revolutions at 300 rpm) is refused with an
// ERROR before it is converted.
#include "urban_detection/core/common/point_types.h"

#include <memory>
#include <mutex>
#include <string>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>
#include "urban_detection/ros/cloud_serialization.h"

#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/ros/lazy_stage.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/pointcloud2_input.h"

namespace urban_detection {
namespace ros_conv {

class CloudInputNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    if (!stage_.load(nh, getPrivateNodeHandle(), getName(), "CloudInput", &params_)) return;
    stage_.start(nh, getPrivateNodeHandle(), getName(), "cloud input", [this, nh]() mutable {
      return nh.subscribe("points_in", params_.queue_size, &CloudInputNodelet::cloudCb, this,
                          ros::TransportHints().tcpNoDelay());
    });
    pub_ = stage_.advertise<CloudXYZIRT>(nh, "velodyne_points", 2);
  }

  void cloudCb(const sensor_msgs::PointCloud2ConstPtr& msg) {
    const ros::WallTime start = ros::WallTime::now();
    StageDiagnostics& diagnostics = stage_.diagnostics();
    diagnostics.input(msg->header.seq);
    const std::uint64_t points = static_cast<std::uint64_t>(msg->width) * msg->height;
    std::string error;
    if (points > static_cast<std::uint64_t>(params_.max_points)) {  // before any allocation of ours
      error = "too many points: " + std::to_string(points) + " (max_points " +
              std::to_string(params_.max_points) + ")";
    }
    auto cloud = boost::make_shared<CloudXYZIRT>();
    ros_conv::PointCloud2InputInfo info;
    if (error.empty()) ros_conv::fromPointCloud2(*msg, cloud.get(), &info, &error);
    if (!error.empty()) {  // one throttled ERROR per kind of fault; counted on /diagnostics
      if (diagnostics.refuse(error)) {
        NODELET_ERROR("CloudInput: refusing a PointCloud2 on points_in: %s", error.c_str());
      }
      return;
    }
    if (!info.has_ring || !info.has_time) {
      NODELET_INFO_ONCE(
          "CloudInput: input has no ring/time fields (e.g. KITTI); they are set "
          "to 0");
    }
    diagnostics.count("non_finite_points", info.non_finite, false);
    cloud->header.seq = msg->header.seq;
    pub_.publish(boost::shared_ptr<const CloudXYZIRT>(cloud));
    stage_.published(start);
  }

  CloudInputParams params_;
  ros::Publisher pub_;
  LazyStage stage_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::CloudInputNodelet, nodelet::Nodelet)
