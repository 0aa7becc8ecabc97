/// \file stage_diagnostics.h
/// diagnostic_updater status of one processing stage of the pipeline (a nodelet that turns one
/// input message per revolution into outputs): input rate, processing time per revolution and
/// whether the stage keeps up with its input. Shared by the stage nodelets so that every stage
/// reports the same keys on /diagnostics.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/node_handle.h>
#include <ros/timer.h>

namespace urban_detection {
namespace ros_conv {

/// Publishes, once per second, a status named `task` for the nodelet `name`:
///   OK    "processing" / "idle (no subscriber)" / "waiting for input";
///   WARN  when the mean processing time over the last second exceeds `load_warn_fraction`
///         of the mean input period (the stage falls behind the sensor and its input queue
///         drops revolutions), or when frames were rejected (bad input) in the last second.
/// Values: input rate [Hz], mean and max processing time [ms], totals of frames and rejects.
/// Thread-safe: frame()/rejected() are called from the stage's callback, update() from a timer.
class StageDiagnostics {
 public:
  StageDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                   const std::string& task, double load_warn_fraction = 0.9);

  /// One input processed in `processing_s` seconds of wall time.
  void frame(double processing_s);
  /// One input rejected (e.g. malformed cloud).
  void rejected();
  /// Whether the stage currently has a subscriber (shown as idle otherwise).
  void setActive(bool active);

 private:
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer timer_;
  double load_warn_fraction_;
  std::mutex mutex_;
  bool active_ = false;
  ros::WallTime window_start_;
  std::uint64_t frames_total_ = 0, rejected_total_ = 0;
  std::uint64_t window_frames_ = 0, window_rejected_ = 0;
  double window_sum_s_ = 0.0, window_max_s_ = 0.0;
};

}  // namespace ros_conv
}  // namespace urban_detection
