#include "urban_detection/ros/stage_diagnostics.h"

#include <algorithm>

namespace urban_detection {
namespace ros_conv {

StageDiagnostics::StageDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                                   const std::string& task, const std::string& input_name,
                                   double load_warn_fraction)
    : updater_(new diagnostic_updater::Updater(nh, pnh, name)),
      input_name_(input_name),
      load_warn_fraction_(load_warn_fraction),
      last_input_(ros::WallTime::now()),
      window_start_(ros::WallTime::now()) {
  updater_->setHardwareID("none");
  updater_->add(task, this, &StageDiagnostics::diagnose);
  // Wall time: with use_sim_time and a paused bag the stage is idle, not stuck.
  timer_ = nh.createWallTimer(ros::WallDuration(1.0),
                              [this](const ros::WallTimerEvent&) { updater_->force_update(); });
}

void StageDiagnostics::input(std::uint32_t seq, const std::string& source) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++inputs_.total;
  ++inputs_.window;
  last_input_ = ros::WallTime::now();
  const std::uint32_t gap = gaps_.add(seq, source);
  skipped_.total += gap;
  skipped_.window += gap;
}

void StageDiagnostics::frame(double processing_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frames_.total;
  ++frames_.window;
  window_sum_s_ += processing_s;
  window_max_s_ = std::max(window_max_s_, processing_s);
}

void StageDiagnostics::output() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++outputs_.total;
  ++outputs_.window;
}

void StageDiagnostics::latency(const ros::Time& stamp, const ros::Time& now) {
  if (stamp.isZero()) {
    count("zero_stamps");
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  // Signed in nanoseconds: a stamp from the future (another clock) must not throw.
  const double s = 1e-9 * (static_cast<double>(now.toNSec()) - static_cast<double>(stamp.toNSec()));
  if (window_latency_s_.size() < 10000) window_latency_s_.push_back(s);
}

void StageDiagnostics::rejected() {
  count("rejected_inputs");
}

bool StageDiagnostics::refuse(const std::string& what) {
  return report("rejected_inputs", "refusing input: " + what, what.substr(0, what.find(':')), 1);
}

bool StageDiagnostics::error(const std::string& key, const std::string& text, std::uint64_t n) {
  return report(key, text, text.substr(0, text.find(':')), n);
}

bool StageDiagnostics::report(const std::string& key, const std::string& text,
                              const std::string& kind, std::uint64_t n) {
  count(key, n, false);
  std::lock_guard<std::mutex> lock(mutex_);
  window_error_ = text;
  window_errors_ += n;
  const ros::WallTime now = ros::WallTime::now();
  const auto it = logged_.find(key + '\n' + kind);
  if (it != logged_.end() && (now - it->second).toSec() < 5.0) return false;
  logged_[key + '\n' + kind] = now;
  return true;
}

void StageDiagnostics::setError(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  error_ = text;
}

void StageDiagnostics::count(const std::string& key, std::uint64_t n, bool warn) {
  std::lock_guard<std::mutex> lock(mutex_);
  Counter& c = counters_[key];
  c.total += n;
  c.window += n;
  c.warn = warn;
}

void StageDiagnostics::setTotal(const std::string& key, std::uint64_t total, bool warn) {
  std::lock_guard<std::mutex> lock(mutex_);
  Counter& c = counters_[key];
  if (total > c.total) c.window += total - c.total;
  c.total = total;
  c.warn = warn;
}

void StageDiagnostics::setActive(bool active) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Revolutions that passed while nobody listened (a lazy stage unsubscribed) were not skipped.
  if (active && !active_) {
    gaps_.reset();
    last_input_ = ros::WallTime::now();
  }
  active_ = active;
}

void StageDiagnostics::setInputTimeouts(double warn_s, double error_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  no_input_warn_s_ = warn_s;
  no_input_error_s_ = error_s;
}

void StageDiagnostics::setExpectedRate(double hz) {
  std::lock_guard<std::mutex> lock(mutex_);
  expected_hz_ = hz;
}

