/// \file clear_mot.h
/// CLEAR-MOT scoring of a multi-object tracker (Bernardin and Stiefelhagen, "Evaluating Multiple
/// Object Tracking Performance: The CLEAR MOT Metrics", 2008), with the trajectory counts of Li,
/// Huang and Nevatia (2009): mostly tracked, mostly lost, fragmentations. ROS-free.
///
/// Objects are points in one fixed frame (box centres on the ground plane). Per frame:
///   1. a ground-truth (GT) object keeps the hypothesis it was matched to in the previous frame
///      when that hypothesis is still present and within `max_distance_m`;
///   2. the remaining GT objects and hypotheses are matched one to one by the Hungarian
///      algorithm on their distance, pairs farther than `max_distance_m` excluded;
///   3. hypotheses still unmatched are matched the same way to the ignored GT objects (too few
///      points, classes not scored) and then dropped: they are neither true nor false;
///   4. a match whose hypothesis differs from the one the GT object was last matched to (in any
///      earlier frame) is an identity switch; a GT object matched again after frames in which
///      it was present but unmatched counts a fragmentation;
///   5. unmatched GT objects are misses, unmatched hypotheses false positives unless marked
///      `dont_care` (e.g. inside a KITTI DontCare region).
/// MOTA = 1 - (misses + false positives + switches) / GT objects; MOTP = mean distance of the
/// matches [m]. A GT trajectory (one id) is mostly tracked when matched in at least 80 % of the
/// frames it is present (and not ignored), mostly lost below 20 %.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Core>

namespace urban_detection {
namespace core {

struct MotGroundTruth {
  std::uint32_t id = 0;                                // trajectory id, stable over frames
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // [m] fixed frame
  bool ignored = false;  // neither a miss nor a match; hypotheses on it are dropped
};

struct MotHypothesis {
  std::uint32_t id = 0;                                // track id
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // [m] fixed frame
  bool dont_care = false;                              // when unmatched, not a false positive
};

struct ClearMotParams {
  double max_distance_m = 2.0;  // [m] largest GT-to-hypothesis distance of a match
  double mostly_tracked = 0.8;  // [0..1] tracked fraction of a mostly tracked trajectory
  double mostly_lost = 0.2;     // [0..1] a trajectory tracked less than this is mostly lost
};

struct ClearMotResult {
  std::size_t frames = 0;
  std::size_t gt = 0;  // GT objects over all frames (not ignored)
  std::size_t matches = 0;
  std::size_t misses = 0;  // false negatives
  std::size_t false_positives = 0;
  std::size_t id_switches = 0;
  std::size_t fragmentations = 0;
  std::size_t gt_tracks = 0;  // GT trajectories present (not ignored) at least once
  std::size_t mostly_tracked = 0, partially_tracked = 0, mostly_lost = 0;
  double distance_sum_m = 0.0;

  double mota() const;       // 1 - (misses + false_positives + id_switches) / gt (1 when gt is 0)
  double motp_m() const;     // mean match distance [m] (0 without matches)
  double recall() const;     // matches / gt
  double precision() const;  // matches / (matches + false_positives)
  double idSwitchesPer100GtTracks() const;
};

class ClearMot {
 public:
  explicit ClearMot(const ClearMotParams& params = ClearMotParams());

  /// Scores one frame. `matched_hypothesis` (optional) receives, per GT object, the index of
  /// the hypothesis matched to it or -1 (also -1 for ignored GT objects).
  void addFrame(const std::vector<MotGroundTruth>& gt, const std::vector<MotHypothesis>& hyp,
                std::vector<int>* matched_hypothesis = nullptr);
  /// Totals so far, the trajectory counts included.
  ClearMotResult result() const;
  const ClearMotParams& params() const { return params_; }

 private:
  struct Trajectory {
    std::size_t present = 0, tracked = 0;
    bool has_last = false;             // matched in some earlier frame
    std::uint32_t last_hyp = 0;        // hypothesis of its latest match
    bool matched_in_previous = false;  // matched in the previous frame it was present in
    bool previous_frame = false;       // present in the frame just before (for step 1)
    std::size_t last_frame = 0;
  };
  ClearMotParams params_;
  ClearMotResult totals_;
  std::map<std::uint32_t, Trajectory> trajectories_;
};

}  // namespace core
}  // namespace urban_detection
