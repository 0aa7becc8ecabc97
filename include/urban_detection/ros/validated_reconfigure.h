/// \file validated_reconfigure.h
/// A dynamic_reconfigure server whose updates are validated before they take effect.
///
/// dynamic_reconfigure clamps each value to the range declared in the .cfg file (the same range
/// the start-up loader accepts, shown as the slider range in rqt_reconfigure) before any callback
/// runs. Combinations that the core rejects (core::validate(), e.g. min_cluster_size >
/// max_cluster_size) are then rejected here: the error names the parameters and the accepted
/// range, is logged, and the previous configuration stays in force and is what the service
/// answers (so `dynparam set` and rqt show the values actually used).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <boost/thread/recursive_mutex.hpp>
#include <dynamic_reconfigure/server.h>
#include <ros/console.h>
#include <ros/node_handle.h>

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
    ROS_ERROR("%s: dynamic_reconfigure update rejected, previous values kept: %s",
              owner_.c_str(), error.c_str());
    config = applied_;  // the server stores and answers with what is really in force
  }

  boost::recursive_mutex mutex_;
  dynamic_reconfigure::Server<Config> server_;
  Config applied_;
  ApplyFn apply_;
  std::string owner_;
  bool first_ = true;
  std::uint64_t rejected_ = 0;
};

}  // namespace ros_conv
}  // namespace urban_detection
