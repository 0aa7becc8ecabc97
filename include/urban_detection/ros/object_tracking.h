/// \file object_tracking.h
/// ROS side of the ObjectTracker: detected-object messages into core objects, core tracks into
/// TrackedObjectArray, the tracks' rviz markers and their parameters' field table (loaded and
/// checked by loadFields/checkFields, ros/param_loading.h). No ROS master needed.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

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
/// moving faster than `moving_speed_mps` over ground) and a text (ns "track_labels"): "id class
/// speed m/s" when moving, "id class" when not, "id class (speed m/s rel.)" and no arrow when
/// the array's velocities_relative is set (no odometry: a parked car is not drawn moving),
/// all with marker id = track id and the track's class colour (colourForClass, as the objects'
/// boxes and the legend; colourForId for an unclassified track). Then DELETE markers in
/// all three namespaces for each id in `deleted` (tracks that died), and for the arrow of a track
/// in `arrows` (the ids that had one in the previous call; updated here) that no longer moves.
void buildTrackMarkers(const TrackedObjectArray& tracks, const std::vector<std::uint32_t>& deleted,
                       const TrackMarkerParams& params, double moving_speed_mps,
                       std::set<std::uint32_t>* arrows, visualization_msgs::MarkerArray* markers);

/// "" when every field is in its table range (ParamFields<TrackMarkerParams> below).
std::string validate(const TrackMarkerParams& params);

}  // namespace ros_conv
}  // namespace urban_detection

/// The tracked markers' field table (core/common/param_fields.h).
namespace urban_detection {
template <>
struct core::ParamFields<ros_conv::TrackMarkerParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"show_tentative", "draw tentative tracks too (thin, grey)"}, p.show_tentative);
    f({"box_alpha", "", 0.0, 1.0, "box opacity"}, p.box_alpha);
    f({"text_size_m", "m", 0.01, 10.0, "label text height"}, p.text_size_m);
    f({"arrow_time_s", "s", 0.0, 10.0, "a velocity arrow is as long as the path in this time"},
      p.arrow_time_s);
  }
};
}  // namespace urban_detection
