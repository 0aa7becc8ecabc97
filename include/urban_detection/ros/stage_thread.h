/// \file stage_thread.h
/// A nodelet stage's own callback thread. The nodelet manager's worker threads are shared by
/// every nodelet it holds, and a queue waits behind whatever runs on the thread it was given:
/// a slow stage (the kd-tree baseline takes seconds per revolution) would hold up the live
/// chain's stages and the markers. A stage that serves its subscriptions from a StageThread
/// runs its callbacks on one thread of its own, in arrival order, and never waits for another
/// stage's callback (nor makes another wait). Zero copy is unaffected: the callback queue only
/// decides which thread runs the callback, the message pointer is the publisher's.
#pragma once

#include <memory>
#include <string>

#include <ros/callback_queue.h>
#include <ros/node_handle.h>
#include <ros/spinner.h>

namespace urban_detection {
namespace ros_conv {

class StageThread {
 public:
  /// `nice` [0..19]: the thread's scheduling niceness (0 = the manager's; higher = yields the
  /// CPU to the other stages, for a baseline that may run behind). `idle`: the thread runs
  /// under SCHED_IDLE (Linux), the lowest class: whenever another thread of the machine is
  /// runnable it gets the CPU first, and a waking stage preempts this one at once (a niceness
  /// only shares the CPU by weight). For a stage whose rate does not matter. Starts at once.
  explicit StageThread(int nice = 0, bool idle = false);
  ~StageThread();  // stop()
  StageThread(const StageThread&) = delete;
  StageThread& operator=(const StageThread&) = delete;

  /// `nh` with this thread's callback queue: subscribe through it.
  ros::NodeHandle handle(const ros::NodeHandle& nh);
  /// Waits for the running callback to return and stops; later callbacks are dropped.
  /// Call it first in the nodelet's destructor, before the state the callbacks use goes.
  void stop();
  /// Why the niceness or the idle class could not be set ("" if they were, or not asked for).
  std::string niceError() const;

 private:
  ros::CallbackQueue queue_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
  int nice_ = 0;
  bool idle_ = false;
  std::shared_ptr<std::string> nice_error_;
};

}  // namespace ros_conv
}  // namespace urban_detection