void StageDiagnostics::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const double open_s = (now - window_start_).toSec();
  // A timer call that follows a late one closely (roscpp catches up on a busy queue) would
  // compute rates over a few milliseconds ("skipped 138 revolutions in 0.0 s"): the previous
  // status stands and this window's counts go to the next one. A pending error is never held.
  if (have_status_ && open_s < kMinWindowS && window_errors_ == 0 && error_.empty()) {
    stat.summary(last_status_.level, last_status_.message);
    stat.values = last_status_.values;
    return;
  }
  const double window_s = std::max(open_s, 1e-3);
  const double input_hz = static_cast<double>(inputs_.window) / window_s;
  const double output_hz = static_cast<double>(outputs_.window) / window_s;
  const double mean_s =
      frames_.window > 0 ? window_sum_s_ / static_cast<double>(frames_.window) : 0.0;
  // Busy fraction of the wall time: above the threshold the input queue overflows.
  const double load = window_sum_s_ / window_s;
  const auto grown = std::find_if(counters_.begin(), counters_.end(), [](const auto& kv) {
    return kv.second.warn && kv.second.window > 0;
  });
  const double silent_s = (now - last_input_).toSec();
  if (!error_.empty()) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, error_);
  } else if (active_ && no_input_error_s_ > 0.0 && silent_s >= no_input_error_s_) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "no sensor data for %.0f s", silent_s);
  } else if (active_ && no_input_warn_s_ > 0.0 && silent_s >= no_input_warn_s_) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "no sensor data for %.0f s", silent_s);
  } else if (window_errors_ > 0) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "%s (%lu in %.1f s)",
                  window_error_.c_str(), static_cast<unsigned long>(window_errors_), window_s);
  } else if (best_effort_ && active_ && (frames_.window > 0 || skipped_.window > 0)) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK,
                  "best effort: %.1f Hz out of %.1f Hz in, newest revolution only (skipped %lu "
                  "in %.1f s)",
                  output_hz, input_hz + static_cast<double>(skipped_.window) / window_s,
                  static_cast<unsigned long>(skipped_.window), window_s);
  } else if (skipped_.window > 0) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "falling behind: skipped %lu revolutions in %.1f s (newest revolution wins)",
                  static_cast<unsigned long>(skipped_.window), window_s);
  } else if (frames_.window > 0 && load > load_warn_fraction_) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "falling behind: busy %.0f%% of the time (%.1f ms per revolution)", 100.0 * load,
                  1e3 * mean_s);
  } else if (grown != counters_.end()) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "dropping input: %s +%lu",
                  grown->first.c_str(), static_cast<unsigned long>(grown->second.window));
  } else if (active_ && expected_hz_ > 0.0 && inputs_.window > 0 &&
             output_hz < 0.8 * expected_hz_) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "output %.1f Hz below the sensor's %.1f Hz", output_hz, expected_hz_);
  } else if (active_ && expected_hz_ > 0.0 && window_s >= 0.5 && output_hz > 1.25 * expected_hz_) {
    // More revolutions than the sensor spins: revolutions cut in pieces (or rpm misconfigured).
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                  "output %.1f Hz above the sensor's %.1f Hz (revolutions cut in pieces?)",
                  output_hz, expected_hz_);
  } else if (!active_) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "idle (no subscriber)");
  } else if (inputs_.window == 0 && frames_.window == 0) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for input");
  } else {
    stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "processing");
  }
  stat.add("input rate [Hz]", input_hz);
  stat.add("output rate [Hz]", output_hz);
  if (expected_hz_ > 0.0) stat.add("expected rate [Hz]", expected_hz_);
  stat.add("mean processing time [ms]", 1e3 * mean_s);
  stat.add("max processing time [ms]", 1e3 * window_max_s_);
  stat.add("busy fraction", load);
  if (!window_latency_s_.empty()) {
    std::vector<double>& l = window_latency_s_;
    auto quantile = [&l](double q) {
      const std::size_t k = static_cast<std::size_t>(q * static_cast<double>(l.size() - 1) + 0.5);
      std::nth_element(l.begin(), l.begin() + static_cast<std::ptrdiff_t>(k), l.end());
      return l[k];
    };
    stat.add("latency p50 [ms]", 1e3 * quantile(0.5));
    stat.add("latency p95 [ms]", 1e3 * quantile(0.95));
    stat.add("latency p99 [ms]", 1e3 * quantile(0.99));
    stat.add("latency max [ms]", 1e3 * *std::max_element(l.begin(), l.end()));
    l.clear();
  }
  stat.add(input_name_, inputs_.total);
  stat.add("revolutions", frames_.total);
  stat.add("outputs", outputs_.total);
  stat.add("skipped_revolutions", skipped_.total);
  if (best_effort_) stat.add("best_effort", "true (spare CPU, newest revolution only)");
  for (auto& kv : counters_) {
    stat.add(kv.first, kv.second.total);
    kv.second.window = 0;
  }
  last_status_ = stat;
  have_status_ = true;
  window_start_ = now;
  inputs_.window = frames_.window = outputs_.window = skipped_.window = 0;
  window_sum_s_ = window_max_s_ = 0.0;
  window_errors_ = 0;
}

std::unique_ptr<RefusalDiagnostics> RefusalDiagnostics::report(ros::NodeHandle nh,
                                                               ros::NodeHandle pnh,
                                                               const std::string& name,
                                                               const std::string& text) {
  ROS_FATAL_STREAM_NAMED(name, text);
  return std::make_unique<RefusalDiagnostics>(nh, pnh, name, text);
}

RefusalDiagnostics::RefusalDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh,
                                       const std::string& name, const std::string& text)
    : updater_(new diagnostic_updater::Updater(nh, pnh, name)), text_(text) {
  updater_->setHardwareID("none");
  updater_->add("refused", [this](diagnostic_updater::DiagnosticStatusWrapper& stat) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, text_);
  });
  timer_ = nh.createWallTimer(ros::WallDuration(1.0),
                              [this](const ros::WallTimerEvent&) { updater_->force_update(); });
  updater_->force_update();
}

}  // namespace ros_conv
}  // namespace urban_detection
