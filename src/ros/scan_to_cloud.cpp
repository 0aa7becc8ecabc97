#include "urban_detection/ros/scan_to_cloud.h"

#include <pcl_conversions/pcl_conversions.h>
#include <tf2_eigen/tf2_eigen.h>

namespace urban_detection {
namespace ros_conv {

ScanToCloud::ScanToCloud(const PacketToCloudParams& params, const ros::NodeHandle& nh)
    : params_(params), decoder_(core::loadCalibration(params.calibration), params.decoder) {
  if (!params_.fixed_frame.empty() || !params_.target_frame.empty()) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
  }
}

bool ScanToCloud::convert(const VelodyneScan& scan, CloudXYZIRT* cloud, ScanDecodeStats* stats,
                          std::string* tf_error) {
  // The scan's own stamp, as velodyne_pointcloud does: its driver chose first or last packet.
  const ros::Time stamp = scan.header.stamp;
  const std::string& sensor_frame = scan.header.frame_id;
  const std::string& frame = outputFrame(sensor_frame);
  // Without a fixed frame, each packet is transformed at its own time into the target frame
  // (the target frame's own motion is then ignored); with one, through it to the target frame
  // at the revolution start.
  const std::string& fixed = params_.fixed_frame.empty() ? frame : params_.fixed_frame;

  PacketTransformFn transform;
  Eigen::Affine3f first_transform = Eigen::Affine3f::Identity();
  bool have_first = false;
  if (tf_buffer_) {
    // Wait once for the newest transform this revolution needs; lookups then do not block.
    tf_buffer_->canTransform(frame, stamp, sensor_frame, scan.packets.back().stamp, fixed,
                             ros::Duration(params_.tf_timeout_s));
    transform = [&](const ros::Time& t, Eigen::Affine3f* out) {
      try {
        *out =
            tf2::transformToEigen(tf_buffer_->lookupTransform(frame, stamp, sensor_frame, t, fixed))
                .cast<float>();
      } catch (const tf2::TransformException& e) {
        *tf_error = e.what();
        return false;
      }
      if (!have_first) first_transform = *out, have_first = true;
      return true;
    };
  }
  decodeScan(decoder_, scan, transform, cloud, stats);
  if (stats->tf_failures == scan.packets.size()) return false;
  cloud->header.frame_id = frame;
  cloud->header.stamp = pcl_conversions::toPCL(stamp);
  cloud->header.seq = scan.header.seq;
  if (have_first) {  // pose of the sensor at the revolution start, in the output frame
    cloud->sensor_origin_ << first_transform.translation(), 0.0f;
    cloud->sensor_orientation_ = Eigen::Quaternionf(first_transform.rotation());
  }
  return true;
}

}  // namespace ros_conv
}  // namespace urban_detection
