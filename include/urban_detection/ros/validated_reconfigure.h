/// \file validated_reconfigure.h
/// A dynamic_reconfigure server whose updates are validated before they take effect, and whose
/// refusals reach the caller.
///
/// dynamic_reconfigure would clamp each value to a range declared in the .cfg file before any
/// callback runs, silently changing what the user asked for. The .cfg files therefore declare
/// no ranges: every value reaches the `apply` function, which checks the complete set with the
/// start-up loader's own checks (checkFields(): the field table's ranges, validate()'s
/// cross-field conditions) and refuses it as a whole when one value is out of range or a
/// combination is invalid.
///
/// A refused set fails the `~set_parameters` call with the reason (naming the parameter and the
/// accepted range, outOfRangeMessage()'s wording), so `dynparam set`, `rosservice call` and
/// rqt_reconfigure show it and exit non-zero; roscpp also logs it as an error. The previous
/// configuration stays in force and is republished on ~parameter_updates (so rqt_reconfigure
/// snaps back to the values actually used).
///
/// Why not dynamic_reconfigure::Server: its service callback swallows every exception of the
/// user callback and always answers success, so a refusal could only be logged. This class
/// speaks the same protocol (~set_parameters, latched ~parameter_descriptions and
/// ~parameter_updates, the values mirrored on the parameter server) with the generated
/// Config's own (de)serialisation, and throws from the service callback: roscpp sends the
/// exception's text back as the service error.
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>

#include <dynamic_reconfigure/Config.h>
#include <dynamic_reconfigure/ConfigDescription.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ros/node_handle.h>

namespace urban_detection {
namespace ros_conv {

/// The error a refused update is served with (the caller sees its what()).
class ReconfigureRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <class Config>
class ValidatedReconfigure {
 public:
  /// Returns "" when `config` was applied, else why it was rejected (nothing changed then).
  using ApplyFn = std::function<std::string(const Config& config)>;

  /// Serves on `nh` (the nodelet's private namespace or a sub-namespace), starting from
  /// `initial` (the loaded parameters, already applied: they are not applied again).
  ValidatedReconfigure(const ros::NodeHandle& nh, const Config& initial, ApplyFn apply)
      : nh_(nh), applied_(initial), apply_(std::move(apply)) {
    std::lock_guard<std::mutex> lock(mutex_);
    descriptions_pub_ =
        nh_.advertise<dynamic_reconfigure::ConfigDescription>("parameter_descriptions", 1, true);
    descriptions_pub_.publish(Config::__getDescriptionMessage__());
    updates_pub_ = nh_.advertise<dynamic_reconfigure::Config>("parameter_updates", 1, true);
    publish();
    service_ = nh_.advertiseService("set_parameters", &ValidatedReconfigure::set, this);
  }

  /// Rejected updates so far (for diagnostics and tests).
  std::uint64_t rejected() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return rejected_;
  }

  /// The message a refused update is served with: the stage's namespace and `error`.
  static std::string refusal(const std::string& ns, const std::string& error) {
    return ns + ": dynamic_reconfigure update refused, previous values kept: " + error;
  }

 private:
  bool set(dynamic_reconfigure::Reconfigure::Request& req,
           dynamic_reconfigure::Reconfigure::Response& res) {
    std::lock_guard<std::mutex> lock(mutex_);
    Config config = applied_;  // parameters absent from the request keep their value
    config.__fromMessage__(req.config);
    config.__clamp__();  // the .cfg files declare no ranges: only the types' own limits
    const std::string error = apply_(config);
    if (!error.empty()) {
      ++rejected_;
      publish();  // GUIs that showed the requested value show the one in force again
      throw ReconfigureRefused(refusal(nh_.getNamespace(), error));
    }
    applied_ = config;
    publish();
    applied_.__toMessage__(res.config);
    return true;
  }

  // Mirrors the values in force on the parameter server and ~parameter_updates.
  void publish() {
    applied_.__toServer__(nh_);
    dynamic_reconfigure::Config msg;
    applied_.__toMessage__(msg);
    updates_pub_.publish(msg);
  }

  mutable std::mutex mutex_;  // one update at a time (service calls may run in parallel)
  ros::NodeHandle nh_;
  Config applied_;
  ApplyFn apply_;
  ros::Publisher descriptions_pub_, updates_pub_;
  ros::ServiceServer service_;
  std::uint64_t rejected_ = 0;
};

}  // namespace ros_conv
}  // namespace urban_detection
