/// \file lazy_stage.h
/// The skeleton of a lazy one-input stage nodelet, written once: the refusal at start-up, the
/// stage's diagnostics (idle until an output is wanted), the lazy subscription of its input and
/// the bookkeeping after each message. A nodelet holds one, declared after the members its
/// callback uses (so that the subscription goes first when the nodelet is unloaded):
///
///   onInit:   if (!stage_.load(nh, pnh, getName(), "Name", &params_)) return;  (or, on any
///             other start-up fault, stage_.refuse(nh, pnh, getName(), "Name: ..."); return;)
///             stage_.start(nh, pnh, getName(), "task", [this] {
///                                   return nh.subscribe("in", queue, &Nodelet::cb, this); });
///                                 pub_ = stage_.advertise<M>(nh, "out", queue);
///   callback: stage_.diagnostics().input(msg->header.seq); ... publish ...;
///             stage_.published(start, msg->header.stamp);
#pragma once

#include <ros/ros.h>

#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"

namespace urban_detection {
namespace ros_conv {

class LazyStage {
 public:
  /// Refuses to start: `text` logged FATAL and kept on /diagnostics; the nodelet stays idle.
  void refuse(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
              const std::string& text) {
    refusal_ = RefusalDiagnostics::report(nh, pnh, name, text);
  }

  /// Loads `params` (field-tabled) from `pnh`; on a bad parameter refuses to start ("<label>:
  /// <why>; the nodelet stays idle") and returns false.
  template <class Params>
  bool load(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
            const std::string& label, Params* params) {
    try {
      loadFields(pnh, params);
      return true;
    } catch (const ParamError& e) {
      refuse(nh, pnh, name, label + ": " + e.what() + "; the nodelet stays idle");
      return false;
    }
  }

  /// Creates the diagnostics (task `task`, input total `input_name`), idle until one of the
  /// outputs advertised through advertise() gains a subscriber; then `subscribe()` makes the
  /// input subscription, shut down again when the last subscriber leaves.
  StageDiagnostics& start(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name,
                          const std::string& task, std::function<ros::Subscriber()> subscribe,
                          const std::string& input_name = "inputs") {
    diagnostics_ = std::make_unique<StageDiagnostics>(nh, pnh, name, task, input_name);
    diagnostics_->setActive(false);
    subscribe_ = std::move(subscribe);
    lazy_ = std::make_unique<LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) return sub_.shutdown();
      sub_ = subscribe_();
    });
    return *diagnostics_;
  }

  /// An output whose subscribers switch the input on (after start()).
  template <class M>
  ros::Publisher advertise(ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue) {
    return lazy_->advertise<M>(nh, topic, queue);
  }

  StageDiagnostics& diagnostics() { return *diagnostics_; }

  /// One message processed since `start` (wall time) and published.
  void published(const ros::WallTime& start) {
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
    diagnostics_->output();
  }
  /// The same, and its latency from `stamp` (the sensor's stamp convention) to now.
  void published(const ros::WallTime& start, const ros::Time& stamp) {
    diagnostics_->latency(stamp, ros::Time::now());
    published(start);
  }

 private:
  std::unique_ptr<StageDiagnostics> diagnostics_;
  std::unique_ptr<RefusalDiagnostics> refusal_;  // set when it refused to start
  std::function<ros::Subscriber()> subscribe_;
  std::unique_ptr<LazyOutputs> lazy_;
  ros::Subscriber sub_;  // destroyed first
};

}  // namespace ros_conv
}  // namespace urban_detection
