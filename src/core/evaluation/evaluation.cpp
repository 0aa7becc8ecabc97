#include "urban_detection/core/evaluation/evaluation.h"

#include <algorithm>
#include <cmath>

#include <dlib/optimization/max_cost_assignment.h>

namespace urban_detection {
namespace core {

void EvalFrame::reset(std::size_t num_points) {
  objects.clear();
  object_of_point.assign(num_points, -1);
  role.assign(num_points, PointRole::kScored);
}

void EvalFrame::finalize(std::size_t min_points) {
  for (auto& o : objects) o.num_points = 0;
  const bool has_roles = role.size() == object_of_point.size();
  for (std::size_t i = 0; i < object_of_point.size(); ++i) {
    const std::int32_t g = object_of_point[i];
    if (g < 0 || static_cast<std::size_t>(g) >= objects.size()) continue;
    if (has_roles && role[i] == PointRole::kExcluded) continue;
    ++objects[g].num_points;
  }
  // An object needs at least one point to be matchable at all.
  const std::size_t needed = std::max<std::size_t>(1, min_points);
  for (auto& o : objects) {
    if (o.num_points < needed) o.ignored = true;
  }
}

double DetectionScore::precision() const {
  const std::size_t claimed = tp + fo;
  return claimed == 0 ? 1.0 : static_cast<double>(tp) / static_cast<double>(claimed);
}

double DetectionScore::recall() const {
  return no == 0 ? 1.0 : static_cast<double>(tp) / static_cast<double>(no);
}

double DetectionScore::fRate() const {
  const double p = precision();
  const double r = recall();
  return (p + r) <= 0.0 ? 0.0 : 2.0 * p * r / (p + r);
}

DetectionScore& DetectionScore::operator+=(const DetectionScore& o) {
  no += o.no;
  mo += o.mo;
  fo += o.fo;
  tp += o.tp;
  ignored += o.ignored;
  detections += o.detections;
  return *this;
}

std::vector<std::int32_t> assignMaxIou(const std::vector<std::vector<double>>& iou,
                                       double min_iou) {
  const std::size_t rows = iou.size();
  std::size_t cols = 0;
  for (const auto& r : iou) cols = std::max(cols, r.size());
  std::vector<std::int32_t> result(rows, -1);
  if (rows == 0 || cols == 0) return result;

  // dlib wants a square integer matrix. Only pairs at or above the threshold can become
  // matches, so only they earn anything: a bonus larger than any possible sum of IoU terms
  // (most valid matches first) plus their IoU scaled to integers with 1e-6 resolution (largest
  // total IoU second). Letting sub-threshold pairs contribute would let the optimiser trade a
  // valid match for two overlaps that count for nothing.
  const std::size_t n = std::max(rows, cols);
  const long kScale = 1000000;
  const long bonus = static_cast<long>(n + 1) * kScale;
  dlib::matrix<long> cost(static_cast<long>(n), static_cast<long>(n));
  cost = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < iou[r].size(); ++c) {
      const double v = iou[r][c];
      if (!(v >= min_iou) || !(v > 0.0)) continue;  // also drops NaN
      cost(static_cast<long>(r), static_cast<long>(c)) =
          bonus + std::lround(std::min(v, 1.0) * kScale);
    }
  }
  const std::vector<long> assignment = dlib::max_cost_assignment(cost);
  for (std::size_t r = 0; r < rows; ++r) {
    const long c = assignment[r];
    if (c < 0 || static_cast<std::size_t>(c) >= iou[r].size()) continue;
    if (iou[r][c] >= min_iou) result[r] = static_cast<std::int32_t>(c);
  }
  return result;
}

DetectionEvaluator::DetectionEvaluator(const EvaluationParams& params) : params_(params) {}

