/// \file rostest_util.h
/// What the gtest rostests (nodelets loaded into the test process with nodelet::Loader) share:
/// polling with a timeout, watchers of /rosout and /diagnostics, a message collector, a free UDP
/// port and the main() that spins the process's callbacks while the tests run.
#pragma once

#include <arpa/inet.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace urban_detection {
namespace rostest_util {

/// Polls `done` every 10 ms until it holds or `timeout_s` passed; returns its last value.
inline bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

/// Every message logged on /rosout since construction (the nodelets of this process log
/// through it too).
class RosoutWatcher {
 public:
  RosoutWatcher() { sub_ = ros::NodeHandle().subscribe("/rosout", 200, &RosoutWatcher::cb, this); }
  /// Number of messages of `level` (rosgraph_msgs::Log::ERROR, ...) containing `text`.
  int count(std::uint8_t level, const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex_);
    int n = 0;
    for (const auto& log : logs_) {
      n += log.level == level && log.msg.find(text) != std::string::npos;
    }
    return n;
  }
  bool contains(std::uint8_t level, const std::string& text) { return count(level, text) > 0; }

 private:
  void cb(const rosgraph_msgs::Log::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    logs_.push_back(*msg);
  }
  std::mutex mutex_;
  std::vector<rosgraph_msgs::Log> logs_;
  ros::Subscriber sub_;
};

/// Every status published on /diagnostics since construction.
class DiagnosticsWatcher {
 public:
  DiagnosticsWatcher() {
    sub_ = ros::NodeHandle().subscribe("/diagnostics", 100, &DiagnosticsWatcher::cb, this);
  }
  /// Latest value of `key` in a status whose name contains `name`, or -1.
  long value(const std::string& name, const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = statuses_.rbegin(); it != statuses_.rend(); ++it) {
      if (it->name.find(name) == std::string::npos) continue;
      for (const auto& kv : it->values) {
        if (kv.key == key) return std::stol(kv.value);
      }
    }
    return -1;
  }
  /// Whether a WARN status whose name contains `name` had a summary containing `text`.
  bool sawWarning(const std::string& name, const std::string& text) {
    return saw(name, diagnostic_msgs::DiagnosticStatus::WARN, text);
  }
  /// The same for an ERROR status.
  bool sawError(const std::string& name, const std::string& text) {
    return saw(name, diagnostic_msgs::DiagnosticStatus::ERROR, text);
  }
  bool saw(const std::string& name, std::uint8_t level, const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : statuses_) {
      if (s.name.find(name) != std::string::npos && s.level == level &&
          s.message.find(text) != std::string::npos) {
        return true;
      }
    }
    return false;
  }
  /// Every status whose name contains `name`, in the order published.
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses(const std::string& name) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<diagnostic_msgs::DiagnosticStatus> out;
    for (const auto& s : statuses_) {
      if (s.name.find(name) != std::string::npos) out.push_back(s);
    }
    return out;
  }

 private:
  void cb(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    statuses_.insert(statuses_.end(), msg->status.begin(), msg->status.end());
  }
  std::mutex mutex_;
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses_;
  ros::Subscriber sub_;
};

/// Keeps every message of a subscription (zero copy: the pointers the publisher sent).
template <typename M>
struct Collector {
  std::mutex mutex;
  std::vector<boost::shared_ptr<const M>> msgs;
  void callback(const boost::shared_ptr<const M>& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    msgs.push_back(msg);
  }
  std::size_t size() {
    std::lock_guard<std::mutex> lock(mutex);
    return msgs.size();
  }
  boost::shared_ptr<const M> at(std::size_t i) {
    std::lock_guard<std::mutex> lock(mutex);
    return msgs.at(i);
  }
};

/// A UDP port on 127.0.0.1 that was free a moment ago (bound to port 0, then released).
inline int freeUdpPort() {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  socklen_t len = sizeof(addr);
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);
  return ntohs(addr.sin_port);
}

/// main() of a rostest gtest node named `node_name`: two spinner threads serve the callbacks
/// of the test's subscribers and of the nodelets it loads while the tests run.
inline int runRostests(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}

}  // namespace rostest_util
}  // namespace urban_detection
