/// \file kitti_box_quality.h
//// Box quality of urban_detection_eval on KITTI object frames (--kitti-object): each labelled
/// vehicle (Car, Van, Truck), Pedestrian and Cyclist that the detection scoring matched to a
/// detection (point sets, IoU >= 0.5, evaluation.h) is compared with the detection's box in
/// the bird's-eye view (core/evaluation/box_quality.h): centre error, heading error modulo
/// 180 deg, bird's-eye IoU; per class and range bin, printed and in the JSON (`box_quality`).
/// Labelled objects the ground truth ignores (fewer than --min-points points) are left out.
/// Beside it, the box fitting alone: the same BoxFitter on each labelled object's own points
/// (the points in its box, without the ground band) with its labelled class, so a missed or
/// misclassified detection does not hide how well the boxes are fitted. UD_BOX_DEBUG=1 prints
/// each labelled object's box and its fitted box (the second table) on stderr.
//// ROS-free.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/evaluation/box_quality.h"
#include "urban_detection/core/evaluation/evaluation.h"

namespace urban_detection {
namespace core {

/// The box-quality samples of the KITTI object frames of one dataset folder.
class KittiBoxQuality {
 public:
  KittiBoxQuality(const std::string& dir, const BoxFittingParams& params)
      : dir_(dir), fitter_(params) {}

  /// One frame: `gt` as built by KittiObjectDataset (object id = label line number), the
  /// detections and their match.
  void addFrame(const std::string& frame_id, const CloudXYZIRT& cloud, const EvalFrame& gt,
                const std::vector<DetectedObject>& objects, const FrameMatch& match);

  /// One row of a table: a class and a range bin.
  struct Row {
    ObjectCategory category;
    std::string name;  ///< "0-20m", "20-40m", "40m+", "0-40m", "all"
    double min_m, max_m;
  };
  /// The rows of the tables, in order (vehicle, pedestrian, cyclist x range bins).
  static std::vector<Row> rows();

  /// Matched detections (the pipeline) and the box fitting alone on the labelled points.
  const std::vector<BoxQualitySample>& detections() const { return samples_; }
  const std::vector<BoxQualitySample>& labelledPoints() const { return own_; }

  /// The JSON object of `box_quality`.
  std::string json() const;
  /// The two tables (matched detections, box fitting alone) as urban_detection_eval prints
  /// them: per class and range bin labelled, matched, median centre and heading errors, median
  /// IoU and the share with IoU >= 0.5 (bins without labelled objects left out).
  std::string tables() const;

 private:
  std::string dir_;
  BoxFitter fitter_;
  std::vector<BoxQualitySample> samples_, own_;  // detections, labelled points
};

}  // namespace core
}  // namespace urban_detection
