/// \file nodelet_params.h
/// The nodelets' own settings (queues, limits, frames, threads, output files): one params struct
/// per nodelet with its field table, loaded with loadFields() (ros/param_loading.h) like the
/// stages' params, so each name, range and description is written once and docs/parameters.md
/// lists them (urban_detection_params). The stages' params (segmentation, detectors, tracker,
/// markers, packets) have their own tables beside their structs.
#pragma once

#include <string>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace ros_conv {

/// CloudInput: PointCloud2 (e.g. KITTI replays) into the pipeline's cloud type.
struct CloudInputParams {
  int queue_size = 2;  // [messages] input queue
  /// [points] larger clouds are refused before any allocation: three revolutions at 300 rpm, as
  /// PacketToCloud's max_packets_per_scan.
  int max_points = static_cast<int>(core::RevolutionBoundary::kMaxPacketsPerRevolution *
                                    core::kBlocksPerPacket * core::kLasersPerBlock);
};

/// GridSegmentation's nodelet settings (the segmenter's are GridSegmenterParams).
struct GridSegmentationNodeletParams {
  int queue_size = 2;          // [messages] input queue
  bool stream_sectors = true;  // bin velodyne_points/sectors as they arrive
};

/// The detector nodelets' settings (HierarchicalGridDetector, KdTreeDetector).
struct DetectorNodeletParams {
  int queue_size = 2;          // [messages] input queue
  int thread_nice = 0;         // nice value of the stage's thread (0 = the manager's)
  bool thread_idle = false;    // SCHED_IDLE stage thread
  bool best_effort = false;    // diagnostics: best-effort rate, newest revolution only
  bool early_objects = false;  // also publish each object on objects/early once final
};

/// ObjectTracker's nodelet settings (the tracker's are TrackerParams).
struct ObjectTrackerNodeletParams {
  std::string fixed_frame = "odom";  // tracks kept in this frame (tf); empty = objects' frame
  int queue_size = 2;                // [messages] input queue
};

/// ObjectMarkers / ObjectExport: input queue only.
struct ObjectQueueParams {
  int queue_size = 2;  // [messages] input queue
};

/// ObjectRecorder: revolutions written as KITTI-style files.
struct ObjectRecorderParams {
  std::string output_dir;  // folder written (mandatory)
  int first_index = 0;     // number of the first revolution's files
  int queue_size = 10;     // [messages] input queue
};

/// SimulatedSensor: a simulated HDL-64E drive published as packets and ground truth.
struct SimulatedSensorParams {
  std::string config;                   // drive YAML (mandatory; e.g. config/demo_drive.yaml)
  bool realtime = true;                 // publish at the sensor's rate (false: as fast as possible)
  double rate_factor = 1.0;             // [-] speed factor of realtime publishing
  bool loop = true;                     // restart the drive at its end
  bool publish_tf = true;               // odom -> base_link -> sensor transforms
  bool timestamp_first_packet = false;  // header.stamp = first packet's (false: last)
  std::string frame_id = "velodyne";    // sensor frame of scans and ground truth
  std::string odom_frame = "odom";      // world frame of the scene
  std::string base_frame = "base_link";  // platform frame, on the ground under the sensor
};

// No cross-field rules: the tables' ranges are the whole check (checkFields needs a validate()).
inline std::string validate(const CloudInputParams&) {
  return "";
}
inline std::string validate(const GridSegmentationNodeletParams&) {
  return "";
}
inline std::string validate(const DetectorNodeletParams&) {
  return "";
}
inline std::string validate(const ObjectTrackerNodeletParams&) {
  return "";
}
inline std::string validate(const ObjectQueueParams&) {
  return "";
}
inline std::string validate(const ObjectRecorderParams&) {
  return "";
}
inline std::string validate(const SimulatedSensorParams&) {
  return "";
}

}  // namespace ros_conv
}  // namespace urban_detection

template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::CloudInputParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"queue_size", "messages", 1, 100, "input queue"}, p.queue_size);
    f({"max_points", "points", 1, 100000000, "larger clouds are refused before any allocation"},
      p.max_points);
  }
};

template <>
struct urban_detection::core::ParamFields<
    urban_detection::ros_conv::GridSegmentationNodeletParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"queue_size", "messages", 1, 100, "input queue"}, p.queue_size);
    f({"stream_sectors", "bin velodyne_points/sectors as they arrive (false: whole revolutions)"},
      p.stream_sectors);
  }
};

template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::DetectorNodeletParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"queue_size", "messages", 1, 100, "input queue"}, p.queue_size);
    f({"thread_nice", "", 0, 19, "nice value of the stage's thread (0: the manager's)"},
      p.thread_nice);
    f({"thread_idle", "SCHED_IDLE stage thread"}, p.thread_idle);
    f({"best_effort", "diagnostics: best-effort rate, newest revolution only"}, p.best_effort);
    f({"early_objects",
       "also publish each object as soon as it is final on objects/early (from "
       "velodyne_points/sectors)"},
      p.early_objects);
  }
};

template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::ObjectTrackerNodeletParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"fixed_frame", "tracks kept in this frame (via tf); empty: the objects' frame"},
      p.fixed_frame);
    f({"queue_size", "messages", 1, 100, "input queue"}, p.queue_size);
  }
};

template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::ObjectQueueParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"queue_size", "messages", 1, 100, "input queue"}, p.queue_size);
  }
};

template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::ObjectRecorderParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"output_dir", "folder written (mandatory)"}, p.output_dir);
    f({"first_index", "", 0, 99999999, "number of the first revolution's files"}, p.first_index);
    f({"queue_size", "messages", 1, 100, "input queue"}, p.queue_size);
  }
};

template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::SimulatedSensorParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"config", "drive YAML (mandatory), e.g. config/demo_drive.yaml"}, p.config);
    f({"realtime", "publish at the sensor's rate (false: as fast as possible)"}, p.realtime);
    f({"rate_factor", "", 1e-3, 100.0, "speed factor of realtime publishing"}, p.rate_factor);
    f({"loop", "restart the drive at its end"}, p.loop);
    f({"publish_tf", "publish odom -> base_link -> sensor transforms"}, p.publish_tf);
    f({"timestamp_first_packet", "header.stamp of a revolution: its first packet's (false: last)"},
      p.timestamp_first_packet);
    f({"frame_id", "sensor frame of scans and ground truth"}, p.frame_id);
    f({"odom_frame", "world frame of the scene"}, p.odom_frame);
    f({"base_frame", "platform frame, on the ground under the sensor"}, p.base_frame);
  }
};
