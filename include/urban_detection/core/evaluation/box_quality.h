/// \file box_quality.h
/// Quality of detected boxes against labelled 3-D boxes, in the bird's-eye view. ROS-free.
///
/// Per labelled object that a detection matched (the detection scoring of evaluation.h decides
/// the match, by point sets): centre error (distance of the box centres on the ground plane
/// [m]), heading error (difference of the yaws modulo 180 deg, so a box turned half way round
/// is right: [0, 90] deg) and bird's-eye IoU (intersection over union of the two rotated
/// rectangles, bevIoU of box_fitting.h). Summaries per class and range bin (range: distance of
/// the labelled centre from the sensor on the ground plane): labelled objects, matched ones,
/// medians of the three errors over the matched, and the share of the matched with IoU >= a
/// threshold.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

/// A box on the ground plane: centre [m], length and width [m], yaw of the length [rad].
struct GroundBox {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double length_m = 0.0, width_m = 0.0, yaw_rad = 0.0;
};

/// The ground box of a detected object's yaw-oriented box.
GroundBox groundBoxOf(const DetectedObject& o);

/// One labelled object.
struct BoxQualitySample {
  ObjectCategory category = ObjectCategory::kUnknown;
  double range_m = 0.0;  // [m] of the labelled centre
  bool matched = false;
  double center_error_m = 0.0;     // [m] when matched
  double heading_error_deg = 0.0;  // [deg] 0..90, when matched
  double iou = 0.0;                // bird's-eye IoU, when matched
};

/// The sample of a labelled box `gt` and, when `detection` is not null, its matched box.
BoxQualitySample scoreBox(ObjectCategory category, const GroundBox& gt, const GroundBox* detection);

/// Summary of the samples of one class within [min_range_m, max_range_m).
struct BoxQualitySummary {
  std::size_t labelled = 0, matched = 0;
  double median_center_error_m = 0.0;     // NaN without matches
  double median_heading_error_deg = 0.0;  // NaN without matches
  double median_iou = 0.0;                // NaN without matches
  double share_iou_at_least = 0.0;        // of the matched; NaN without matches
};

BoxQualitySummary summarize(const std::vector<BoxQualitySample>& samples, ObjectCategory category,
                            double min_range_m, double max_range_m, double iou_threshold = 0.5);

}  // namespace core
}  // namespace urban_detection
