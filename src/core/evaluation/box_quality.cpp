#include "urban_detection/core/evaluation/box_quality.h"

#include <algorithm>
#include <cmath>

#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/evaluation/report.h"

namespace urban_detection {
namespace core {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

GroundBox groundBoxOf(const DetectedObject& o) {
  GroundBox b;
  b.center = o.obb_center.head<2>().cast<double>();
  b.length_m = o.obb_size.x();
  b.width_m = o.obb_size.y();
  b.yaw_rad = o.obb_yaw_rad;
  return b;
}

BoxQualitySample scoreBox(ObjectCategory category, const GroundBox& gt, const GroundBox* det) {
  BoxQualitySample s;
  s.category = category;
  s.range_m = gt.center.norm();
  if (!det) return s;
  s.matched = true;
  s.center_error_m = (det->center - gt.center).norm();
  double d = std::fmod(std::fabs(det->yaw_rad - gt.yaw_rad), kPi);
  if (d > 0.5 * kPi) d = kPi - d;
  s.heading_error_deg = d * 180.0 / kPi;
  s.iou = bevIoU(det->center, det->length_m, det->width_m, det->yaw_rad, gt.center, gt.length_m,
                 gt.width_m, gt.yaw_rad);
  return s;
}

BoxQualitySummary summarize(const std::vector<BoxQualitySample>& samples, ObjectCategory category,
                            double min_range_m, double max_range_m, double iou_threshold) {
  BoxQualitySummary r;
  std::vector<double> center, heading, iou;
  std::size_t good = 0;
  for (const BoxQualitySample& s : samples) {
    if (s.category != category || s.range_m < min_range_m || s.range_m >= max_range_m) continue;
    ++r.labelled;
    if (!s.matched) continue;
    ++r.matched;
    center.push_back(s.center_error_m);
    heading.push_back(s.heading_error_deg);
    iou.push_back(s.iou);
    good += s.iou >= iou_threshold;
  }
  r.median_center_error_m = median(center);
  r.median_heading_error_deg = median(heading);
  r.median_iou = median(iou);
  r.share_iou_at_least = r.matched ? static_cast<double>(good) / r.matched : std::nan("");
  return r;
}

}  // namespace core
}  // namespace urban_detection
