/// \file object_tracking.h
/// ROS side of the ObjectTracker (issue 28): detected-object messages into core objects, core
/// tracks into TrackedObjectArray, the tracks' rviz markers, and the parameter loading and
/// checking shared by the start-up loader and dynamic_reconfigure. No ROS master needed.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <ros/node_handle.h>
#include <visualization_msgs/MarkerArray.h>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/TrackedObjectArray.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace ros_conv {

/// The tracked markers' options (~markers in config/object_tracker.yaml).
struct TrackMarkerParams {
  bool show_tentative = false;  // [-] draw tentative tracks too (thin, grey)
  double box_alpha = 0.5;       // [0..1] box opacity
  double text_size_m = 0.6;     // [m] label text height
  double arrow_time_s = 1.0;    // [s] a velocity arrow is as long as the path in this time
};

/// Fills `object` (box, class) from `msg`: obb_pose -> obb_center and obb_yaw_rad (the yaw of
/// the quaternion; a zero quaternion gives NaN, which the tracker refuses), obb_dimensions ->
/// obb_size, class_label -> category.
void fromMsg(const DetectedObject& msg, core::DetectedObject* object);

/// Fills `msg` from a track (frame and stamp are the array's).
void toMsg(const core::Track& track, TrackedObject* msg);

/// Builds the tracked markers: for every confirmed or lost track (and tentative ones with
/// show_tentative) a box (ns "tracks"), a velocity arrow (ns "track_velocities", only when
/// moving faster than `moving_speed_mps`) and a text "id class speed" (ns "track_labels",
/// speed in m/s), all with marker id = track id and the track's colour (colourForId: stable per
/// id). Then DELETE markers in all three namespaces for each id in `deleted` (tracks that
/// died), and for the arrow of a track in `arrows` (the ids that had one in the previous call;
/// updated here) that no longer moves.
void buildTrackMarkers(const TrackedObjectArray& tracks, const std::vector<std::uint32_t>& deleted,
                       const TrackMarkerParams& params, double moving_speed_mps,
                       std::set<std::uint32_t>* arrows, visualization_msgs::MarkerArray* markers);

/// Reads ~tracker/* into `params` (each optional; throws ParamError naming the first bad one,
/// with the range of TrackerParams::validate()).
void loadTrackerParams(const ros::NodeHandle& nh, core::TrackerParams* params);
/// The same checks on a complete set (dynamic_reconfigure): "" or the reason, naming the
/// parameter resolved in `nh`.
std::string checkTrackerParams(const ros::NodeHandle& nh, const core::TrackerParams& params);
/// Reads ~markers/* (throws ParamError).
void loadTrackMarkerParams(const ros::NodeHandle& nh, TrackMarkerParams* params);

/// core::TrackerParams <-> ObjectTrackerConfig (cfg/ObjectTracker.cfg), as tunable_fields.h.
struct TrackerTunables {
  template <class C, class P, class F>
  void operator()(C& c, P& p, F f) const {
    f(c.gate_distance_m, p.gate_distance_m);
    f(c.gate_sigmas, p.gate_sigmas);
    f(c.overlap_weight_m, p.overlap_weight_m);
    f(c.birth_hits, p.birth_hits);
    f(c.death_misses, p.death_misses);
    f(c.tentative_max_misses, p.tentative_max_misses);
    f(c.measurement_std_m, p.measurement_std_m);
    f(c.process_accel_std_mps2, p.process_accel_std_mps2);
  }
};

}  // namespace ros_conv
}  // namespace urban_detection
