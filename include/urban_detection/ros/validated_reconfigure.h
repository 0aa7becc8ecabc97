/// \file validated_reconfigure.h
/// A dynamic_reconfigure server whose updates are validated before they take effect.
///
/// dynamic_reconfigure would clamp each value to a range declared in the .cfg file before any
/// callback runs, silently changing what the user asked for. The .cfg files therefore declare
/// no ranges: every value reaches the `apply` function, which checks the complete set with the
/// start-up loader's own checks (ParamTable ranges, core::validate() cross-field conditions) and
/// refuses it as a whole when one value is out of range or a combination is invalid. A refused
/// set is logged as an error naming the parameter and the accepted range (the same message is
/// repeated at most every 5 s), the previous configuration stays in force, and it is what the
/// service answers and what ~parameter_updates publishes (so `dynparam set` and rqt_reconfigure
/// show the values actually used).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <boost/thread/recursive_mutex.hpp>
#include <dynamic_reconfigure/server.h>
#include <ros/console.h>
#include <ros/node_handle.h>
#include <ros/time.h>

namespace urban_detection {
namespace ros_conv {

template <class Config>
class ValidatedReconfigure {
 public:
  /// Returns "" when `config` was applied, else why it was rejected (nothing changed then).
  using ApplyFn = std::function<std::string(const Config& config)>;

  /// Serves on `nh` (the nodelet's private namespace or a sub-namespace), starting from
  /// `initial` (the loaded parameters, already applied: they are not applied again).
  ValidatedReconfigure(const ros::NodeHandle& nh, const Config& initial, ApplyFn apply)
      : server_(mutex_, nh), applied_(initial), apply_(std::move(apply)), owner_(nh.getNamespace()) {
    {
      boost::recursive_mutex::scoped_lock lock(mutex_);
      server_.updateConfig(initial);
    }
    server_.setCallback([this](Config& config, std::uint32_t) { callback(config); });
  }

  /// Rejected updates so far (for diagnostics and tests).
  std::uint64_t rejected() const { return rejected_; }

 private:
  void callback(Config& config) {
    if (first_) {  // setCallback() calls back at once with the initial values: already applied
      first_ = false;
      return;
    }
    const std::string error = apply_(config);
    if (error.empty()) {
      applied_ = config;
      return;
    }
    ++rejected_;
    const ros::WallTime now = ros::WallTime::now();
    if (error != last_error_ || (now - last_error_time_).toSec() >= kRepeatPeriodS) {
      ROS_ERROR("%s: dynamic_reconfigure update rejected, previous values kept: %s", owner_.c_str(),
                error.c_str());
      last_error_ = error;
      last_error_time_ = now;
    }
    config = applied_;  // the server stores, answers and publishes what is really in force
  }

  static constexpr double kRepeatPeriodS = 5.0;  // [s] an identical error is logged once per

  boost::recursive_mutex mutex_;
  dynamic_reconfigure::Server<Config> server_;
  Config applied_;
  ApplyFn apply_;
  std::string owner_;
  bool first_ = true;
  std::uint64_t rejected_ = 0;
  std::string last_error_;
  ros::WallTime last_error_time_;
};

}  // namespace ros_conv
}  // namespace urban_detection
