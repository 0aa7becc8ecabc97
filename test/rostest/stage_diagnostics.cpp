// StageDiagnostics driven by hand (its wall timer on a callback queue nobody spins, so every
// status comes from update()):
//  * an update that closely follows another (roscpp's timer catching up after a late call)
//    does not report rates over a few milliseconds: the previous status stands and the
//    revolutions skipped meanwhile are reported with the next window, none lost;
//  * an error is never held back by that rule;
//  * a best-effort stage (a baseline on spare CPU) that skips revolutions says so at OK
//    level with its rates, never "falling behind";
//  * a StageThread asked for the idle class runs its callbacks under SCHED_IDLE.
#include <sched.h>

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <gtest/gtest.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <regex>
#include <string>
#include <thread>

#include "rostest_util.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/stage_thread.h"

namespace urban_detection {
namespace {

using rostest_util::DiagnosticsWatcher;
using rostest_util::waitFor;

void sleepS(double s) {
  std::this_thread::sleep_for(std::chrono::duration<double>(s));
}

/// The seconds of "... in X s" in a status message, or -1.
double windowSeconds(const std::string& message) {
  std::smatch m;
  static const std::regex re("in ([0-9.]+) s");
  return std::regex_search(message, m, re) ? std::stod(m[1]) : -1.0;
}

TEST(StageDiagnostics, CloseUpdatesKeepThePreviousWindowAndLoseNoSkip) {
  DiagnosticsWatcher diagnostics;
  ros::CallbackQueue unspun;  // the stage's own 1 s timer never fires
  ros::NodeHandle nh;
  nh.setCallbackQueue(&unspun);
  ros::NodeHandle pnh("~stage_a");
  pnh.setCallbackQueue(&unspun);
  ros_conv::StageDiagnostics stage(nh, pnh, "/stage_a", "revolutions");
  sleepS(1.0);
  stage.input(1, "driver");
  stage.input(5, "driver");  // 2, 3, 4 lost
  stage.update();
  stage.input(9, "driver");  // 6, 7, 8 lost, a moment later
  stage.update();            // right after: a window of a few milliseconds
  sleepS(0.6);
  stage.update();
  EXPECT_TRUE(
      waitFor([&] { return diagnostics.value("stage_a", "skipped_revolutions") == 6; }, 10.0))
      << "revolutions skipped in the short window were lost: "
      << diagnostics.value("stage_a", "skipped_revolutions");
  int skip_warnings = 0;
  for (const auto& s : diagnostics.statuses("stage_a")) {
    if (s.message.find("skipped") == std::string::npos) continue;
    ++skip_warnings;
    EXPECT_EQ(s.level, diagnostic_msgs::DiagnosticStatus::WARN) << s.message;
    EXPECT_GE(windowSeconds(s.message), 0.5) << "a rate over a too short window: " << s.message;
    std::fprintf(stderr, "status: %s\n", s.message.c_str());
  }
  EXPECT_GE(skip_warnings, 2) << "the second gap was not reported";
}

TEST(StageDiagnostics, AnErrorIsReportedEvenRightAfterAnUpdate) {
  DiagnosticsWatcher diagnostics;
  ros::CallbackQueue unspun;
  ros::NodeHandle nh;
  nh.setCallbackQueue(&unspun);
  ros::NodeHandle pnh("~stage_b");
  pnh.setCallbackQueue(&unspun);
  ros_conv::StageDiagnostics stage(nh, pnh, "/stage_b", "revolutions");
  sleepS(0.6);
  stage.input(1, "driver");
  stage.update();
  stage.refuse("point_step 0: no point can be read");
  stage.update();
  EXPECT_TRUE(waitFor([&] { return diagnostics.sawError("stage_b", "point_step 0"); }, 10.0));
}

TEST(StageDiagnostics, ABestEffortStageSkipsWithoutFallingBehind) {
  DiagnosticsWatcher diagnostics;
  ros::CallbackQueue unspun;
  ros::NodeHandle nh;
  nh.setCallbackQueue(&unspun);
  ros::NodeHandle pnh("~stage_c");
  pnh.setCallbackQueue(&unspun);
  ros_conv::StageDiagnostics stage(nh, pnh, "/stage_c", "revolutions");
  stage.setBestEffort(true);
  sleepS(0.6);
  stage.input(1, "driver");
  stage.frame(0.5);
  stage.output();
  stage.input(8, "driver");  // 2..7 skipped: the newest revolution only
  stage.frame(0.5);
  stage.output();
  stage.update();
  EXPECT_TRUE(
      waitFor([&] { return diagnostics.value("stage_c", "skipped_revolutions") == 6; }, 10.0));
  bool best_effort = false;
  for (const auto& s : diagnostics.statuses("stage_c")) {
    EXPECT_EQ(s.message.find("falling behind"), std::string::npos) << s.message;
    if (s.message.find("best effort") == std::string::npos) continue;
    best_effort = true;
    EXPECT_EQ(s.level, diagnostic_msgs::DiagnosticStatus::OK) << s.message;
    EXPECT_NE(s.message.find("skipped 6"), std::string::npos) << s.message;
  }
  EXPECT_TRUE(best_effort) << "no best-effort status";
}

TEST(StageThread, IdleClassAppliesToTheStagesCallbacks) {
  for (const bool idle : {true, false}) {
    ros_conv::StageThread thread(0, idle);
    EXPECT_EQ(thread.niceError(), "");
    std::atomic<int> policy{-1};
    ros::NodeHandle nh;
    ros::NodeHandle own = thread.handle(nh);
    const ros::WallTimer timer = own.createWallTimer(
        ros::WallDuration(0.01),
        [&](const ros::WallTimerEvent&) { policy = sched_getscheduler(0); }, true);
    EXPECT_TRUE(waitFor([&] { return policy >= 0; }, 10.0));
    EXPECT_EQ(policy.load(), idle ? SCHED_IDLE : SCHED_OTHER) << "idle " << idle;
    thread.stop();
  }
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_stage_diagnostics");
}
