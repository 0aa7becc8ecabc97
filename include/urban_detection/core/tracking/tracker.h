/// \file tracker.h
/// Multi-object tracking of detected objects over revolutions. ROS-free.
///
/// Each track is a constant-velocity Kalman filter on the box centre in a fixed frame
/// (state x, y, vx, vy [m, m/s]); height, yaw and box size are smoothed exponentially. Every
/// revolution:
///   1. the detections are moved from the sensor frame into the fixed frame with the sensor
///      pose of that revolution (odom_T_sensor), so a parked car stays still while the sensor
///      drives past it (ego-motion compensation);
///   2. every track is predicted to the revolution's stamp;
///   3. detections are assigned to tracks by a minimum-cost one-to-one assignment (Hungarian
///      algorithm, hungarian.h) over the gated pairs: a pair is admissible when the distance
///      between the predicted centre and the detected centre is at most the track's gate,
///      `gate_distance_m + gate_sigmas * sigma` (sigma: std dev of the predicted centre along
///      its most uncertain axis; at most 2 x gate_distance_m); its cost is that distance plus
///      `overlap_weight_m * (1 - bird's-eye IoU)` of the two yaw-oriented boxes. Confirmed and
///      lost tracks are assigned first, tentative tracks then share the detections left. The
///      gated pairs split each stage into independent groups, each solved on its own (a street
///      of 100 objects is many 1x1 and 2x2 problems);
///   4. matched tracks are updated; unmatched detections start tentative tracks; a tentative
///      track becomes confirmed after `birth_hits` hits (or as soon as its class evidence,
///      class_evidence.h, gives vehicle, pedestrian or cyclist a posterior of at least
///      `confident_birth_probability`, when that is above 0) and is deleted after
///      `tentative_max_misses` consecutive misses; a confirmed track that misses becomes lost
///      (coasting on its prediction) and is deleted after `death_misses` consecutive misses;
///      a lost track that is matched again is confirmed again, keeping its id.
/// Ids start at 1 and are never reused within one Tracker.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/detection/box_fitting.h"  // bevIoU
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/tracking/class_evidence.h"

