// urban_detection/PacketToCloud: `velodyne_packets` (urban_detection/VelodyneScan, or
// velodyne_msgs/VelodyneScan: same MD5) -> `velodyne_points` (CloudXYZIRT), calibrated, optionally
// transformed packet by packet at each packet's own timestamp (ros/scan_to_cloud.h).
// Lazy: subscribed to the packets only while someone listens to the points.
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>
#include "urban_detection/ros/cloud_serialization.h"

#include <memory>
#include <mutex>

#include "urban_detection/ros/lazy_stage.h"
#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/scan_to_cloud.h"

namespace urban_detection {
namespace ros_conv {

class PacketToCloudNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      params_ = loadPacketToCloudParams(getPrivateNodeHandle());
      converter_ = std::make_unique<ScanToCloud>(params_, getNodeHandle());
    } catch (const std::exception& e) {  // ParamError, core::CalibrationError
      return stage_.refuse(getNodeHandle(), getPrivateNodeHandle(), getName(),
                           "PacketToCloud inactive: " + std::string(e.what()));
    }
    NODELET_INFO("PacketToCloud: calibration %s, range [%.2f, %.2f] m",
                 converter_->decoder().calibration().source.c_str(), params_.decoder.min_range_m,
                 params_.decoder.max_range_m);
    // Input queue_size: the newest revolutions win when decoding is slow.
    ros::NodeHandle& nh = getNodeHandle();
    StageDiagnostics& diagnostics = stage_.start(
        nh, getPrivateNodeHandle(), getName(), "decoding",
        [this, nh]() mutable {
          return nh.subscribe("velodyne_packets", params_.queue_size, &PacketToCloudNodelet::scanCb,
                              this, ros::TransportHints().tcpNoDelay());
        },
        "scans");
    diagnostics.setInputTimeouts(kNoSensorDataWarnS, kNoSensorDataErrorS);
    pub_ = stage_.advertise<CloudXYZIRT>(nh, "velodyne_points", params_.queue_size);
  }

  void scanCb(const ros::MessageEvent<const VelodyneScan>& event) {
    const ros::WallTime start = ros::WallTime::now();
    const VelodyneScan::ConstPtr& scan = event.getConstMessage();
    StageDiagnostics& diagnostics = stage_.diagnostics();
    diagnostics.input(scan->header.seq, event.getPublisherName());
    if (scan->packets.empty()) {
      diagnostics.count("empty_scans");
      NODELET_WARN_THROTTLE(10, "dropping an empty VelodyneScan");
      return;
    }
    if (scan->packets.size() > static_cast<std::size_t>(params_.max_packets_per_scan)) {
      // Refused before any allocation of ours.
      const std::string why =
          "too many packets: a VelodyneScan of " + std::to_string(scan->packets.size()) +
          " packets (max_packets_per_scan " + std::to_string(params_.max_packets_per_scan) + ")";
      if (diagnostics.refuse(why)) {
        NODELET_ERROR("PacketToCloud: refusing %s; nothing of it is decoded", why.c_str());
      }
      return;
    }
    auto cloud = boost::make_shared<CloudXYZIRT>();
    ScanDecodeStats stats;
    std::string tf_error;
    const bool ok = converter_->convert(*scan, cloud.get(), &stats, &tf_error);
    diagnostics.count("bad_packets", stats.decode.bad_packets);
    diagnostics.count("tf_failures", stats.tf_failures);
    diagnostics.count("points", cloud->size(), false);
    const std::string empty = emptyRevolutionCause(stats.decode, converter_->decoder().params());
    if (!empty.empty()) {
      diagnostics.count("revolutions without points");
      NODELET_WARN_THROTTLE(10, "PacketToCloud: %s", empty.c_str());
    }
    if (stats.decode.bad_packets > 0) {
      NODELET_WARN_THROTTLE(5, "dropped %zu of %zu packets of a revolution (last: %s)",
                            stats.decode.bad_packets, scan->packets.size(),
                            core::toString(stats.last_bad_status));
    }
    if (stats.tf_failures > 0) {
      NODELET_WARN_THROTTLE(5, "no transform for %zu of %zu packets (%s -> %s): %s",
                            stats.tf_failures, scan->packets.size(), scan->header.frame_id.c_str(),
                            converter_->outputFrame(scan->header.frame_id).c_str(),
                            tf_error.c_str());
    }
    if (!ok) return diagnostics.frame((ros::WallTime::now() - start).toSec());  // nothing placed
    pub_.publish(cloud);  // fresh, never touched again: zero copy inside the manager
    stage_.published(start);
  }

  PacketToCloudParams params_;
  std::unique_ptr<ScanToCloud> converter_;
  ros::Publisher pub_;
  LazyStage stage_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::PacketToCloudNodelet, nodelet::Nodelet)
