// urban_detection/SimulatedSensor: a virtual HDL-64E driving through the procedural street of
// a YAML drive description. Publishes velodyne_packets (one VelodyneScan per revolution),
// ground_truth (per-point labels in decoder order) and tf odom -> base_link -> velodyne.
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/core/simulation/simulation_config.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/simulation_conversions.h"
#include "urban_detection/ros/stage_diagnostics.h"

namespace urban_detection {
namespace ros_conv {

class SimulatedSensorNodelet : public nodelet::Nodelet {
 public:
  ~SimulatedSensorNodelet() override {
    running_ = false;
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override {
    if (!loadParams()) return;
    ros::NodeHandle& nh = getNodeHandle();
    scan_pub_ = nh.advertise<VelodyneScan>("velodyne_packets", 4);
    gt_pub_ = nh.advertise<GroundTruth>("ground_truth", 4);
    tf_.reset(new tf2_ros::TransformBroadcaster());
    static_tf_.reset(new tf2_ros::StaticTransformBroadcaster());
    diagnostics_.reset(new ros_conv::StageDiagnostics(nh, getPrivateNodeHandle(), getName(),
                                                      "simulation", "revolutions_simulated"));
    diagnostics_->setHardwareId("simulated HDL-64E");
    if (params_.realtime)
      diagnostics_->setExpectedRate(config_.sensor.rpm / 60.0 * params_.rate_factor);
    running_ = true;
    worker_ = std::thread(&SimulatedSensorNodelet::run, this);
  }

  bool loadParams() {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    try {  // type-checked: a wrong type is refused, never replaced by the default
      loadFields(pnh, &params_);
    } catch (const ParamError& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "SimulatedSensor: " + std::string(e.what()) + "; the nodelet stays idle");
      return false;
    }
    const std::string& config_path = params_.config;
    if (config_path.empty()) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "SimulatedSensor: parameter ~config (path of a drive YAML such as "
          "config/demo_drive.yaml) is required; the nodelet stays idle");
      return false;
    }
    stamp_ = params_.timestamp_first_packet ? ScanStamp::kFirstPacket : ScanStamp::kLastPacket;
    frames_.sensor = params_.frame_id;
    frames_.odom = params_.odom_frame;
    frames_.base_link = params_.base_frame;
    try {
      config_ = core::loadSimulationConfig(config_path);
      calibration_ = core::loadCalibration(config_.calibration_file);
    } catch (const std::exception& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "SimulatedSensor: " + std::string(e.what()) + "; the nodelet stays idle");
      return false;
    }
    return true;
  }

  void run() {
    core::SimRevolution rev;
    while (running_ && ros::ok()) {
      // Stamps follow the ROS clock: the drive starts "now" and restarts "now" when looping.
      core::SimulationConfig c = config_;
      c.sensor.start_stamp_s = ros::Time::now().toSec();
      core::LidarSimulator sim(core::generateScene(c.scene, c.drive), c.scene, c.drive,
                               calibration_, c.sensor);
      NODELET_INFO("SimulatedSensor: driving %.0f m at %.1f m/s, %zu objects, %.0f rpm",
                   c.drive.length(), c.drive.speed_mps, sim.scene().objects.size(), c.sensor.rpm);
      const ros::WallTime wall0 = ros::WallTime::now();
      bool first = true;
      while (running_ && ros::ok() && !sim.driveFinished()) {
        const ros::WallTime start = ros::WallTime::now();
        sim.simulateNext(&rev);
        diagnostics_->input();
        diagnostics_->frame((ros::WallTime::now() - start).toSec());
        const double rev_s = 60.0 / c.sensor.rpm;
        if (params_.realtime) {  // publish when the revolution's last packet would have arrived
          const ros::WallTime due =
              wall0 + ros::WallDuration((rev.start_time_s + rev_s) / params_.rate_factor);
          const ros::WallDuration wait = due - ros::WallTime::now();
          if (wait > ros::WallDuration(0.0)) wait.sleep();
          if (wait < ros::WallDuration(-rev_s / params_.rate_factor)) {  // the machine is too slow
            diagnostics_->count("late_revolutions");
          }
        }
        if (params_.publish_tf) publishTf(sim, rev, rev_s, first);
        first = false;
        auto scan = boost::make_shared<VelodyneScan>();
        ros_conv::toScanMsg(rev, frames_.sensor, scan.get(), stamp_);
        scan->header.seq = ++revolutions_;  // numbered: consumers count what they never got
        scan_pub_.publish(boost::shared_ptr<const VelodyneScan>(scan));
        diagnostics_->output();
        if (gt_pub_.getNumSubscribers() > 0) {
          auto gt = boost::make_shared<GroundTruth>();
          ros_conv::toGroundTruthMsg(rev, frames_.sensor, gt.get(), stamp_);
          gt_pub_.publish(boost::shared_ptr<const GroundTruth>(gt));
        }
        if (!params_.realtime && rev.stats.returns == 0) {
          NODELET_WARN_THROTTLE(5.0, "SimulatedSensor: a revolution without any return");
        }
      }
      if (!params_.loop) break;
    }
  }

  void publishTf(const core::LidarSimulator& sim, const core::SimRevolution& rev, double rev_s,
                 bool first) {
    geometry_msgs::TransformStamped odom_base, base_sensor;
    if (first) {
      ros_conv::toTransforms(sim, rev.start_time_s, rev.stamp_s, frames_, &odom_base, &base_sensor);
      static_tf_->sendTransform(base_sensor);
      tf_->sendTransform(odom_base);
    }
    // The pose at the revolution's end: every packet stamp is bracketed by two samples.
    ros_conv::toTransforms(sim, rev.start_time_s + rev_s, rev.stamp_s + rev_s, frames_, &odom_base,
                           &base_sensor);
    tf_->sendTransform(odom_base);
  }

  core::SimulationConfig config_;
  core::Calibration calibration_;
  ros_conv::SimulationFrames frames_;
  SimulatedSensorParams params_;
  ScanStamp stamp_ = ScanStamp::kLastPacket;  // header.stamp of scans and ground truth
  ros::Publisher scan_pub_, gt_pub_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_tf_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  std::uint32_t revolutions_ = 0;  // published so far (header.seq), worker thread only
  std::atomic<bool> running_{false};
  std::thread worker_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::SimulatedSensorNodelet, nodelet::Nodelet)