namespace urban_detection {
namespace core {

/// Parameters of the Tracker. Units in the comments; ranges in the field table below.
struct TrackerParams {
  double gate_distance_m = 2.0;         // [m] largest predicted-to-detected centre distance
  double gate_sigmas = 2.0;             // [-] the gate widens by this many std devs of the
                                        //   predicted centre (at most to 2 x gate_distance_m)
  double overlap_weight_m = 1.0;        // [m] cost of a pair with no box overlap vs full overlap
  int birth_hits = 3;                   // [-] hits that confirm a tentative track (N)
  int death_misses = 20;                // [-] consecutive misses that delete a confirmed track (M)
  int tentative_max_misses = 2;         // [-] consecutive misses that delete a tentative track
  double measurement_std_m = 0.3;       // [m] std dev of a detected box centre
  double process_accel_std_mps2 = 2.0;  // [m/s^2] std dev of the unmodelled acceleration
  double initial_velocity_std_mps = 5.0;  // [m/s] velocity std dev of a new track
  double smoothing = 0.3;                 // [0..1] weight of a new measurement in z, yaw and size
  double default_dt_s = 0.1;              // [s] revolution period used when stamps do not advance
  double max_dt_s = 1.0;                  // [s] a larger gap between stamps restarts the tracker
  double moving_speed_mps = 0.5;          // [m/s] above it the heading follows the velocity
  double confident_birth_probability = 0.0;  // [0..1] a tentative track whose class evidence
                                             //   gives vehicle, pedestrian or cyclist at least
                                             //   this posterior is confirmed (0: off)
};

/// "" when every value is in its table range (ParamFields<TrackerParams> below) and
/// max_dt_s >= default_dt_s, else a message naming the first offending field. NaN is refused.
std::string validate(const TrackerParams& params);

template <>
struct ParamFields<TrackerParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("gate_distance_m", "m", 0.1, 20, "largest predicted-to-detected centre distance"),
      p.gate_distance_m);
    f(FieldInfo("gate_sigmas", "", 0, 10,
                "the gate widens by this many std devs of the predicted centre (at most to 2 x "
                "gate_distance_m)"),
      p.gate_sigmas);
    f(FieldInfo("overlap_weight_m", "m", 0, 20, "pair cost of no box overlap vs full overlap"),
      p.overlap_weight_m);
    f(FieldInfo("birth_hits", "", 1, 100, "hits that confirm a tentative track (N)"), p.birth_hits);
    f(FieldInfo("death_misses", "", 1, 1000,
                "consecutive misses that delete a confirmed track (M)"),
      p.death_misses);
    f(FieldInfo("tentative_max_misses", "", 1, 100,
                "consecutive misses that delete a tentative track"),
      p.tentative_max_misses);
    f(FieldInfo("measurement_std_m", "m", 0.01, 10, "std dev of a detected box centre"),
      p.measurement_std_m);
    f(FieldInfo("process_accel_std_mps2", "m/s^2", 0.01, 50,
                "std dev of the unmodelled acceleration"),
      p.process_accel_std_mps2);
    f(FieldInfo("initial_velocity_std_mps", "m/s", 0.01, 100, "velocity std dev of a new track"),
      p.initial_velocity_std_mps);
    f(FieldInfo("smoothing", "", 0.01, 1, "weight of a new measurement in z, yaw and size"),
      p.smoothing);
    f(FieldInfo("default_dt_s", "s", 0.001, 10,
                "revolution period used when stamps do not advance"),
      p.default_dt_s);
    f(FieldInfo("max_dt_s", "s", 0.001, 3600, "a larger gap between stamps restarts the tracker"),
      p.max_dt_s);
    f(FieldInfo("moving_speed_mps", "m/s", 0, 100, "above it the heading follows the velocity"),
      p.moving_speed_mps);
    f(FieldInfo("confident_birth_probability", "", 0, 1,
                "a tentative track whose class evidence gives vehicle, pedestrian or cyclist at "
                "least this posterior is confirmed before birth_hits (0: off)"),
      p.confident_birth_probability);
  }
};

/// Life cycle of a track.
enum class TrackState : std::uint8_t {
  kTentative = 0,  // fewer than birth_hits hits so far
  kConfirmed = 1,  // confirmed and matched in the latest revolution
  kLost = 2,       // confirmed, but missed in the latest revolution(s): coasting
};

/// "tentative", "confirmed", "lost".
const char* toString(TrackState s);

/// One track, in the fixed frame.
struct Track {
  std::uint32_t id = 0;  // 1.., stable for the track's life
  TrackState state = TrackState::kTentative;
  std::uint32_t age = 0;     // [revolutions] since birth (1 in its first revolution)
  std::uint32_t hits = 0;    // [revolutions] matched to a detection
  std::uint32_t misses = 0;  // [revolutions] consecutive revolutions without a match
  Eigen::Vector3d center = Eigen::Vector3d::Zero();    // [m] box centre (x, y filtered, z smoothed)
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // [m/s] in the fixed frame
  Eigen::Matrix2d velocity_covariance = Eigen::Matrix2d::Identity();  // [m^2/s^2]
  Eigen::Matrix2d position_covariance = Eigen::Matrix2d::Identity();  // [m^2]
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // [m] length, width, height (smoothed)
  double yaw_rad = 0.0;                            // [rad] box yaw; along the velocity when moving
  ObjectCategory category = ObjectCategory::kUnknown;  // class with the most evidence over its
                                                       //   hits (class_evidence.h)
  float class_confidence = 0.0f;                       // [0..1] posterior probability of `category`
  int detection = -1;  // index of the detection it was matched to in the latest
                       // revolution, -1 when it was not matched

