/// \file scan_to_cloud.h
/// The conversion of the PacketToCloud nodelet: one VelodyneScan -> one calibrated CloudXYZIRT,
/// optionally transformed packet by packet at each packet's own stamp through tf2 (motion
/// compensation) into the target frame at the scan's stamp, with the sensor pose at the
/// revolution start in the cloud's sensor_origin_.
#pragma once

#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <memory>
#include <string>

#include <ros/node_handle.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {
namespace ros_conv {

class ScanToCloud {
 public:
  /// Loads the calibration (throws core::CalibrationError naming the file, laser and field);
  /// listens to tf on `nh` only when a fixed or target frame is set.
  ScanToCloud(const PacketToCloudParams& params, const ros::NodeHandle& nh);

  /// Decodes `scan` (not empty) into `cloud` with header stamp = the scan's header.stamp (its
  /// driver's convention: velodyne_driver and PacketSource stamp the last packet unless
  /// timestamp_first_packet is true) and
  /// header.seq = the scan's seq (so later stages can count revolutions they never received).
  /// Returns false when no packet had a transform (nothing to publish); `tf_error` then holds
  /// the last tf2 error.
  bool convert(const VelodyneScan& scan, CloudXYZIRT* cloud, ScanDecodeStats* stats,
               std::string* tf_error);

  const core::PacketDecoder& decoder() const { return decoder_; }
  /// The frame the clouds of a scan in `sensor_frame` are published in.
  const std::string& outputFrame(const std::string& sensor_frame) const {
    return params_.target_frame.empty() ? sensor_frame : params_.target_frame;
  }

 private:
  PacketToCloudParams params_;
  core::PacketDecoder decoder_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
};

}  // namespace ros_conv
}  // namespace urban_detection
