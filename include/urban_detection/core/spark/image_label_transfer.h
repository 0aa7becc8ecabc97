/// \file image_label_transfer.h
/// Live transfer of a 2-D semantic segmentation onto detected 3-D objects: every object point is
/// projected into the camera image, looks up the class of its pixel in the network's scores, and
/// the object takes the class with the largest (confidence-weighted) vote. The detector finds
/// *where* objects are (detection paper Sec. 3.2), the image tells *what* they are (SPARK, second
/// seed paper Sec. 3.4, here with the real camera instead of a virtual one). ROS-free.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace core {

/// A pinhole camera looking at a rectified image: pixel (u, v) = (a / c, b / c) with
/// (a, b, c) = projection * (x, y, z, 1) for a point in the camera's optical frame (x right,
/// y down, z forward) [m]. ROS: CameraInfo.P; KITTI: P2 (with R0_rect in the extrinsics).
struct PinholeCamera {
  Eigen::Matrix<double, 3, 4> projection = Eigen::Matrix<double, 3, 4>::Zero();  ///< [px]
  int width_px = 0;   ///< [px] image width
  int height_px = 0;  ///< [px] image height

  /// False for a non-positive size, a non-finite matrix or focal lengths <= 0.
  bool valid() const;
  /// Projects a point of the optical frame; false when its depth z <= min_depth_m or the
  /// projection is not finite. (u, v) may lie outside the image.
  bool project(const Eigen::Vector3d& p_camera, double min_depth_m, double* u, double* v) const;
};

/// Parameters of the vote, mirrored in config/image_label_transfer.yaml (`transfer:`).
struct ImageLabelTransferParams {
  double min_depth_m = 0.5;     ///< [m] points closer to (or behind) the camera are ignored
  int min_points = 3;           ///< [-] objects with fewer considered points stay unknown
  double min_confidence = 0.3;  ///< [0..1] objects whose best confidence is lower stay unknown
  /// [m] a point is occluded (does not vote) when, in its image cell, a point of another object
  /// is closer to the camera by more than this; <= 0 disables the test.
  double occlusion_margin_m = 1.0;
  int occlusion_cell_px = 8;  ///< [px] side of the image cells of the occlusion test
  /// Classes that vote, indexed by class id (true = votes); empty = every class votes. Pixels
  /// of other classes (road, sky, building, ...) count as considered but vote for nothing.
  std::vector<bool> kept_classes;
};

/// "" when every field is in its table range (ParamFields<ImageLabelTransferParams> below).
std::string validate(const ImageLabelTransferParams& params);

/// ImageLabelTransferParams' field table (core/common/param_fields.h); kept_classes comes from
/// the model's class names (the nodelet's model/keep_classes).
template <>
struct ParamFields<ImageLabelTransferParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"min_depth_m", "m", 0.0, 100.0, "points closer to (or behind) the camera are ignored"},
      p.min_depth_m);
    f({"min_points", "points", 1, 1000000, "objects with fewer considered points stay unknown"},
      p.min_points);
    f({"min_confidence", "", 0.0, 1.0, "objects whose best confidence is lower stay unknown"},
      p.min_confidence);
    f({"occlusion_margin_m", "m", 0.0, 100.0,
       "a point is occluded when a point of another object in its image cell is closer by more "
       "than this (0: no occlusion test)"},
      p.occlusion_margin_m);
    f({"occlusion_cell_px", "px", 1, 256, "side of the image cells of the occlusion test"},
      p.occlusion_cell_px);
  }
};

/// The vote of one object.
struct ObjectClassVote {
  std::uint32_t object_id = 0;  ///< the object's label in the object points
  int class_id = -1;            ///< winning class, -1 = unknown (too few points, too unsure)
  /// [0..1] summed pixel confidence of the winning class / considered points (with confident
  /// pixels this is the share of the object's visible points that fall on the class).
  float confidence = 0.0f;
  int best_class_id = -1;        ///< best class even when rejected (for diagnostics)
  std::uint32_t points = 0;      ///< object points received
  std::uint32_t considered = 0;  ///< in front of the camera, inside the image, not occluded
  std::uint32_t occluded = 0;    ///< inside the image but behind another object
};

/// Statistics of the last transfer() call.
struct ImageLabelTransferStats {
  std::uint32_t points = 0;      ///< object points received
  std::uint32_t projected = 0;   ///< inside the image and in front of the camera
  std::uint32_t considered = 0;  ///< projected and not occluded
  std::uint32_t non_finite = 0;  ///< NaN/inf points skipped
};

/// Votes a class per object from a segmented camera image. Holds its scratch buffers between
/// frames (no allocation in steady state).
class ImageLabelTransfer {
 public:
  explicit ImageLabelTransfer(const ImageLabelTransferParams& params = {}) : params_(params) {}
  const ImageLabelTransferParams& params() const { return params_; }
  void setParams(const ImageLabelTransferParams& params) { params_ = params; }

  /// `object_points`: the detector's `objects/points` (label = object id) in the LiDAR frame;
  /// `camera_from_lidar`: transform of LiDAR-frame points into the camera's optical frame;
  /// `camera`: the rectified image the network saw (any size; the scores are sampled at the
  /// scaled pixel). `votes` is cleared and receives one entry per object id present, sorted by
  /// id. Non-finite points are skipped; an invalid camera or empty scores give all-unknown
  /// votes.
  void transfer(const LabeledCloud& object_points, const Eigen::Isometry3d& camera_from_lidar,
                const PinholeCamera& camera, const SegmentationScores& scores,
                std::vector<ObjectClassVote>* votes);
  const ImageLabelTransferStats& stats() const { return stats_; }
  /// Number of class ids of the last transfer() (the scores' classIdBound()).
  int classBound() const { return bound_; }
  /// Summed pixel confidence per class id (classBound() entries) of the object in `votes[slot]`
  /// of the last transfer(): every class counted, kept or not (the camera evidence the fusion
  /// of spark/camera_fusion.h reads). Null when that transfer had no usable camera or scores.
  const float* classScores(std::size_t slot) const {
    return bound_ > 0 && (slot + 1) * bound_ <= all_scores_.size()
               ? all_scores_.data() + slot * bound_
               : nullptr;
  }

 private:
  struct Projected {
    std::int32_t slot;    // index into votes
    std::int32_t cell;    // occlusion cell, -1 when the test is off
    float depth;          // [m]
    std::int32_t sx, sy;  // score-map pixel
  };
  ImageLabelTransferParams params_;
  ImageLabelTransferStats stats_;
  std::vector<std::uint32_t> ids_;        // sorted unique object ids
  std::vector<std::int32_t> slot_of_id_;  // object id -> slot (ids up to ~4x the points)
  std::vector<Projected> projected_;
  std::vector<float> cell_depth_;        // per occlusion cell: nearest depth
  std::vector<std::int32_t> cell_slot_;  // ... and the object slot it belongs to
  std::vector<float> scores_;            // [slot][class] summed confidences of kept classes
  std::vector<float> all_scores_;        // [slot][class] summed confidences of every class
  int bound_ = 0;
};

}  // namespace core
}  // namespace urban_detection