  double speed() const { return velocity.norm(); }  // [m/s]
};

/// What the latest update did.
struct TrackerStats {
  std::size_t detections = 0;          // detections given
  std::size_t invalid_detections = 0;  // refused: non-finite centre, size or yaw
  std::size_t matched = 0;
  std::size_t born = 0;       // new tentative tracks
  std::size_t confirmed = 0;  // tracks in state kConfirmed after the update
  std::size_t tentative = 0;
  std::size_t lost = 0;
  std::size_t died = 0;    // tracks deleted in this update
  bool restarted = false;  // the tracker was reset (time went back or jumped)
};

/// The tracker. Not thread-safe; holds its scratch buffers between revolutions.
class Tracker {
 public:
  /// Throws std::invalid_argument with validate()'s message when `params` is invalid.
  explicit Tracker(const TrackerParams& params = TrackerParams());

  /// Processes one revolution: `objects` in the sensor frame, `odom_T_sensor` the sensor pose
  /// in the fixed frame at `stamp_s` [s] (identity: the sensor frame is the fixed frame).
  /// Objects with a non-finite centre, size or yaw are skipped (counted in the stats). A stamp
  /// that goes back or jumps by more than max_dt_s drops every track first (a replayed or
  /// restarted stream), so ids keep rising. Returns the stats of this update.
  const TrackerStats& update(const std::vector<DetectedObject>& objects,
                             const Eigen::Isometry3d& odom_T_sensor, double stamp_s);

  /// Every live track (tentative, confirmed, lost), ordered by id.
  const std::vector<Track>& tracks() const { return tracks_; }
  /// Ids of the tracks deleted in the latest update (and by reset() calls before it).
  const std::vector<std::uint32_t>& died() const { return died_; }
  const TrackerStats& stats() const { return stats_; }
  const TrackerParams& params() const { return params_; }
  /// Replaces the parameters (between revolutions); throws std::invalid_argument like the
  /// constructor. The tracks are kept.
  void setParams(const TrackerParams& params);
  /// Drops every track (ids keep rising); the next update() reports them in died().
  void reset();

 private:
  struct Filter {  // Kalman state of one track, in the same order as tracks_
    Eigen::Vector4d x = Eigen::Vector4d::Zero();
    Eigen::Matrix4d P = Eigen::Matrix4d::Identity();
    ClassEvidence class_evidence;  // accumulated class probabilities of its detections
  };
  struct Measurement {  // one detection in the fixed frame
    Eigen::Vector3d center;
    Eigen::Vector3d size;
    double yaw_rad;
    ObjectCategory category;
    float confidence;
    int index;  // in the caller's vector
  };

  void predict(double dt_s);
  void associate();
  void associateStage(bool tentative);
  void updateTrack(std::size_t t, const Measurement& m);
  void startTrack(const Measurement& m);
  bool confidentBirth(const Track& t) const;

  TrackerParams params_;
  std::vector<Track> tracks_;
  std::vector<Filter> filters_;
  std::vector<std::uint32_t> died_;
  std::vector<std::uint32_t> reset_died_;  // dropped by reset(), reported by the next update
  TrackerStats stats_;
  std::uint32_t next_id_ = 1;
  bool have_stamp_ = false;
  double last_stamp_s_ = 0.0;
  // Scratch, reused between revolutions.
  std::vector<Measurement> measurements_;
  std::vector<int> track_match_;  // per track: measurement index or -1
  std::vector<int> meas_match_;   // per measurement: track index or -1
  std::vector<int> parent_;       // union-find over tracks + measurements
  std::vector<std::vector<int>> group_rows_, group_cols_;
  std::vector<double> cost_, hungarian_scratch_;
  std::vector<int> local_row_, local_col_, row_to_col_;
  std::vector<int> assignment_;
  struct Pair {
    int track, meas;
    double cost;
  };
  std::vector<Pair> pairs_;
};

}  // namespace core
}  // namespace urban_detection
