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

/// [s] the first stage of a live chain without sensor data this long: WARN, then ERROR.
constexpr double kNoSensorDataWarnS = 1.0;
constexpr double kNoSensorDataErrorS = 5.0;

/// Counts revolutions lost between two stages from the gaps in the header.seq numbers that the
/// sources (PacketSource, SimulatedSensor) give their revolutions and every stage passes on.
/// seq 0 (a driver that does not number its messages) is ignored; a smaller seq than the
/// previous one is a restarted source (a looped replay, a new drive), not a gap. Each publisher
/// (`source`: its caller id) has a numbering of its own: two drivers on one topic interleave
/// two sequences whose differences are no lost revolutions.
class SeqGapCounter {
 public:
  /// Returns the number of revolutions missing before `seq` of `source`.
  std::uint32_t add(std::uint32_t seq, const std::string& source = std::string()) {
    std::uint32_t& last = last_[source];
    std::uint32_t gap = 0;
    if (seq != 0 && last != 0 && seq > last + 1) gap = seq - last - 1;
    if (seq != 0) last = seq;
    return gap;
  }
  /// Forgets the last seqs: what passes while a lazy stage is unsubscribed is not lost.
  void reset() { last_.clear(); }

 private:
  std::map<std::string, std::uint32_t> last_;
};

/// Publishes, once per second, a status named `task` for the nodelet `name`:
///   ERROR "<text>" while setError() holds a text; ERROR "refusing input: ..." / "<text>" in a
///         second when refuse() / error() was called (a stage that logs an ERROR is never OK
///         on /diagnostics);
///   WARN  "skipped N revolutions": input revolutions were lost before this stage (its input
///         queue keeps only the newest; an upstream stage or the network dropped them);
///   WARN  "falling behind": the processing time exceeds `load_warn_fraction` of the wall time;
///   WARN  "<counter>: +N": a counter registered as a warning grew in the last second;
///   WARN  "output below the sensor rate": with setExpectedRate(), output < 0.8 x expected;
///   WARN / ERROR "no sensor data for N s": with setInputTimeouts();
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
  /// header.seq: gaps count as skipped revolutions (0 = not numbered), per publisher `source`.
  void input(std::uint32_t seq = 0, const std::string& source = std::string());
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
  /// One input refused as malformed, `what` saying why (its kind first, up to a ':'): counted
  /// as "rejected_inputs"; the status is ERROR "refusing input: <what>" for the window it
  /// happened in. Returns whether the caller should log it now: the first of its kind since
  /// the last one logged, or 5 s after that one (one throttled ERROR per kind).
  bool refuse(const std::string& what);
  /// The same for any fault the stage logs as ERROR: adds `n` to the counter `key` and turns
  /// the status ERROR with `text` for the window; returns whether to log it now (per `key`
  /// and kind of `text`, up to its first ':').
  bool error(const std::string& key, const std::string& text, std::uint64_t n = 1);
  /// A lasting fault the stage logged as ERROR (the status stays ERROR with `text` until
  /// cleared with ""): a replay that stopped, a capture with no packet for the port.
  void setError(const std::string& text);
  /// Adds `n` to the named counter; a `warn` counter that grows turns the status to WARN.
  void count(const std::string& key, std::uint64_t n = 1, bool warn = true);
  /// Sets a counter that the caller keeps itself (a total, e.g. the kernel's drops).
  void setTotal(const std::string& key, std::uint64_t total, bool warn = true);
  /// Whether the stage currently has a subscriber (shown as idle otherwise).
  void setActive(bool active);
  /// Revolutions per second the sensor delivers (rpm / 60); 0 = not checked.
  void setExpectedRate(double hz);
  /// A best-effort stage (a baseline on spare CPU, the newest revolution only): skipped
  /// revolutions and a rate below the sensor's are its normal state, so the status stays OK
  /// and says so, with its output rate, instead of "falling behind".
  void setBestEffort(bool on) { best_effort_ = on; }
  /// For the stage that takes the sensor's data: while active and no input came for `warn_s`
  /// seconds the status is WARN "no sensor data for N s", after `error_s` ERROR (0: off).
  void setInputTimeouts(double warn_s, double error_s);
  /// Shown in the status; for a source the sensor address or file.
  void setHardwareId(const std::string& id) { updater_->setHardwareID(id); }
  /// Status computed now, closing the current window (for tests and the timer); a window
  /// younger than half a second keeps the previous status unless an error is pending.
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
  bool best_effort_ = false;
  double expected_hz_ = 0.0;
  double no_input_warn_s_ = 0.0, no_input_error_s_ = 0.0;
  ros::WallTime last_input_;  // or when the stage became active
  ros::WallTime window_start_;
  static constexpr double kMinWindowS = 0.5;  // shorter windows keep the previous status
  diagnostic_msgs::DiagnosticStatus last_status_;
  bool have_status_ = false;
  SeqGapCounter gaps_;
  Counter inputs_, frames_, outputs_, skipped_;
  std::map<std::string, Counter> counters_;
  double window_sum_s_ = 0.0, window_max_s_ = 0.0;
  std::vector<double> window_latency_s_;
  std::string error_;  // setError()
  bool report(const std::string& key, const std::string& text, const std::string& kind,
              std::uint64_t n);
  std::string window_error_;  // last refuse() / error() text of the window
  std::uint64_t window_errors_ = 0;
  std::map<std::string, ros::WallTime> logged_;  // kind of fault -> when last logged
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
