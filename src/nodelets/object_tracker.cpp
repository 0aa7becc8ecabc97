// urban_detection/ObjectTracker: objects -> objects/tracked (TrackedObjectArray:
// stable ids, velocities, tentative/confirmed/lost) and objects/tracked/markers. Tracks live
// in ~fixed_frame (default odom) when tf gives fixed_frame <- the objects' frame at their stamp,
// else in the objects' own frame with velocities marked relative (velocities_relative; one
// warning on entering it; a change of frame restarts the tracks). Stamps going back (a looping
// bag, a restarted simulation) reset the tracks and the tf buffer once, with one INFO.
// Lazy. Parameters: ~tracker/*, ~markers/*, ~fixed_frame, ~queue_size
// (config/object_tracker.yaml); tunable in ~tracker (cfg/ObjectTracker.cfg).
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/ObjectTrackerConfig.h"
#include "urban_detection/TrackedObjectArray.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/object_tracking.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/tunable_fields.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {
namespace ros_conv {

class ObjectTrackerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const ros::NodeHandle tnh(pnh, "tracker");
    core::TrackerParams params;
    try {
      loadFields(tnh, &params);
      loadFields(ros::NodeHandle(pnh, "markers"), &marker_params_);
      loadFields(pnh, &params_);
    } catch (const ParamError& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), pnh, getName(),
          "ObjectTracker: " + std::string(e.what()) + "; the nodelet stays idle");
      return;
    }
    tracker_ = std::make_unique<core::Tracker>(params);
    const auto initial = ros_conv::toConfig<ObjectTrackerConfig>(params);
    auto apply = [this, tnh](const ObjectTrackerConfig& c) {
      std::lock_guard<std::mutex> lock(mutex_);  // applied from the next message on
      const core::TrackerParams p = ros_conv::fromConfig(c, tracker_->params());
      const std::string error = checkFields(tnh, p);
      if (error.empty()) tracker_->setParams(p);
      return error;
    };
    reconfigure_ = std::make_unique<Reconfigure>(tnh, initial, apply);
    if (!params_.fixed_frame.empty()) {
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
    }
    diagnostics_ =
        std::make_unique<ros_conv::StageDiagnostics>(getNodeHandle(), pnh, getName(), "tracker");
    diagnostics_->setActive(false);
    lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) return sub_.shutdown();
      sub_ = getNodeHandle().subscribe("objects", params_.queue_size,
                                       &ObjectTrackerNodelet::objectsCb, this);
    });
    ros::NodeHandle& nh = getNodeHandle();
    tracks_pub_ = lazy_->advertise<TrackedObjectArray>(nh, "objects/tracked", 2);
    markers_pub_ =
        lazy_->advertise<visualization_msgs::MarkerArray>(nh, "objects/tracked/markers", 2);
  }

  // odom_T_sensor at the objects' stamp, or identity in the sensor frame when tf cannot say.
  // `wait_s`: how long to wait for a late transform of frames tf knows.
  std::string fixedFrame(const std_msgs::Header& header, double wait_s, Eigen::Isometry3d* pose,
                         std::string* error) {
    *pose = Eigen::Isometry3d::Identity();
    if (!tf_buffer_ || params_.fixed_frame == header.frame_id) return header.frame_id;
    try {
      // Waits for a transform that is late, not for a frame nobody publishes; the very first
      // revolution also waits, as tf may not have heard of any frame yet.
      const bool known = frame_.empty() || (tf_buffer_->_frameExists(params_.fixed_frame) &&
                                            tf_buffer_->_frameExists(header.frame_id));
      *pose = tf2::transformToEigen(tf_buffer_->lookupTransform(
          params_.fixed_frame, header.frame_id, header.stamp, ros::Duration(known ? wait_s : 0.0)));
      return params_.fixed_frame;
    } catch (const tf2::TransformException& e) {
      diagnostics_->count("tf_failures");
      *error = e.what();
      return header.frame_id;
    }
  }

  // A stamp before the previous one: the stream restarted (a looping bag). Resets the tracks
  // once. True for the first second of stamps of a stream (the first one or a restarted one),
  // while tf may not have the stream's transforms yet. The tf buffer itself is not cleared
  // here: under simulated time tf2's listener clears it when the clock goes back, and a clear
  // after the objects arrive would drop the new stream's transforms already received.
  bool streamStarting(const ros::Time& stamp) {
    if (last_stamp_.isZero()) {
      restart_stamp_ = stamp;
    } else if (stamp < last_stamp_) {
      NODELET_INFO(
          "objects' stamp went back %.2f s (a looping bag or a restarted source): tracks reset",
          (last_stamp_ - stamp).toSec());
      std::lock_guard<std::mutex> lock(mutex_);
      tracker_->reset();
      restart_stamp_ = stamp;
    }
    last_stamp_ = stamp;
    return (stamp - restart_stamp_).toSec() < kRestartGraceS;
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& msg) {
    const ros::WallTime start = ros::WallTime::now();
    diagnostics_->input(msg->header.seq);
    const bool starting = streamStarting(msg->header.stamp);
    Eigen::Isometry3d pose;
    std::string tf_error;
    const std::string frame = fixedFrame(
        msg->header, starting || frame_.empty() ? kRestartTfWaitS : 0.05, &pose, &tf_error);
    if (!tf_error.empty()) {
      if (starting && (frame_ == params_.fixed_frame ||
                       (frame_.empty() && tf_buffer_->_frameExists(params_.fixed_frame)))) {
        // A stream that starts or restarts while tf lacks its first transforms (the listener
        // joined after the first revolution, or tf went back with the clock): skip this
        // revolution rather than track in the sensor frame and flip back.
        diagnostics_->count("skipped_waiting_for_tf");
        return;
      }
      if (!sensor_frame_warned_) {
        NODELET_WARN(
            "no transform %s <- %s (%s): tracking in the sensor frame %s; velocities "
            "are relative to the moving sensor (velocities_relative)",
            params_.fixed_frame.c_str(), msg->header.frame_id.c_str(), tf_error.c_str(),
            msg->header.frame_id.c_str());
        sensor_frame_warned_ = true;
      }
    } else if (frame == params_.fixed_frame) {
      sensor_frame_warned_ = false;  // warn again should odometry stop
    }
    auto tracked = boost::make_shared<TrackedObjectArray>();
    auto markers = boost::make_shared<visualization_msgs::MarkerArray>();
    const bool want_markers = markers_pub_.getNumSubscribers() > 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      objects_.resize(msg->objects.size());
      for (std::size_t k = 0; k < objects_.size(); ++k)
        ros_conv::fromMsg(msg->objects[k], &objects_[k]);
      if (frame != frame_) {  // a new frame: positions are not comparable, start over
        if (!frame_.empty()) {
          NODELET_INFO("tracking in frame %s (was %s): tracks restarted", frame.c_str(),
                       frame_.c_str());
        }
        tracker_->reset();
        frame_ = frame;
      }
      const ros::WallTime t0 = ros::WallTime::now();
      const core::TrackerStats& s = tracker_->update(objects_, pose, msg->header.stamp.toSec());
      const double association_s = (ros::WallTime::now() - t0).toSec();
      if (s.invalid_detections > 0) {
        const std::string text =
            "invalid objects: skipped " + std::to_string(s.invalid_detections) + " of " +
            std::to_string(s.detections) + " objects with a non-finite box or pose";
        if (diagnostics_->error("invalid_objects", text, s.invalid_detections)) {
          NODELET_ERROR("%s", text.c_str());
        }
      }
      if (s.restarted) {  // a stamp going back was handled above: this is a jump forward
        NODELET_WARN_THROTTLE(5, "objects' stamp jumped forward: tracks restarted");
      }
      diagnostics_->setTotal("confirmed_tracks", s.confirmed, false);
      diagnostics_->setTotal("tentative_tracks", s.tentative, false);
      diagnostics_->setTotal("lost_tracks", s.lost, false);
      diagnostics_->setTotal("tracker_update_us", static_cast<std::uint64_t>(association_s * 1e6),
                             false);
      tracked->header = msg->header;
      tracked->header.frame_id = frame;
      tracked->velocities_relative = params_.fixed_frame.empty() || frame != params_.fixed_frame;
      tracked->detector = msg->detector;
      tracked->objects.resize(tracker_->tracks().size());
      for (std::size_t k = 0; k < tracked->objects.size(); ++k) {
        const core::Track& t = tracker_->tracks()[k];
        ros_conv::toMsg(t, &tracked->objects[k]);
        if (t.detection >= 0) {
          tracked->objects[k].detection_id =
              static_cast<std::int32_t>(msg->objects[t.detection].id);
        }
      }
      if (want_markers) {
        ros_conv::buildTrackMarkers(*tracked, tracker_->died(), marker_params_,
                                    tracker_->params().moving_speed_mps, &arrows_, markers.get());
      }
    }
    if (tracks_pub_.getNumSubscribers() > 0) {
      tracks_pub_.publish(boost::shared_ptr<const TrackedObjectArray>(tracked));
    }
    if (want_markers)
      markers_pub_.publish(boost::shared_ptr<const visualization_msgs::MarkerArray>(markers));
    diagnostics_->latency(msg->header.stamp, ros::Time::now());
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
    diagnostics_->output();
  }

  using Reconfigure = ros_conv::ValidatedReconfigure<ObjectTrackerConfig>;
  std::mutex mutex_;  // tracker_ between messages and reconfigure
  std::unique_ptr<core::Tracker> tracker_;
  std::vector<core::DetectedObject> objects_;  // converted input, reused
  ros_conv::TrackMarkerParams marker_params_;
  std::string frame_;                             // the frame the current tracks live in
  bool sensor_frame_warned_ = false;              // said that tracks are in the sensor frame
  ros::Time last_stamp_;                          // of the previous objects message
  ros::Time restart_stamp_;                       // first stamp of the (re)started stream
  static constexpr double kRestartGraceS = 1.0;   // [s] of stamps at a (re)start: tf may lag
  static constexpr double kRestartTfWaitS = 0.2;  // [s] wait for tf then
  std::set<std::uint32_t> arrows_;                // tracks whose velocity arrow is shown
  ObjectTrackerNodeletParams params_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<Reconfigure> reconfigure_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher tracks_pub_, markers_pub_;
  ros::Subscriber sub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ObjectTrackerNodelet, nodelet::Nodelet)
