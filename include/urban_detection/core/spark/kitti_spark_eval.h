/// \file kitti_spark_eval.h
/// KITTI object frames for the camera stage: one frame's cloud, labels, calibration
/// and image as the live transfer sees them (a pinhole camera and the camera <- LiDAR
/// transform), the objects made of the points of each labelled 3-D box, and the KITTI type ->
/// object category rule of the evaluation. Used by `urban_detection_spark kitti` and the tests.
/// ROS-free.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/spark/image_label_transfer.h"

namespace urban_detection {
namespace core {

/// One KITTI object frame `id` ("000003") of `dir` (calib/, label_2/, velodyne/, image_2/).
struct KittiSparkFrame {
  std::string id;
  KittiCalibration calib;
  std::vector<KittiLabel> labels;
  CloudXYZIRT cloud;
  cv::Mat image;         ///< BGR image_2 (empty when not loaded)
  PinholeCamera camera;  ///< P2 and the image size
  Eigen::Isometry3d camera_from_velo = Eigen::Isometry3d::Identity();  ///< R0_rect * Tr_velo_to_cam
};

/// Reads the frame; `with_image` false reads only the PNG's size. False with `error`.
bool loadKittiSparkFrame(const std::string& dir, const std::string& id, bool with_image,
                         KittiSparkFrame* frame, std::string* error);

/// The evaluation's category of a KITTI type: Car, Van, Truck -> vehicle; Pedestrian,
/// Person_sitting -> pedestrian; Cyclist -> cyclist; anything else (Tram, Misc, DontCare)
/// kUnknown (not scored).
ObjectCategory kittiTypeCategory(const std::string& type);

/// The points strictly inside labelled box `label` (not DontCare), excluding the bottom
/// `ground_band_m` (the road under it), as indices into frame.cloud.
std::vector<std::size_t> kittiBoxPoints(const KittiSparkFrame& frame, const KittiLabel& label,
                                        double ground_band_m = 0.2);

/// The labelled objects as the transfer's input: the points of label k get object id k + 1
/// (DontCare labels get none).
void kittiLabelObjects(const KittiSparkFrame& frame, LabeledCloud* points,
                       double ground_band_m = 0.2);

/// [m] horizontal distance of a label from the LiDAR (its box centre).
double kittiLabelRange(const KittiSparkFrame& frame, const KittiLabel& label);

/// The "box oracle" segmentation: label k's 2-D box painted with the index of its type in
/// `names` (types not in `names` left out), far boxes first so that near ones cover them;
/// 0 elsewhere. The size of frame.image.
cv::Mat kittiBoxOracleMask(const KittiSparkFrame& frame, const std::vector<std::string>& names);

/// Per cloud point: the index of the label (not DontCare) whose box, grown by 20 cm in length
/// and width and 10 cm in height, holds it (no ground band), else -1.
std::vector<int> kittiPointOwners(const KittiSparkFrame& frame);

/// The truth of one detection for the camera-fusion precision: made mostly of points in the
/// camera view (`in_view`), true when most of those lie in one label's box (`label`, with the
/// category of its type), left out (`scored` false) when out of view or, not true, mostly in
/// DontCare rectangles.
struct KittiDetectionTruth {
  bool scored = false;
  bool is_true = false;
  int label = -1;  // index into frame.labels when is_true
  ObjectCategory truth = ObjectCategory::kNonObject;
};
KittiDetectionTruth kittiDetectionTruth(const KittiSparkFrame& frame,
                                        const std::vector<int>& owners, const DetectedObject& o);

/// Precision counts of the in-view detections under one class rule (LiDAR only, fused).
struct SparkPrecisionCounts {
  int kept = 0, true_objects = 0, class_correct = 0, vetoed = 0, vetoed_true = 0;
  /// One scored detection given category `given` (kNonObject: vetoed).
  void add(ObjectCategory given, const KittiDetectionTruth& t);
  /// {"kept", "true", "class_correct", "vetoed", "vetoed_true", "precision", "class_precision"}
  std::string json() const;
};

}  // namespace core
}  // namespace urban_detection
