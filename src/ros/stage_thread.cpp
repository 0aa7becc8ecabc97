#include "urban_detection/ros/stage_thread.h"

#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <future>
#include <mutex>

#include <ros/callback_queue_interface.h>
#include <boost/make_shared.hpp>

namespace urban_detection {
namespace ros_conv {

namespace {
std::mutex nice_mutex;  // nice_error_ written on the stage thread, read by the nodelet

// Runs once on the stage thread: sets that thread's niceness (Linux: per thread).
class NiceCallback : public ros::CallbackInterface {
 public:
  NiceCallback(int nice, bool idle, std::shared_ptr<std::string> error,
               std::shared_ptr<std::promise<void>> done)
      : nice_(nice), idle_(idle), error_(std::move(error)), done_(std::move(done)) {}
  CallResult call() override {
    const pid_t tid = static_cast<pid_t>(syscall(SYS_gettid));
    if (nice_ != 0 && setpriority(PRIO_PROCESS, static_cast<id_t>(tid), nice_) != 0) {
      std::lock_guard<std::mutex> lock(nice_mutex);
      *error_ = std::string("setpriority: ") + std::strerror(errno);
    }
    if (idle_) {
      // Per thread on Linux (the tid); an unprivileged thread may always lower its class.
      sched_param param{};
      param.sched_priority = 0;
      if (sched_setscheduler(tid, SCHED_IDLE, &param) != 0) {
        std::lock_guard<std::mutex> lock(nice_mutex);
        *error_ += std::string(error_->empty() ? "" : "; ") +
                   "sched_setscheduler(SCHED_IDLE): " + std::strerror(errno);
      }
    }
    done_->set_value();
    return Success;
  }

 private:
  int nice_;
  bool idle_;
  std::shared_ptr<std::string> error_;
  std::shared_ptr<std::promise<void>> done_;
};
}  // namespace

StageThread::StageThread(int nice, bool idle)
    : nice_(nice), idle_(idle), nice_error_(std::make_shared<std::string>()) {
  auto done = std::make_shared<std::promise<void>>();
  std::future<void> applied = done->get_future();
  const bool adjust = nice_ != 0 || idle_;
  if (adjust) {
    queue_.addCallback(boost::make_shared<NiceCallback>(nice_, idle_, nice_error_, done));
  }
  spinner_ = std::make_unique<ros::AsyncSpinner>(1, &queue_);
  spinner_->start();
  if (adjust && applied.wait_for(std::chrono::seconds(2)) != std::future_status::ready) {
    std::lock_guard<std::mutex> lock(nice_mutex);
    *nice_error_ = "the stage thread did not start";
  }
}

StageThread::~StageThread() {
  stop();
}

ros::NodeHandle StageThread::handle(const ros::NodeHandle& nh) {
  ros::NodeHandle own(nh);
  own.setCallbackQueue(&queue_);
  return own;
}

void StageThread::stop() {
  if (!spinner_) return;
  spinner_->stop();  // joins the thread
  spinner_.reset();
  queue_.disable();
  queue_.clear();
}

std::string StageThread::niceError() const {
  std::lock_guard<std::mutex> lock(nice_mutex);
  return *nice_error_;
}

}  // namespace ros_conv
}  // namespace urban_detection
