/// \file camera_labeller.h
/// The camera stage's labelling of one revolution's objects, ROS-free: the objects' points vote
/// in one segmented image (ImageLabelTransfer), and the fusion mode decides the class each
/// object leaves with (camera_fusion.h):
///   camera: the network's class name ("unknown" when too unsure) where the camera sees the
///           object (at least fusion_rule/min_visible_points points), its LiDAR class elsewhere;
///   fused:  fuseObjectClass() of its LiDAR category and the camera's evidence; a vetoed object
///           is dropped, an unseen one keeps its label and confidence verbatim;
///   lidar:  every object as it came.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/image_label_transfer.h"

namespace urban_detection {
namespace core {

/// One object as the camera stage sees it.
struct ObjectClassLabel {
  std::uint32_t id = 0;           ///< its label in the object points
  std::string class_label;        ///< in: its LiDAR class; out: the class it leaves with
  float class_confidence = 0.0f;  ///< [0..1] likewise
  bool vetoed = false;            ///< out (fused): the camera saw background: drop the object
};

class CameraLabeller {
 public:
  /// `transfer.kept_classes`, `names` (class id -> name; "class_<id>" beyond) and `class_map`
  /// as loadCameraModel() gives them.
  CameraLabeller(const CameraFusionParams& fusion, const ImageLabelTransferParams& transfer,
                 std::vector<std::string> names, CameraClassMap class_map);

  /// Labels `objects` (sorted or not) from the camera image the network segmented into
  /// `scores`: `points` are the objects' points (label = object id) in the LiDAR frame,
  /// `camera_from_lidar` takes them into the camera's optical frame.
  void label(const LabeledCloud& points, const Eigen::Isometry3d& camera_from_lidar,
             const PinholeCamera& camera, const SegmentationScores& scores,
             std::vector<ObjectClassLabel>* objects);

  const CameraFusionParams& fusion() const { return fusion_; }
  /// The votes of the last label() call, sorted by object id.
  const std::vector<ObjectClassVote>& votes() const { return votes_; }
  const ImageLabelTransferStats& stats() const { return transfer_.stats(); }

 private:
  const ObjectClassVote* voteOf(std::uint32_t id) const;
  std::string className(int class_id) const;

  CameraFusionParams fusion_;
  ImageLabelTransfer transfer_;
  std::vector<std::string> names_;
  CameraClassMap class_map_;
  std::vector<ObjectClassVote> votes_;
};

}  // namespace core
}  // namespace urban_detection
