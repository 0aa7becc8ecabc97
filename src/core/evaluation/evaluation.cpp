#include "urban_detection/core/evaluation/evaluation.h"

#include "urban_detection/core/tracking/hungarian.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

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

  // A square matrix for the minimum-cost assignment (tracking/hungarian.h), of negated
  // profits. Only pairs at or above the threshold can become matches, so only they earn
  // anything: a bonus larger than any possible sum of IoU terms (most valid matches first) plus
  // their IoU in integer steps of 1e-6 (largest total IoU second; integers keep the sums exact).
  // Letting sub-threshold pairs contribute would let the optimiser trade a valid match for two
  // overlaps that count for nothing.
  const std::size_t n = std::max(rows, cols);
  const double kScale = 1e6;
  const double bonus = static_cast<double>(n + 1) * kScale;
  std::vector<double> cost(n * n, 0.0);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < iou[r].size(); ++c) {
      const double v = iou[r][c];
      if (!(v >= min_iou) || !(v > 0.0)) continue;  // also drops NaN
      cost[r * n + c] = -(bonus + std::round(std::min(v, 1.0) * kScale));
    }
  }
  std::vector<int> assignment;
  solveAssignment(cost, static_cast<int>(n), static_cast<int>(n), &assignment);
  for (std::size_t r = 0; r < rows; ++r) {
    const int c = assignment[r];
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
  // Small objects (min_points) count only when matched.
  for (std::size_t g = 0; g < num_gt; ++g) {
    const EvalObject& o = gt.objects[g];
    if (!o.ignored && (o.num_points >= params_.min_points || m.matched_detection[g] >= 0)) ++s.no;
  }
  for (std::size_t d = 0; d < num_det; ++d) {
    DetectionVerdict v;
    if (m.matched_gt[d] >= 0) {
      v = gt.objects[m.matched_gt[d]].ignored ? DetectionVerdict::kIgnored
                                              : DetectionVerdict::kTrue;
    } else if (scored[d] == 0 || scored[d] < params_.min_points ||
               static_cast<double>(dont_care[d]) >
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

// ------------------------------------------------------------------------------------------
// RecallBreakdown

const char* RecallBreakdown::className(int c) {
  static const char* const kNames[kClasses] = {"vehicle", "pedestrian", "cyclist", "other_object"};
  return c >= 0 && c < kClasses ? kNames[c] : "?";
}

const char* RecallBreakdown::pointBinName(int b) {
  static const char* const kNames[kPointBins] = {"<30", "30-100", "100-300", ">=300"};
  return b >= 0 && b < kPointBins ? kNames[b] : "?";
}

const char* RecallBreakdown::rangeBinName(int b) {
  static const char* const kNames[kRangeBins] = {"<20m", "20-40m", ">=40m"};
  return b >= 0 && b < kRangeBins ? kNames[b] : "?";
}

int RecallBreakdown::classIndex(const std::string& gt_label) {
  switch (categoryOfClassName(gt_label)) {
    case ObjectCategory::kVehicle:
      return 0;
    case ObjectCategory::kPedestrian:
      return 1;
    case ObjectCategory::kCyclist:
      return 2;
    case ObjectCategory::kOtherObject:
      return 3;
    default:
      return -1;
  }
}

namespace {

int pointBin(std::size_t n) {
  return n < 30 ? 0 : n < 100 ? 1 : n < 300 ? 2 : 3;
}

int rangeBin(float r) {
  return r < 20.0f ? 0 : r < 40.0f ? 1 : 2;
}

ObjectCategory categoryOfIndex(int c) {
  static const ObjectCategory kCats[RecallBreakdown::kClasses] = {
      ObjectCategory::kVehicle, ObjectCategory::kPedestrian, ObjectCategory::kCyclist,
      ObjectCategory::kOtherObject};
  return kCats[c];
}

}  // namespace

void RecallBreakdown::addFrame(const EvalFrame& gt, const FrameMatch& match,
                               const std::vector<DetectedObject>& detections,
                               const std::vector<float>& gt_range_m, std::size_t min_points) {
  for (std::size_t g = 0; g < gt.objects.size(); ++g) {
    const EvalObject& o = gt.objects[g];
    if (o.ignored) continue;
    const bool found = g < match.matched_detection.size() && match.matched_detection[g] >= 0;
    const int c = classIndex(o.label);
    const int pb = pointBin(o.num_points);
    const int rb = rangeBin(g < gt_range_m.size() ? gt_range_m[g] : 0.0f);
    by_points[pb].total += 1;
    by_points[pb].found += found;
    by_range[rb].total += 1;
    by_range[rb].found += found;
    if (c < 0) continue;
    class_by_points[c][pb].total += 1;
    class_by_points[c][pb].found += found;
    class_by_range[c][rb].total += 1;
    class_by_range[c][rb].found += found;
    if (o.num_points >= min_points || found) {
      by_class[c].total += 1;
      by_class[c].found += found;
    }
    if (found) {
      const std::int32_t d = match.matched_detection[g];
      if (static_cast<std::size_t>(d) < detections.size()) {
        ++class_kept[c];
        class_correct[c] += detections[d].category == categoryOfIndex(c);
      }
    }
  }
}

RecallBreakdown& RecallBreakdown::operator+=(const RecallBreakdown& o) {
  for (int c = 0; c < kClasses; ++c) {
    by_class[c] += o.by_class[c];
    class_kept[c] += o.class_kept[c];
    class_correct[c] += o.class_correct[c];
    for (int b = 0; b < kPointBins; ++b) class_by_points[c][b] += o.class_by_points[c][b];
    for (int b = 0; b < kRangeBins; ++b) class_by_range[c][b] += o.class_by_range[c][b];
  }
  for (int b = 0; b < kPointBins; ++b) by_points[b] += o.by_points[b];
  for (int b = 0; b < kRangeBins; ++b) by_range[b] += o.by_range[b];
  return *this;
}

double RecallBreakdown::classAccuracy(int c) const {
  return class_kept[c] == 0 ? 1.0 : static_cast<double>(class_correct[c]) / class_kept[c];
}

std::string RecallBreakdown::table(const std::string& indent) const {
  std::ostringstream o;
  char b[200];
  auto cell = [&b](const Count& k) {
    std::snprintf(b, sizeof b, " %4zu/%-4zu %5.3f", k.found, k.total, k.recall());
    return std::string(b);
  };
  o << indent << "recall per class (min-points rule) and class right of the kept:\n";
  for (int c = 0; c < kClasses; ++c) {
    std::snprintf(b, sizeof b, "%s  %-13s", indent.c_str(), className(c));
    o << b << cell(by_class[c]);
    std::snprintf(b, sizeof b, "   class right %4zu/%-4zu\n", class_correct[c], class_kept[c]);
    o << b;
  }
  o << indent << "recall by points (every GT object): ";
  for (int k = 0; k < kPointBins; ++k) o << " " << pointBinName(k) << cell(by_points[k]);
  o << "\n" << indent << "recall by range (every GT object):  ";
  for (int k = 0; k < kRangeBins; ++k) o << " " << rangeBinName(k) << cell(by_range[k]);
  o << "\n";
  for (int c = 0; c < 3; ++c) {
    std::snprintf(b, sizeof b, "%s  %-11s points:", indent.c_str(), className(c));
    o << b;
    for (int k = 0; k < kPointBins; ++k) o << " " << pointBinName(k) << cell(class_by_points[c][k]);
    o << "  range:";
    for (int k = 0; k < kRangeBins; ++k) o << " " << rangeBinName(k) << cell(class_by_range[c][k]);
    o << "\n";
  }
  return o.str();
}

std::string RecallBreakdown::json() const {
  std::ostringstream o;
  auto count = [](const Count& k) {
    std::ostringstream c;
    c << "{\"found\": " << k.found << ", \"total\": " << k.total << ", \"recall\": " << k.recall()
      << "}";
    return c.str();
  };
  o << "{\"by_class\": {";
  for (int c = 0; c < kClasses; ++c) {
    o << (c ? ", " : "") << "\"" << className(c) << "\": {\"recall\": " << count(by_class[c])
      << ", \"kept\": " << class_kept[c] << ", \"class_right\": " << class_correct[c]
      << ", \"by_points\": {";
    for (int k = 0; k < kPointBins; ++k) {
      o << (k ? ", " : "") << "\"" << pointBinName(k) << "\": " << count(class_by_points[c][k]);
    }
    o << "}, \"by_range\": {";
    for (int k = 0; k < kRangeBins; ++k) {
      o << (k ? ", " : "") << "\"" << rangeBinName(k) << "\": " << count(class_by_range[c][k]);
    }
    o << "}}";
  }
  o << "}, \"by_points\": {";
  for (int k = 0; k < kPointBins; ++k) {
    o << (k ? ", " : "") << "\"" << pointBinName(k) << "\": " << count(by_points[k]);
  }
  o << "}, \"by_range\": {";
  for (int k = 0; k < kRangeBins; ++k) {
    o << (k ? ", " : "") << "\"" << rangeBinName(k) << "\": " << count(by_range[k]);
  }
  o << "}}";
  return o.str();
}

std::vector<float> gtObjectRanges(const EvalFrame& gt, const CloudXYZIRT& cloud) {
  const std::size_t n = std::min(cloud.size(), gt.object_of_point.size());
  const bool has_roles = gt.role.size() == gt.object_of_point.size();
  std::vector<double> sx(gt.objects.size(), 0.0), sy(gt.objects.size(), 0.0);
  std::vector<std::size_t> cnt(gt.objects.size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t g = gt.object_of_point[i];
    if (g < 0 || static_cast<std::size_t>(g) >= gt.objects.size()) continue;
    if (has_roles && gt.role[i] == PointRole::kExcluded) continue;
    if (!std::isfinite(cloud[i].x) || !std::isfinite(cloud[i].y)) continue;
    sx[g] += cloud[i].x;
    sy[g] += cloud[i].y;
    ++cnt[g];
  }
  std::vector<float> r(gt.objects.size(), 0.0f);
  for (std::size_t g = 0; g < r.size(); ++g) {
    if (cnt[g] > 0) r[g] = static_cast<float>(std::hypot(sx[g] / cnt[g], sy[g] / cnt[g]));
  }
  return r;
}

}  // namespace core
}  // namespace urban_detection
