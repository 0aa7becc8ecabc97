/// \file stage_diagnostics.h
/// diagnostic_updater status of one nodelet of the pipeline, the same keys for every nodelet:
/// input rate, output rate, processing time per revolution, skipped revolutions, and named
/// counters of dropped or bad input. Every nodelet reports through this one class.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/node_handle.h>
#include <ros/timer.h>

namespace urban_detection {
namespace ros_conv {

/// Counts revolutions lost between two stages from the gaps in the header.seq numbers that the
/// sources (PacketSource, SimulatedSensor) give their revolutions and every stage passes on.
/// seq 0 (a driver that does not number its messages) is ignored; a smaller seq than the
/// previous one is a restarted source (a looped replay, a new drive), not a gap.
class SeqGapCounter {
 public:
  /// Returns the number of revolutions missing before `seq`.
  std::uint32_t add(std::uint32_t seq) {
    std::uint32_t gap = 0;
    if (seq != 0 && last_ != 0 && seq > last_ + 1) gap = seq - last_ - 1;
    if (seq != 0) last_ = seq;
    return gap;
  }
  /// Forgets the last seq: what passes while a lazy stage is unsubscribed is not lost.
  void reset() { last_ = 0; }

 private:
  std::uint32_t last_ = 0;
};

/// Publishes, once per second, a status named `task` for the nodelet `name`:
///   WARN  "skipped N revolutions": input revolutions were lost before this stage (its input
///         queue keeps only the newest; an upstream stage or the network dropped them);
///   WARN  "falling behind": the processing time exceeds `load_warn_fraction` of the wall time;
///   WARN  "<counter>: +N": a counter registered as a warning grew in the last second;
///   WARN  "output below the sensor rate": with setExpectedRate(), output < 0.8 x expected;
///   OK    "processing" / "idle (no subscriber)" / "waiting for input" otherwise.
/// Values: input and output rates [Hz], mean and max processing time per revolution [ms], busy
/// fraction, totals of inputs, outputs, skipped revolutions and of every counter.
/// Thread-safe: the counting calls come from callbacks and worker threads, the update from a
/// wall timer of the nodelet's callback queue.
class StageDiagnostics {
 public:
  /// `input_name` is the key of the input total ("packets" for a source).
  StageDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                   const std::string& task, const std::string& input_name = "inputs",
                   double load_warn_fraction = 0.9);

  /// One input message arrived (a packet for a source, a revolution for a stage). `seq` is its
  /// header.seq: gaps count as skipped revolutions (0 = not numbered).
  void input(std::uint32_t seq = 0);
  /// One revolution processed in `processing_s` seconds of wall time.
  void frame(double processing_s);
  /// One revolution published.
  void output();
  /// One revolution published `latency_s` after its header.stamp (with the sensor's stamp
  /// convention: after its last packet). Shown as p50 / p95 / max of the window in ms
  /// ("latency p50 [ms]" ...); a zero stamp (a ROS clock that does not run: use_sim_time
  /// without /clock) is counted as "zero_stamps" and turns the status to WARN.
  void latency(const ros::Time& stamp, const ros::Time& now);
  /// One input rejected (malformed); same as count("rejected inputs", 1, true).
  void rejected();
  /// Adds `n` to the named counter; a `warn` counter that grows turns the status to WARN.
  void count(const std::string& key, std::uint64_t n = 1, bool warn = true);
  /// Sets a counter that the caller keeps itself (a total, e.g. the kernel's drops).
  void setTotal(const std::string& key, std::uint64_t total, bool warn = true);
  /// Whether the stage currently has a subscriber (shown as idle otherwise).
  void setActive(bool active);
  /// Revolutions per second the sensor delivers (rpm / 60); 0 = not checked.
  void setExpectedRate(double hz);
  /// Shown in the status; for a source the sensor address or file.
  void setHardwareId(const std::string& id) { updater_->setHardwareID(id); }
  /// Status computed now, closing the current window (for tests and the timer).
  void update() { updater_->force_update(); }

 private:
  struct Counter {
    std::uint64_t total = 0, window = 0;
    bool warn = true;
  };
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer timer_;
  std::string input_name_;
  double load_warn_fraction_;
  std::mutex mutex_;
  bool active_ = true;
  double expected_hz_ = 0.0;
  ros::WallTime window_start_;
  SeqGapCounter gaps_;
  Counter inputs_, frames_, outputs_, skipped_;
  std::map<std::string, Counter> counters_;
  double window_sum_s_ = 0.0, window_max_s_ = 0.0;
  std::vector<double> window_latency_s_;
};

/// The /diagnostics entry of a nodelet that refused to start (a bad parameter, calibration or
/// model): ERROR with the refusal's text, the text of its FATAL log line, published once a
/// second while the nodelet is loaded, so monitoring sees it and not "waiting for input".
class RefusalDiagnostics {
 public:
  /// Logs `text` as FATAL (logger named after the nodelet `name`) and returns the entry that
  /// keeps it on /diagnostics: `refusal_ = RefusalDiagnostics::report(...)`.
  static std::unique_ptr<RefusalDiagnostics> report(ros::NodeHandle nh, ros::NodeHandle pnh,
                                                    const std::string& name,
                                                    const std::string& text);
  RefusalDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                     const std::string& text);

 private:
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer timer_;
  std::string text_;
};

}  // namespace ros_conv
}  // namespace urban_detection
