#include "urban_detection/ros/stage_diagnostics.h"

#include <algorithm>

namespace urban_detection {
namespace ros_conv {

StageDiagnostics::StageDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh,
                                   const std::string& name, const std::string& task,
                                   double load_warn_fraction)
    : updater_(new diagnostic_updater::Updater(nh, pnh, name)),
      load_warn_fraction_(load_warn_fraction),
      window_start_(ros::WallTime::now()) {
  updater_->setHardwareID("none");
  updater_->add(task, this, &StageDiagnostics::diagnose);
  // Wall time: with use_sim_time and a paused bag the stage is idle, not stuck.
  timer_ = nh.createWallTimer(ros::WallDuration(1.0),
                              [this](const ros::WallTimerEvent&) { updater_->force_update(); });
}

void StageDiagnostics::frame(double processing_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frames_total_;
  ++window_frames_;
  window_sum_s_ += processing_s;
  window_max_s_ = std::max(window_max_s_, processing_s);
}

void StageDiagnostics::rejected() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++rejected_total_;
  ++window_rejected_;
}

void StageDiagnostics::setActive(bool active) {
  std::lock_guard<std::mutex> lock(mutex_);
  active_ = active;
}

void StageDiagnostics::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const double window_s = std::max((now - window_start_).toSec(), 1e-3);
  const double rate_hz = static_cast<double>(window_frames_) / window_s;
  const double mean_s = window_frames_ > 0 ? window_sum_s_ / static_cast<double>(window_frames_)
                                           : 0.0;
  // Busy fraction of the wall time: above the threshold the input queue overflows.
  const double load = window_sum_s_ / window_s;
  if (window_rejected_ > 0) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "rejecting malformed input");
  } else if (window_frames_ > 0 && load > load_warn_fraction_) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "falling behind: busy %.0f%% of the time (%.1f ms per frame at %.1f Hz)",
                  100.0 * load, 1e3 * mean_s, rate_hz);
  } else if (!active_) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "idle (no subscriber)");
  } else if (window_frames_ == 0) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for input");
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "processing");
  }
  stat.add("input rate [Hz]", rate_hz);
  stat.add("mean processing time [ms]", 1e3 * mean_s);
  stat.add("max processing time [ms]", 1e3 * window_max_s_);
  stat.add("busy fraction", load);
  stat.add("frames", frames_total_);
  stat.add("rejected frames", rejected_total_);
  window_start_ = now;
  window_frames_ = window_rejected_ = 0;
  window_sum_s_ = window_max_s_ = 0.0;
}

}  // namespace ros_conv
}  // namespace urban_detection
