#include "urban_detection/core/classification/object_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace urban_detection {
namespace core {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

std::string validate(const ObjectFilterParams& p) {
  return checkFieldRanges(p);
}

ObjectFilter::ObjectFilter(const ObjectFilterParams& params) {
  setParams(params);
}

void ObjectFilter::setParams(const ObjectFilterParams& params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument("ObjectFilter: " + error);
  params_ = params;
}

void ObjectFilter::indexForeground(const LabeledCloud& foreground) {
  index_.build(foreground);
}

ObjectFeatures ObjectFilter::features(const LabeledCloud& foreground,
                                      const DetectedObject& object) {
  ObjectFeatures f;
  row_points_.clear();
  double zmin = 0.0, zmax = 0.0, isum = 0.0, isq = 0.0;
  // Azimuths relative to the object's centroid azimuth: no wrap at +-pi inside one object.
  const double az0 = std::atan2(object.centroid.y(), object.centroid.x());
  for (std::uint32_t idx : object.indices) {
    const LabeledPoint* found = index_.find(foreground, idx);
    if (!found) continue;
    const LabeledPoint& p = *found;
    if (!isFinitePoint(p)) continue;
    const double rho = std::hypot(p.x, p.y);
    const double r = std::sqrt(rho * rho + static_cast<double>(p.z) * p.z);
    if (!(r > 0.0)) continue;
    double az = std::atan2(p.y, p.x) - az0;
    if (az > M_PI) az -= 2.0 * M_PI;
    if (az < -M_PI) az += 2.0 * M_PI;
    row_points_.push_back(
        {static_cast<float>(std::atan2(p.z, rho)), static_cast<float>(az), static_cast<float>(r)});
    if (f.points == 0) zmin = zmax = p.z;
    zmin = std::min<double>(zmin, p.z);
    zmax = std::max<double>(zmax, p.z);
    const double in = std::isfinite(p.intensity) ? p.intensity : 0.0;
    isum += in;
    isq += in * in;
    ++f.points;
  }
  f.range_m = std::hypot(object.centroid.x(), object.centroid.y());
  f.length_m =
      std::max({object.obb_size.x(), object.obb_size.y(), object.max_pt.x() - object.min_pt.x(),
                object.max_pt.y() - object.min_pt.y()});
  if (f.points == 0) return f;
  f.height_m = zmax - zmin;
  f.mean_intensity = isum / f.points;
  f.std_intensity = std::sqrt(std::max(0.0, isq / f.points - f.mean_intensity * f.mean_intensity));

  // Scan rows: runs of elevation with gaps <= row_gap; inside a row, order by azimuth.
  std::sort(row_points_.begin(), row_points_.end(),
            [](const RowPoint& a, const RowPoint& b) { return a.elevation < b.elevation; });
  const float row_gap = static_cast<float>(params_.row_gap_deg * kDegToRad);
  const float max_gap = static_cast<float>(params_.max_azimuth_gap_deg * kDegToRad);
  std::size_t begin = 0;
  while (begin < row_points_.size()) {
    std::size_t end = begin + 1;
    while (end < row_points_.size() &&
           row_points_[end].elevation - row_points_[end - 1].elevation <= row_gap) {
      ++end;
    }
    std::sort(row_points_.begin() + begin, row_points_.begin() + end,
              [](const RowPoint& a, const RowPoint& b) { return a.azimuth < b.azimuth; });
    for (std::size_t k = begin + 1; k + 1 < end; ++k) {
      const RowPoint& a = row_points_[k - 1];
      const RowPoint& b = row_points_[k];
      const RowPoint& c = row_points_[k + 1];
      if (b.azimuth - a.azimuth > max_gap || c.azimuth - b.azimuth > max_gap) continue;
      ++f.triplets;
      if (std::abs(b.range - 0.5f * (a.range + c.range)) > params_.jump_m) ++f.jumps;
    }
    begin = end;
  }
  if (f.triplets > 0) f.jump_fraction = static_cast<double>(f.jumps) / f.triplets;
  return f;
}

RejectReason ObjectFilter::classify(const ObjectFeatures& f) const {
  if (params_.uniform_max_intensity_std > 0.0 &&
      f.points >= static_cast<std::size_t>(params_.uniform_min_points) &&
      f.std_intensity < params_.uniform_max_intensity_std) {
    return RejectReason::kUniform;
  }
  if (f.points < static_cast<std::size_t>(params_.min_points) ||
      !(f.range_m <= params_.max_range_m)) {
    return RejectReason::kNone;
  }
  if (f.triplets >= static_cast<std::size_t>(params_.min_triplets) &&
      f.jump_fraction > params_.max_jump_fraction) {
    return RejectReason::kPorous;
  }
  if (params_.hedge_min_intensity > 0.0 && f.mean_intensity > params_.hedge_min_intensity &&
      f.length_m >= params_.hedge_min_length_m) {
    return RejectReason::kBrightHedge;
  }
  return RejectReason::kNone;
}

ObjectFilterStats ObjectFilter::apply(const LabeledCloud& foreground,
                                      std::vector<DetectedObject>* objects,
                                      std::vector<DetectedObject>* rejected) {
  ObjectFilterStats s;
  s.input = objects->size();
  if (rejected) rejected->clear();
  if (!params_.enabled || objects->empty()) {
    s.kept = objects->size();
    return s;
  }
  indexForeground(foreground);
  kept_.clear();
  for (DetectedObject& o : *objects) {
    const ObjectFeatures f = features(foreground, o);
    if (f.points < static_cast<std::size_t>(params_.min_points) ||
        !(f.range_m <= params_.max_range_m)) {
      ++s.not_judged;
    }
    const RejectReason why = classify(f);
    if (why != RejectReason::kNone) {
      ++s.vegetation;
      ++(why == RejectReason::kPorous        ? s.porous
         : why == RejectReason::kBrightHedge ? s.bright_hedge
                                             : s.uniform);
      if (rejected) rejected->push_back(std::move(o));
      continue;
    }
    kept_.push_back(std::move(o));
  }
  objects->swap(kept_);
  renumberObjects(objects);
  s.kept = objects->size();
  return s;
}

}  // namespace core
}  // namespace urban_detection
