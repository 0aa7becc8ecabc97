/// \file lazy_outputs.h
/// The lazy-nodelet pattern, written once: a stage subscribes to its input only while one of
/// its outputs has a subscriber (the chain costs nothing until someone listens), and its
/// diagnostics say "idle" meanwhile.
#pragma once

#include <ros/ros.h>

#include <functional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace urban_detection {
namespace ros_conv {

class LazyOutputs {
 public:
  /// `on_change(true)` when the first output gains a subscriber (subscribe the input there),
  /// `on_change(false)` when the last one loses it (shut the input down). Called from roscpp's
  /// connection callbacks, one at a time.
  explicit LazyOutputs(std::function<void(bool wanted)> on_change)
      : on_change_(std::move(on_change)) {}

  /// Advertises an output whose subscribers count.
  template <class M>
  ros::Publisher advertise(ros::NodeHandle& nh, const std::string& topic, std::uint32_t queue) {
    ros::SubscriberStatusCallback update = [this](const ros::SingleSubscriberPublisher&) {
      this->update();
    };
    std::lock_guard<std::mutex> lock(mutex_);  // update() must see the publisher stored
    outputs_.push_back(nh.advertise<M>(topic, queue, update, update));
    return outputs_.back();
  }

 private:
  void update() {
    std::lock_guard<std::mutex> lock(mutex_);
    bool wanted = false;
    for (const ros::Publisher& p : outputs_) wanted = wanted || p.getNumSubscribers() > 0;
    if (wanted == wanted_) return;
    wanted_ = wanted;
    on_change_(wanted);
  }

  std::function<void(bool)> on_change_;
  std::mutex mutex_;
  std::vector<ros::Publisher> outputs_;
  bool wanted_ = false;
};

}  // namespace ros_conv
}  // namespace urban_detection