void DetectionEvaluator::evaluate(const EvalFrame& gt,
                                  const std::vector<DetectedObject>& detections,
                                  FrameMatch* match) {
  FrameMatch local;
  FrameMatch& m = match ? *match : local;
  const std::size_t num_det = detections.size();
  const std::size_t num_gt = gt.objects.size();
  const std::size_t num_points = gt.object_of_point.size();
  const bool has_roles = gt.role.size() == num_points;

  m.score = DetectionScore();
  m.verdict.assign(num_det, DetectionVerdict::kFalse);
  m.matched_gt.assign(num_det, -1);
  m.iou.assign(num_det, 0.0);
  m.matched_detection.assign(num_gt, -1);

  struct Overlap {
    std::uint32_t det;
    std::uint32_t gt;
    std::uint32_t inter;
  };
  std::vector<Overlap> overlaps;
  std::vector<std::size_t> scored(num_det, 0);     // scored points of each detection
  std::vector<std::size_t> dont_care(num_det, 0);  // don't-care or ignored-GT points
  gt_hits_.assign(num_gt, 0);

  for (std::size_t d = 0; d < num_det; ++d) {
    touched_.clear();
    for (const std::uint32_t idx : detections[d].indices) {
      if (idx >= num_points) continue;
      const PointRole role = has_roles ? gt.role[idx] : PointRole::kScored;
      if (role == PointRole::kExcluded) continue;
      ++scored[d];
      const std::int32_t g = gt.object_of_point[idx];
      if (g >= 0 && static_cast<std::size_t>(g) < num_gt) {
        if (gt_hits_[g]++ == 0) touched_.push_back(g);
        if (gt.objects[g].ignored) ++dont_care[d];
      } else if (role == PointRole::kDontCare) {
        ++dont_care[d];
      }
    }
    for (const std::int32_t g : touched_) {
      overlaps.push_back(
          {static_cast<std::uint32_t>(d), static_cast<std::uint32_t>(g), gt_hits_[g]});
      gt_hits_[g] = 0;
    }
  }

  // Only detections and GT objects that overlap something take part in the assignment; the
  // rest are unmatched by construction, which keeps the Hungarian matrix small.
  std::vector<std::int32_t> det_row(num_det, -1), gt_col(num_gt, -1);
  std::vector<std::uint32_t> row_det, col_gt;
  for (const Overlap& o : overlaps) {
    if (det_row[o.det] < 0) {
      det_row[o.det] = static_cast<std::int32_t>(row_det.size());
      row_det.push_back(o.det);
    }
    if (gt_col[o.gt] < 0) {
      gt_col[o.gt] = static_cast<std::int32_t>(col_gt.size());
      col_gt.push_back(o.gt);
    }
  }
  std::vector<std::vector<double>> iou(row_det.size(), std::vector<double>(col_gt.size(), 0.0));
  for (const Overlap& o : overlaps) {
    const double uni = static_cast<double>(scored[o.det]) +
                       static_cast<double>(gt.objects[o.gt].num_points) - o.inter;
    iou[det_row[o.det]][gt_col[o.gt]] = uni > 0.0 ? o.inter / uni : 0.0;
  }
  const std::vector<std::int32_t> assigned = assignMaxIou(iou, params_.min_iou);

  for (std::size_t r = 0; r < row_det.size(); ++r) {
    if (assigned[r] < 0) continue;
    const std::uint32_t d = row_det[r];
    const std::uint32_t g = col_gt[assigned[r]];
    m.matched_gt[d] = static_cast<std::int32_t>(g);
    m.iou[d] = iou[r][assigned[r]];
    m.matched_detection[g] = static_cast<std::int32_t>(d);
  }

  DetectionScore& s = m.score;
  for (const auto& o : gt.objects) {
    if (!o.ignored) ++s.no;
  }
  for (std::size_t d = 0; d < num_det; ++d) {
    DetectionVerdict v;
    if (m.matched_gt[d] >= 0) {
      v = gt.objects[m.matched_gt[d]].ignored ? DetectionVerdict::kIgnored
                                              : DetectionVerdict::kTrue;
    } else if (scored[d] == 0 || static_cast<double>(dont_care[d]) >
                                     params_.ignore_majority * static_cast<double>(scored[d])) {
      v = DetectionVerdict::kIgnored;
    } else {
      v = DetectionVerdict::kFalse;
    }
    m.verdict[d] = v;
    if (v == DetectionVerdict::kTrue) ++s.tp;
    if (v == DetectionVerdict::kFalse) ++s.fo;
    if (v == DetectionVerdict::kIgnored) ++s.ignored;
  }
  s.mo = s.no - s.tp;
  s.detections = num_det;
  total_ += s;
}

}  // namespace core
}  // namespace urban_detection
