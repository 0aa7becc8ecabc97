// urban_detection/PacketToCloud: `velodyne_packets` (urban_detection/VelodyneScan, or
// velodyne_msgs/VelodyneScan: same MD5) -> `velodyne_points` (CloudXYZIRT), calibrated, optionally
// transformed packet by packet at each packet's own timestamp (motion compensation).
// Lazy: subscribed to the packets only while someone listens to the points.
#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <pcl_conversions/pcl_conversions.h>
#include <pcl_ros/point_cloud.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <atomic>
#include <memory>
#include <mutex>

#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {

class PacketToCloud : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      params_ = loadPacketToCloudParams(getPrivateNodeHandle());
      decoder_ = std::make_unique<core::PacketDecoder>(core::loadCalibration(params_.calibration),
                                                       params_.decoder);
    } catch (const std::exception& e) {  // ParamError, core::CalibrationError
      NODELET_FATAL("PacketToCloud inactive: %s", e.what());
      return;
    }
    NODELET_INFO("PacketToCloud: calibration %s, range [%.2f, %.2f] m",
                 decoder_->calibration().source.c_str(), params_.decoder.min_range_m,
                 params_.decoder.max_range_m);
    if (!params_.fixed_frame.empty() || !params_.target_frame.empty()) {
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, getNodeHandle());
    }
    updater_ = std::make_unique<diagnostic_updater::Updater>(getNodeHandle(),
                                                             getPrivateNodeHandle(), getName());
    updater_->setHardwareID("none");
    updater_->add("decoding", this, &PacketToCloud::diagnose);
    diag_timer_ = getNodeHandle().createWallTimer(
        ros::WallDuration(0.5), [this](const ros::WallTimerEvent&) { updater_->update(); });

    std::lock_guard<std::mutex> lock(connect_mutex_);  // connectCb must see pub_ assigned
    auto connect_cb = [this](const ros::SingleSubscriberPublisher&) { connectCb(); };
    pub_ = getNodeHandle().advertise<CloudXYZIRT>("velodyne_points", params_.queue_size,
                                                  connect_cb, connect_cb);
  }

  void connectCb() {
    std::lock_guard<std::mutex> lock(connect_mutex_);
    if (pub_.getNumSubscribers() == 0) {
      sub_.shutdown();
      subscribed_ = false;
    } else if (!sub_) {
      subscribed_ = true;
      sub_ = getNodeHandle().subscribe("velodyne_packets", params_.queue_size,
                                       &PacketToCloud::scanCb, this,
                                       ros::TransportHints().tcpNoDelay());
    }
  }

  void scanCb(const VelodyneScan::ConstPtr& scan) {
    ++scans_;
    // PacketSource numbers its revolutions: a gap means the input queue dropped some (the
    // newest revolution wins when decoding falls behind). Other drivers may leave seq at 0.
    const std::uint32_t seq = scan->header.seq;
    if (last_seq_ != 0 && seq > last_seq_ + 1) {
      skipped_ += seq - last_seq_ - 1;
      NODELET_WARN_THROTTLE(5, "falling behind: %lu revolutions skipped so far",
                            static_cast<unsigned long>(skipped_));
    }
    last_seq_ = seq;
    if (scan->packets.empty()) {
      ++empty_scans_;
      NODELET_WARN_THROTTLE(10, "dropping empty VelodyneScan (%lu so far)",
                            static_cast<unsigned long>(empty_scans_));
      return;
    }
    const ros::Time stamp = scan->packets.front().stamp;
    const std::string& sensor_frame = scan->header.frame_id;
    const std::string& frame = params_.target_frame.empty() ? sensor_frame : params_.target_frame;

    PacketTransformFn transform;
    Eigen::Affine3f first_transform = Eigen::Affine3f::Identity();
    bool have_first = false;
    std::string tf_error;
    if (tf_buffer_) {
      // Wait once for the newest transform this revolution needs; lookups then do not block.
      tf_buffer_->canTransform(frame, stamp, sensor_frame, scan->packets.back().stamp,
                               fixedFrame(frame), ros::Duration(params_.tf_timeout_s));
      transform = [&](const ros::Time& t, Eigen::Affine3f* out) {
        try {
          *out = tf2::transformToEigen(
                     tf_buffer_->lookupTransform(frame, stamp, sensor_frame, t, fixedFrame(frame)))
                     .cast<float>();
        } catch (const tf2::TransformException& e) {
          tf_error = e.what();
          return false;
        }
        if (!have_first) first_transform = *out, have_first = true;
        return true;
      };
    }
    auto cloud = boost::make_shared<CloudXYZIRT>();
    ScanDecodeStats stats;
    decodeScan(*decoder_, *scan, transform, cloud.get(), &stats);
    bad_packets_ += stats.decode.bad_packets;
    tf_failures_ += stats.tf_failures;
    points_ += cloud->size();
    if (stats.decode.bad_packets > 0) {
      NODELET_WARN_THROTTLE(5, "dropped %zu of %zu packets of a revolution (last: %s); %lu so far",
                            stats.decode.bad_packets, scan->packets.size(),
                            core::toString(stats.last_bad_status),
                            static_cast<unsigned long>(bad_packets_));
    }
    if (stats.tf_failures > 0) {
      NODELET_WARN_THROTTLE(5, "no transform for %zu of %zu packets (%s -> %s): %s",
                            stats.tf_failures, scan->packets.size(), sensor_frame.c_str(),
                            frame.c_str(), tf_error.c_str());
      if (stats.tf_failures == scan->packets.size()) return;  // nothing to publish
    }
    cloud->header.frame_id = frame;
    cloud->header.stamp = pcl_conversions::toPCL(stamp);
    if (have_first) {  // pose of the sensor at the revolution start, in the output frame
      cloud->sensor_origin_ << first_transform.translation(), 0.0f;
      cloud->sensor_orientation_ = Eigen::Quaternionf(first_transform.rotation());
    }
    pub_.publish(cloud);  // fresh, never touched again: zero copy inside the manager
  }

  // Without a fixed frame, each packet is transformed at its own time into the target frame
  // (the target frame's own motion is then ignored); with one, through it to the target frame
  // at the revolution start.
  const std::string& fixedFrame(const std::string& target) const {
    return params_.fixed_frame.empty() ? target : params_.fixed_frame;
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    const std::uint64_t bad = bad_packets_ + tf_failures_ + empty_scans_ + skipped_;
    if (bad > reported_bad_) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "dropping packets or revolutions");
    } else {
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, subscribed_ ? "decoding" : "idle (lazy)");
    }
    reported_bad_ = bad;
    stat.add("revolutions", scans_.load());
    stat.add("points", points_.load());
    stat.add("bad_packets", bad_packets_.load());
    stat.add("tf_failures", tf_failures_.load());
    stat.add("empty_scans", empty_scans_.load());
    stat.add("skipped_revolutions", skipped_.load());
  }

  PacketToCloudParams params_;
  std::unique_ptr<core::PacketDecoder> decoder_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer diag_timer_;
  std::mutex connect_mutex_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
  std::atomic<bool> subscribed_{false};
  std::atomic<std::uint64_t> scans_{0}, points_{0}, bad_packets_{0}, tf_failures_{0},
      empty_scans_{0}, skipped_{0};
  std::uint32_t last_seq_ = 0;      // scanCb only (roscpp serialises a subscription's callbacks)
  std::uint64_t reported_bad_ = 0;  // diagnostics thread only
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::PacketToCloud, nodelet::Nodelet)
