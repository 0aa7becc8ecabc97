/// \file tracking_eval.h
//// Tracking evaluation (urban_detection_eval --tracking): the pipeline (segmentation, detector,
//// classifier, box fitting) followed by the Tracker, scored with CLEAR-MOT (clear_mot.h).
//// ROS-free. Unreadable frames and sequences are skipped with a warning on stderr;
//// UD_TRACK_DEBUG=1 prints one line per identity switch on the simulated drive.
///
///   --tracking (with --sim GT --pcap PCAP): the simulated drive. The tracker gets each
///     revolution's sensor pose from the ground-truth file (world_T_velodyne), as the nodelet
///     gets odom -> velodyne from tf. GT objects are the scene's street objects (cars, vans,
///     pedestrians, cyclists, bins, benches) with at least --min-points returns in the
///     revolution, at their box centre in the world frame; street objects with fewer returns and
///     trunks, poles and signs are ignored (a track on them is neither true nor false); a track
///     anywhere else (vegetation, walls, ground) is a false positive. Hypotheses are the
///     confirmed tracks (detected in this revolution). Match: centre distance <= 2 m on the
///     ground plane. Speed error: |track speed - GT speed| of matched cars and vans that move
///     faster than 0.5 m/s. The detector's own recall and precision under the same matching
///     (every detection a hypothesis) are printed beside: MOTA cannot exceed that recall by
///     more than what coasting adds.
///   --tracking --semantic-kitti DIR (the dataset root with sequences/NN/, or one sequence
///     folder): each sequence's scans in order, the tracker in the world frame of poses.txt
///     (world_T_velodyne = Tr^-1 * pose_i * Tr, Tr from calib.txt, or the nominal KITTI
///     camera-from-LiDAR axes when calib.txt has no Tr), a fresh tracker per sequence. GT
///     objects: the thing instances (vehicles, persons, riders, two-wheelers; SemanticKITTI's
///     instance ids are stable through a sequence) with at least --min-points points, at the
///     centroid of their points in the world frame; emptier ones are ignored. Hypotheses:
///     confirmed tracks detected in this scan, at the centroid of their detection's points in
///     the world frame (SemanticKITTI has no boxes: both sides are centroids of points); one
///     whose detection is mostly don't-care points (poles, trunks, signs, other-object,
///     unlabelled) is not a false positive when unmatched. Match: distance <= 2 m.
///   --kitti-tracking DIR: velodyne/<seq>/*.bin, label_02/<seq>.txt, calib/<seq>.txt. No poses
///     are read (KITTI tracking's oxts are not used): the tracker runs in the sensor frame, so
///     velocities include the ego motion and are not scored. GT: Car and Van (vehicle),
///     Pedestrian and Cyclist labels with at least --min-points LiDAR points in their box;
///     Truck, Tram, Person_sitting, Misc and those with fewer points are ignored. Hypotheses:
///     confirmed tracks the classifier calls vehicle, pedestrian or cyclist (any confirmed
///     track with the classifier off) whose centre
///     projects into image 2 (1242 x 375); a hypothesis whose centre projects into a DontCare
///     rectangle is not a false positive when unmatched. Match: distance of the box centres on
///     the ground plane <= 2 m (not the devkit's image-box overlap).
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/tracking/clear_mot.h"

namespace urban_detection {
namespace core {

/// The pipeline whose tracker is scored (its `tracking` switch is turned on by the runs) and
/// the ground-truth rule.
struct TrackingEvalParams {
  PipelineParams params;
  std::size_t min_gt_points = 10;                         ///< fewer: the GT object is ignored
  std::size_t max_frames = static_cast<std::size_t>(-1);  ///< revolutions / scans read at most
};

/// The simulated drive (--tracking --sim GT --pcap PCAP).
struct SimTrackingResult {
  std::size_t frames = 0, skipped = 0;  ///< revolutions scored, skipped by the reader
  ClearMotResult tracker;               ///< confirmed tracks
  ClearMotResult detector;              ///< every detection a one-revolution hypothesis
  ClearMotResult oracle;                ///< the same tracker fed the scored GT boxes themselves
  std::vector<double> speed_error;      ///< [m/s] matched moving cars and vans (GT > 0.5 m/s)
  std::vector<double> static_speed;     ///< [m/s] track speed of matched parked cars and vans
  std::vector<double> update_ms;        ///< [ms] tracker update per revolution (wall clock)
};
/// False with `*error` when the drive cannot be read or has no revolution.
bool evaluateSimTracking(const TrackingEvalParams& p, const std::string& gt_path,
                         const std::string& pcap_path, const Calibration& calibration,
                         double cut_angle_deg, SimTrackingResult* out, std::string* error);

/// KITTI tracking (--kitti-tracking DIR), sensor frame.
struct KittiTrackingEvalResult {
  std::size_t sequences = 0, frames = 0;
  ClearMotResult tracker;
};
/// False with `*error` when DIR has no labels or no frame could be read.
bool evaluateKittiTracking(const TrackingEvalParams& p, const std::string& dir,
                           KittiTrackingEvalResult* out, std::string* error);

/// SemanticKITTI (--tracking --semantic-kitti DIR), world frame of poses.txt.
struct SemanticKittiTrackingEvalResult {
  std::size_t frames = 0;
  bool nominal_tr = false;  ///< a sequence without Tr in calib.txt used the nominal axes
  ClearMotResult tracker;   ///< pooled over the sequences
  ClearMotResult detector;  ///< every detection a one-scan hypothesis, pooled
  std::vector<std::pair<std::string, ClearMotResult>> per_sequence;
  std::vector<double> update_ms;  ///< [ms] tracker update per scan
};
/// False with `*error` when DIR has no sequence or no scan could be read.
bool evaluateSemanticKittiTracking(const TrackingEvalParams& p, const std::string& dir,
                                   SemanticKittiTrackingEvalResult* out, std::string* error);

/// One CLEAR-MOT result as a JSON object (counts, MOTA, MOTP, recall, precision, ...).
std::string motJson(const ClearMotResult& r);

/// The JSON reports of the three runs (results/tracking_*.json).
std::string simTrackingJson(const SimTrackingResult& r, const std::string& pcap);
std::string kittiTrackingJson(const KittiTrackingEvalResult& r, const std::string& dir);
std::string semanticKittiTrackingJson(const SemanticKittiTrackingEvalResult& r,
                                      const std::string& dir, std::size_t min_gt_points);

/// One CLEAR-MOT result as a line of the text summary, `what` in front.
std::string motLine(const char* what, const ClearMotResult& r);

/// The dataset of a tracking run: exactly one of a simulated drive, a SemanticKITTI folder
/// (EvalDatasetSource; no KITTI object frames) or a KITTI tracking folder.
struct TrackingEvalInput : EvalDatasetSource {
  std::string kitti_tracking_dir;
};

/// The tracking evaluation of `in` (evaluateSimTracking, evaluateSemanticKittiTracking or
/// evaluateKittiTracking): `text` the summary urban_detection_eval --tracking prints, `json`
/// its report. False with `error` (nothing read, a calibration that cannot be loaded).
bool runTrackingEvaluation(const TrackingEvalParams& p, const TrackingEvalInput& in,
                           std::string* text, std::string* json, std::string* error);

}  // namespace core
}  // namespace urban_detection
