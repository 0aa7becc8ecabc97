#include "urban_detection/core/classification/object_features.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace urban_detection {
namespace core {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

const char* const kFeatureNames[kNumObjectFeatures] = {"points",
                                                       "points_at_10m",
                                                       "range_m",
                                                       "length_m",
                                                       "width_m",
                                                       "height_m",
                                                       "footprint_m2",
                                                       "bottom_m",
                                                       "top_m",
                                                       "mean_above_bottom_m",
                                                       "std_z_m",
                                                       "linearity",
                                                       "planarity",
                                                       "scattering",
                                                       "normal_z",
                                                       "principal_z",
                                                       "xy_elongation",
                                                       "profile_0",
                                                       "profile_1",
                                                       "profile_2",
                                                       "profile_3",
                                                       "below_0_5m",
                                                       "above_1_5m",
                                                       "rows",
                                                       "points_per_row",
                                                       "azimuth_fill",
                                                       "row_neighbours",
                                                       "jump_fraction",
                                                       "mean_second_diff_m",
                                                       "intensity_mean",
                                                       "intensity_std",
                                                       "intensity_q10",
                                                       "intensity_q50",
                                                       "intensity_q90",
                                                       "intensity_max"};

// Buckets of the rank selection: linear in the value between the smallest and the largest
// (so monotone: every value of a bucket lies below every value of a later one), computed in
// double so that neither a tiny nor a huge spread can overflow. Objects with fewer values
// than kDirectSelect select directly.
constexpr int kRankBuckets = 256;
constexpr std::size_t kDirectSelect = 64;

// Ranges up to this long std::sort orders by insertion sort alone, which keeps equal elements
// in their order (libstdc++: _S_threshold); elsewhere no range is assumed to be.
#ifdef __GLIBCXX__
constexpr std::size_t kStableSortRow = 16;
#else
constexpr std::size_t kStableSortRow = 1;
#endif

}  // namespace

void selectRanks(const std::vector<float>& values, const std::size_t* ranks, int count, float* out,
                 std::vector<float>* scratch) {
  const std::size_t n = values.size();
  if (count <= 0 || n == 0) return;
  if (n < kDirectSelect) {
    // Few values: one copy, then each rank selected among the values above the previous one
    // (nth_element leaves every value past the k-th not below it).
    scratch->assign(values.begin(), values.end());
    std::size_t from = 0;
    for (int r = 0; r < count; ++r) {
      const std::size_t k = ranks[r];
      if (r > 0 && k == ranks[r - 1]) {
        out[r] = out[r - 1];
        continue;
      }
      const auto kth = scratch->begin() + static_cast<std::ptrdiff_t>(k);
      std::nth_element(scratch->begin() + static_cast<std::ptrdiff_t>(from), kth, scratch->end());
      out[r] = *kth;
      from = k + 1;
    }
    return;
  }
  float lo = values[0], hi = values[0];
  for (const float v : values) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (!(hi > lo)) {  // all equal
    for (int r = 0; r < count; ++r) out[r] = lo;
    return;
  }
  const double base = lo;
  const double scale = kRankBuckets / (static_cast<double>(hi) - base);
  auto bucketOf = [base, scale](float v) {
    return std::min(kRankBuckets - 1, static_cast<int>((static_cast<double>(v) - base) * scale));
  };
  std::uint32_t start[kRankBuckets + 1] = {};
  for (const float v : values) ++start[bucketOf(v) + 1];
  for (int b = 1; b <= kRankBuckets; ++b) start[b] += start[b - 1];
  // The buckets holding the ranks (ascending, at most `count` distinct ones), and one pass
  // gathering their values into consecutive segments of scratch.
  constexpr int kMaxTargets = 8;
  int target[kMaxTargets];
  std::size_t offset[kMaxTargets + 1];
  int targets = 0;
  int b = 0;
  for (int r = 0; r < count; ++r) {
    while (start[b + 1] <= ranks[r]) ++b;
    if (targets > 0 && target[targets - 1] == b) continue;
    if (targets == kMaxTargets) break;  // more ranks than this: the rest below, bucket by bucket
    target[targets++] = b;
  }
  offset[0] = 0;
  for (int t = 0; t < targets; ++t)
    offset[t + 1] = offset[t] + (start[target[t] + 1] - start[target[t]]);
  scratch->resize(offset[targets]);
  std::size_t fill[kMaxTargets];
  for (int t = 0; t < targets; ++t) fill[t] = offset[t];
  float* dst = scratch->data();
  for (const float v : values) {
    const int vb = bucketOf(v);
    for (int t = 0; t < targets; ++t) {
      if (vb == target[t]) {
        dst[fill[t]++] = v;
        break;
      }
    }
  }
  int t = 0;
  std::vector<float> extra;  // only for more than kMaxTargets distinct buckets
  for (int r = 0; r < count; ++r) {
    const std::size_t k = ranks[r];
    if (r > 0 && k == ranks[r - 1]) {
      out[r] = out[r - 1];
      continue;
    }
    while (t < targets && start[target[t] + 1] <= k) ++t;
    if (t < targets && start[target[t]] <= k) {
      const auto first = scratch->begin() + static_cast<std::ptrdiff_t>(offset[t]);
      const auto last = scratch->begin() + static_cast<std::ptrdiff_t>(offset[t + 1]);
      const auto kth = first + static_cast<std::ptrdiff_t>(k - start[target[t]]);
      std::nth_element(first, kth, last);
      out[r] = *kth;
      continue;
    }
    int kb = 0;
    while (start[kb + 1] <= k) ++kb;
    extra.clear();
    for (const float v : values) {
      if (bucketOf(v) == kb) extra.push_back(v);
    }
    const auto kth = extra.begin() + static_cast<std::ptrdiff_t>(k - start[kb]);
    std::nth_element(extra.begin(), kth, extra.end());
    out[r] = *kth;
  }
}

namespace {

// Orders [first, first + n) by `less` (a strict weak order) keeping equal elements in their
// order: the ascending runs are found, then merged pairwise through `tmp`. A row of a few
// interleaved runs costs n log(runs). `bounds` and `next` are scratch.
template <class T, class Less>
void mergeAscendingRuns(T* first, std::size_t n, Less less, std::vector<T>* tmp,
                        std::vector<std::size_t>* bounds, std::vector<std::size_t>* next) {
  bounds->clear();
  bounds->push_back(0);
  for (std::size_t k = 1; k < n; ++k) {
    if (less(first[k], first[k - 1])) bounds->push_back(k);
  }
  bounds->push_back(n);
  if (bounds->size() <= 2) return;
  tmp->resize(n);
  T* src = first;
  T* dst = tmp->data();
  while (bounds->size() > 2) {
    next->clear();
    next->push_back(0);
    const std::size_t runs = bounds->size() - 1;
    for (std::size_t r = 0; r < runs; r += 2) {
      const std::size_t a = (*bounds)[r], b = (*bounds)[r + 1];
      if (r + 1 < runs) {
        const std::size_t c = (*bounds)[r + 2];
        std::merge(src + a, src + b, src + b, src + c, dst + a, less);  // stable
        next->push_back(c);
      } else {
        std::copy(src + a, src + b, dst + a);
        next->push_back(b);
      }
    }
    bounds->swap(*next);
    std::swap(src, dst);
  }
  if (src != first) std::copy(src, src + n, first);
}

}  // namespace

std::string validate(const ObjectFeatureParams& p) {
  return checkFieldRanges(p);
}

const char* featureName(int feature) {
  return feature >= 0 && feature < kNumObjectFeatures ? kFeatureNames[feature] : "?";
}

ObjectFeatureExtractor::ObjectFeatureExtractor(const ObjectFeatureParams& params)
    : params_(params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument("ObjectFeatureExtractor: " + error);
}

void ObjectFeatureExtractor::indexForeground(const LabeledCloud& foreground) {
  index_.build(foreground);
}

ObjectFeatureVector ObjectFeatureExtractor::compute(const LabeledCloud& foreground,
                                                    const DetectedObject& object) {
  // Every value below is computed by the same operations in the same order as in
  // computeReference(); only the passes, the scratch layout and the row ordering differ.
  ObjectFeatureVector f;
  f.fill(0.0f);
  const double range = std::hypot(object.centroid.x(), object.centroid.y());
  const double length = std::max(object.obb_size.x(), object.obb_size.y());
  const double width = std::min(object.obb_size.x(), object.obb_size.y());
  f[kFeatRange] = static_cast<float>(range);
  f[kFeatLength] = static_cast<float>(length);
  f[kFeatWidth] = static_cast<float>(width);
  f[kFeatFootprint] = static_cast<float>(length * width);

  // One pass: moments (the six distinct products of q q^T; q_i q_j == q_j q_i exactly), z,
  // elevation and intensity ranges, the scan-row coordinates.
  const std::size_t capacity = object.indices.size();
  if (rows_.size() < capacity) rows_.resize(capacity);
  if (intensities_.size() < capacity) intensities_.resize(capacity);
  RowPoint* const rows = rows_.data();
  float* const intensities = intensities_.data();
  const double ux = range > 1e-6 ? object.centroid.x() / range : 1.0;
  const double uy = range > 1e-6 ? object.centroid.y() / range : 0.0;
  double sx = 0.0, sy = 0.0, sz = 0.0;
  double sxx = 0.0, sxy = 0.0, sxz = 0.0, syy = 0.0, syz = 0.0, szz = 0.0;
  double zmin = 0.0, zmax = 0.0;
  float emin = 0.0f, emax = 0.0f;
  std::size_t n = 0;
  for (const std::uint32_t idx : object.indices) {
    const LabeledPoint* found = index_.find(foreground, idx);
    if (!found) continue;
    const LabeledPoint& p = *found;
    if (!isFinitePoint(p)) continue;
    const double rho = std::sqrt(static_cast<double>(p.x) * p.x + static_cast<double>(p.y) * p.y);
    if (!(rho > 1e-3)) continue;
    const double qx = p.x, qy = p.y, qz = p.z;
    if (n == 0) zmin = zmax = qz;
    zmin = std::min(zmin, qz);
    zmax = std::max(zmax, qz);
    sx += qx;
    sy += qy;
    sz += qz;
    sxx += qx * qx;
    sxy += qx * qy;
    sxz += qx * qz;
    syy += qy * qy;
    syz += qy * qz;
    szz += qz * qz;
    const double dot = ux * p.x + uy * p.y;
    const double cross = ux * p.y - uy * p.x;
    const double tan_az = dot > 1e-3 ? cross / dot : (cross >= 0.0 ? 1e3 : -1e3);
    const float elevation = static_cast<float>(qz / rho);
    if (n == 0) emin = emax = elevation;
    emin = std::min(emin, elevation);
    emax = std::max(emax, elevation);
    rows[n] = {elevation, static_cast<float>(tan_az),
               static_cast<float>(std::sqrt(rho * rho + qz * qz)), static_cast<float>(qz)};
    intensities[n] = std::isfinite(p.intensity) ? p.intensity : 0.0f;
    ++n;
  }
  f[kFeatPoints] = static_cast<float>(n);
  f[kFeatPointsAt10m] = static_cast<float>(n * (range / 10.0) * (range / 10.0));
  if (n == 0) return f;

  // Scan rows: bins as in computeReference(); beyond its counting-sort limit (absurd objects)
  // the reference itself.
  const float row_gap = static_cast<float>(std::tan(params_.row_gap_deg * kDegToRad));
  const float max_gap = static_cast<float>(std::tan(params_.max_azimuth_gap_deg * kDegToRad));
  const std::size_t bins = static_cast<std::size_t>((emax - emin) / row_gap) + 1;
  constexpr std::size_t kMaxBins = 1u << 16;
  if (bins > kMaxBins) return computeReference(foreground, object);

  const double nd = static_cast<double>(n);
  const Eigen::Vector3d sum(sx, sy, sz);
  Eigen::Matrix3d sq;
  sq << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  const Eigen::Vector3d mean = sum / nd;
  Eigen::Matrix3d cov = sq / nd - mean * mean.transpose();
  cov = 0.5 * (cov + cov.transpose());
  const double ground = -params_.sensor_height_m;
  f[kFeatHeight] = static_cast<float>(zmax - zmin);
  f[kFeatBottom] = static_cast<float>(zmin - ground);
  f[kFeatTop] = static_cast<float>(zmax - ground);
  f[kFeatMeanAboveBottom] = static_cast<float>(mean.z() - zmin);
  f[kFeatStdZ] = static_cast<float>(std::sqrt(std::max(0.0, cov(2, 2))));

  if (n >= 3) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    const Eigen::Vector3d ev = eig.eigenvalues().cwiseMax(0.0);
    const double l1 = ev(2), l2 = ev(1), l3 = ev(0);
    if (l1 > 1e-12) {
      f[kFeatLinearity] = static_cast<float>((l1 - l2) / l1);
      f[kFeatPlanarity] = static_cast<float>((l2 - l3) / l1);
      f[kFeatScattering] = static_cast<float>(l3 / l1);
    }
    f[kFeatNormalZ] = static_cast<float>(std::abs(eig.eigenvectors()(2, 0)));
    f[kFeatPrincipalZ] = static_cast<float>(std::abs(eig.eigenvectors()(2, 2)));
    const double a = cov(0, 0), b = cov(0, 1), c = cov(1, 1);
    const double mid = 0.5 * (a + c), dev = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
    if (mid + dev > 1e-12)
      f[kFeatXyElongation] = static_cast<float>(1.0 - (mid - dev) / (mid + dev));
  }

  // Vertical profile and the elevation bins (each point's bin computed once).
  const double height = zmax - zmin;
  std::size_t quarter[4] = {0, 0, 0, 0}, below = 0, above = 0;
  if (bin_of_.size() < n) bin_of_.resize(n);
  std::uint32_t* const bin_of = bin_of_.data();
  bin_start_.assign(bins + 1, 0u);
  std::uint32_t* const bin_start = bin_start_.data();
  for (std::size_t k = 0; k < n; ++k) {
    const RowPoint& r = rows[k];
    const double z = r.z - zmin;
    const int qi = height > 1e-6 ? std::min(3, static_cast<int>(4.0 * z / height)) : 0;
    ++quarter[std::max(0, qi)];
    below += z < 0.5;
    above += z > 1.5;
    const std::size_t bin =
        std::min(bins - 1, static_cast<std::size_t>((r.elevation - emin) / row_gap));
    bin_of[k] = static_cast<std::uint32_t>(bin);
    ++bin_start[bin + 1];
  }
  for (int k = 0; k < 4; ++k) f[kFeatProfile0 + k] = static_cast<float>(quarter[k] / nd);
  f[kFeatBelow05] = static_cast<float>(below / nd);
  f[kFeatAbove15] = static_cast<float>(above / nd);

  // Counting sort by bin (stable, as the reference's).
  for (std::size_t b = 1; b <= bins; ++b) bin_start[b] += bin_start[b - 1];
  if (sorted_.size() < n) sorted_.resize(n);
  RowPoint* const sorted = sorted_.data();
  fill_.assign(bin_start_.begin(), bin_start_.end());
  std::uint32_t* const fill = fill_.data();
  for (std::size_t k = 0; k < n; ++k) sorted[fill[bin_of[k]]++] = rows[k];

  auto by_azimuth = [](const RowPoint& a, const RowPoint& b) { return a.azimuth < b.azimuth; };
  auto reversed = [](const RowPoint& a, const RowPoint& b) { return a.azimuth > b.azimuth; };
  std::size_t num_rows = 0, triplets = 0, jumps = 0, steps = 0, both_sides = 0;
  double second_diff = 0.0, step_sum = 0.0;
  std::size_t begin = 0;
  std::size_t bin = 0;
  while (begin < n) {
    while (bin_start[bin + 1] == bin_start[bin]) ++bin;
    while (bin < bins && bin_start[bin + 1] > bin_start[bin]) ++bin;
    const std::size_t end = bin_start[bin];
    ++num_rows;
    RowPoint* const row_begin = sorted + begin;
    RowPoint* const row_end = sorted + end;
    if (!std::is_sorted(row_begin, row_end, by_azimuth)) {
      if (std::is_sorted(row_begin, row_end, reversed)) {
        std::reverse(row_begin, row_end);
      } else {
        // Distinct azimuths have one ascending order, whichever algorithm finds it; so have
        // equal ones in a row short enough for std::sort to be an insertion sort (stable, as
        // the merge is). Otherwise the reference's std::sort on the same input decides.
        const bool short_row = end - begin <= kStableSortRow;
        if (!short_row) row_copy_.assign(row_begin, row_end);
        mergeAscendingRuns(row_begin, end - begin, by_azimuth, &merge_, &runs_, &next_runs_);
        bool ties = false;
        if (!short_row) {
          for (const RowPoint* r = row_begin + 1; r < row_end; ++r) {
            ties |= r->azimuth == r[-1].azimuth;
          }
        }
        if (ties) {
          std::copy(row_copy_.begin(), row_copy_.end(), row_begin);
          std::sort(row_begin, row_end, by_azimuth);
        }
      }
    }
    for (std::size_t k = begin + 1; k < end; ++k) {
      const float step = sorted[k].azimuth - sorted[k - 1].azimuth;
      if (step <= max_gap) {
        ++steps;
        step_sum += step;
      }
    }
    for (std::size_t k = begin + 1; k + 1 < end; ++k) {
      const RowPoint& a = sorted[k - 1];
      const RowPoint& b = sorted[k];
      const RowPoint& c = sorted[k + 1];
      if (b.azimuth - a.azimuth > max_gap || c.azimuth - b.azimuth > max_gap) continue;
      ++triplets;
      ++both_sides;
      const double d = std::abs(b.range - 0.5 * (a.range + c.range));
      second_diff += d;
      if (d > params_.jump_m) ++jumps;
    }
    begin = end;
  }
  f[kFeatRows] = static_cast<float>(num_rows);
  f[kFeatPointsPerRow] = static_cast<float>(nd / static_cast<double>(num_rows));
  if (steps > 0) {
    f[kFeatAzimuthFill] = static_cast<float>(step_sum / static_cast<double>(steps) /
                                             (params_.azimuth_resolution_deg * kDegToRad));
  }
  f[kFeatRowNeighbours] = static_cast<float>(both_sides / nd);
  if (triplets > 0) {
    f[kFeatJumpFraction] = static_cast<float>(jumps / static_cast<double>(triplets));
    f[kFeatMeanSecondDiff] = static_cast<float>(second_diff / static_cast<double>(triplets));
  }

  // Intensity (selectRanks reads a vector: the object's values are its first n entries).
  double isum = 0.0, isq = 0.0;
  float imax = intensities[0];
  for (std::size_t k = 0; k < n; ++k) {
    const float v = intensities[k];
    isum += v;
    isq += static_cast<double>(v) * v;
    imax = std::max(imax, v);
  }
  const double imean = isum / nd;
  f[kFeatIntensityMean] = static_cast<float>(imean);
  f[kFeatIntensityStd] = static_cast<float>(std::sqrt(std::max(0.0, isq / nd - imean * imean)));
  f[kFeatIntensityMax] = imax;
  const std::size_t ranks[3] = {std::min(n - 1, static_cast<std::size_t>(0.1 * nd)),
                                std::min(n - 1, static_cast<std::size_t>(0.5 * nd)),
                                std::min(n - 1, static_cast<std::size_t>(0.9 * nd))};
  float quantiles[3];
  intensities_.resize(n);
  selectRanks(intensities_, ranks, 3, quantiles, &bucket_values_);
  f[kFeatIntensityQ10] = quantiles[0];
  f[kFeatIntensityQ50] = quantiles[1];
  f[kFeatIntensityQ90] = quantiles[2];
  return f;
}

ObjectFeatureVector ObjectFeatureExtractor::computeReference(const LabeledCloud& foreground,
                                                             const DetectedObject& object) {
  ObjectFeatureVector f;
  f.fill(0.0f);
  const double range = std::hypot(object.centroid.x(), object.centroid.y());
  const double length = std::max(object.obb_size.x(), object.obb_size.y());
  const double width = std::min(object.obb_size.x(), object.obb_size.y());
  f[kFeatRange] = static_cast<float>(range);
  f[kFeatLength] = static_cast<float>(length);
  f[kFeatWidth] = static_cast<float>(width);
  f[kFeatFootprint] = static_cast<float>(length * width);

  // One pass: moments, z and intensity ranges, the scan-row coordinates.
  rows_.clear();
  intensities_.clear();
  const double ux = range > 1e-6 ? object.centroid.x() / range : 1.0;
  const double uy = range > 1e-6 ? object.centroid.y() / range : 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
  double zmin = 0.0, zmax = 0.0;
  for (const std::uint32_t idx : object.indices) {
    const LabeledPoint* found = index_.find(foreground, idx);
    if (!found) continue;
    const LabeledPoint& p = *found;
    if (!isFinitePoint(p)) continue;
    const double rho = std::sqrt(static_cast<double>(p.x) * p.x + static_cast<double>(p.y) * p.y);
    if (!(rho > 1e-3)) continue;
    const Eigen::Vector3d q(p.x, p.y, p.z);
    if (rows_.empty()) zmin = zmax = q.z();
    zmin = std::min(zmin, q.z());
    zmax = std::max(zmax, q.z());
    sum += q;
    sq.noalias() += q * q.transpose();
    // Rows and neighbours are found on tangents, not angles: tan(elevation) = z / rho, and
    // tan(azimuth relative to the centroid's direction) = cross / dot. Both are monotonic
    // (within +-90 deg of the centroid's direction, all of an object but around the sensor)
    // and within 1.2x of the angle's steps at an HDL-64E's elevations and within +-25 deg of
    // azimuth, which the gap thresholds allow for; no atan2 per point.
    const double dot = ux * p.x + uy * p.y;
    const double cross = ux * p.y - uy * p.x;
    const double tan_az = dot > 1e-3 ? cross / dot : (cross >= 0.0 ? 1e3 : -1e3);
    rows_.push_back({static_cast<float>(q.z() / rho), static_cast<float>(tan_az),
                     static_cast<float>(std::sqrt(rho * rho + q.z() * q.z())),
                     static_cast<float>(q.z())});
    intensities_.push_back(std::isfinite(p.intensity) ? p.intensity : 0.0f);
  }
  const std::size_t n = rows_.size();
  f[kFeatPoints] = static_cast<float>(n);
  f[kFeatPointsAt10m] = static_cast<float>(n * (range / 10.0) * (range / 10.0));
  if (n == 0) return f;
  const double nd = static_cast<double>(n);
  const Eigen::Vector3d mean = sum / nd;
  Eigen::Matrix3d cov = sq / nd - mean * mean.transpose();
  cov = 0.5 * (cov + cov.transpose());
  const double ground = -params_.sensor_height_m;
  f[kFeatHeight] = static_cast<float>(zmax - zmin);
  f[kFeatBottom] = static_cast<float>(zmin - ground);
  f[kFeatTop] = static_cast<float>(zmax - ground);
  f[kFeatMeanAboveBottom] = static_cast<float>(mean.z() - zmin);
  f[kFeatStdZ] = static_cast<float>(std::sqrt(std::max(0.0, cov(2, 2))));

  // Shape: eigenvalues ascending (l3 <= l2 <= l1).
  if (n >= 3) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    const Eigen::Vector3d ev = eig.eigenvalues().cwiseMax(0.0);
    const double l1 = ev(2), l2 = ev(1), l3 = ev(0);
    if (l1 > 1e-12) {
      f[kFeatLinearity] = static_cast<float>((l1 - l2) / l1);
      f[kFeatPlanarity] = static_cast<float>((l2 - l3) / l1);
      f[kFeatScattering] = static_cast<float>(l3 / l1);
    }
    f[kFeatNormalZ] = static_cast<float>(std::abs(eig.eigenvectors()(2, 0)));
    f[kFeatPrincipalZ] = static_cast<float>(std::abs(eig.eigenvectors()(2, 2)));
    const double a = cov(0, 0), b = cov(0, 1), c = cov(1, 1);
    const double mid = 0.5 * (a + c), dev = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
    if (mid + dev > 1e-12)
      f[kFeatXyElongation] = static_cast<float>(1.0 - (mid - dev) / (mid + dev));
  }

  // Vertical profile.
  const double height = zmax - zmin;
  std::size_t quarter[4] = {0, 0, 0, 0}, below = 0, above = 0;
  for (const RowPoint& r : rows_) {
    const double z = r.z - zmin;
    const int qi = height > 1e-6 ? std::min(3, static_cast<int>(4.0 * z / height)) : 0;
    ++quarter[std::max(0, qi)];
    below += z < 0.5;
    above += z > 1.5;
  }
  for (int k = 0; k < 4; ++k) f[kFeatProfile0 + k] = static_cast<float>(quarter[k] / nd);
  f[kFeatBelow05] = static_cast<float>(below / nd);
  f[kFeatAbove15] = static_cast<float>(above / nd);

  // Scan rows: elevation bins `row_gap` wide; a row is a run of occupied bins (an HDL-64E's
  // rows are 0.33 deg or more apart, so an empty bin lies between two rows). The points are
  // ordered by bin with a counting sort (an object spans at most a few hundred bins), then
  // by azimuth inside each row.
  const float row_gap = static_cast<float>(std::tan(params_.row_gap_deg * kDegToRad));
  const float max_gap = static_cast<float>(std::tan(params_.max_azimuth_gap_deg * kDegToRad));
  float emin = rows_[0].elevation, emax = emin;
  for (const RowPoint& r : rows_) {
    emin = std::min(emin, r.elevation);
    emax = std::max(emax, r.elevation);
  }
  const std::size_t bins = static_cast<std::size_t>((emax - emin) / row_gap) + 1;
  constexpr std::size_t kMaxBins = 1u << 16;  // beyond (absurd objects): a plain sort
  bin_start_.assign(std::min(bins, kMaxBins) + 1, 0u);
  if (bins <= kMaxBins) {
    auto binOf = [&](const RowPoint& r) {
      return std::min(bins - 1, static_cast<std::size_t>((r.elevation - emin) / row_gap));
    };
    for (const RowPoint& r : rows_) ++bin_start_[binOf(r) + 1];
    for (std::size_t b = 1; b <= bins; ++b) bin_start_[b] += bin_start_[b - 1];
    sorted_.resize(n);
    fill_ = bin_start_;
    for (const RowPoint& r : rows_) sorted_[fill_[binOf(r)]++] = r;
    rows_.swap(sorted_);
  } else {
    std::sort(rows_.begin(), rows_.end(),
              [](const RowPoint& a, const RowPoint& b) { return a.elevation < b.elevation; });
  }
  std::size_t num_rows = 0, triplets = 0, jumps = 0, steps = 0, both_sides = 0;
  double second_diff = 0.0, step_sum = 0.0;
  std::size_t begin = 0;
  std::size_t bin = 0;  // first bin of the next row (counting-sort path)
  while (begin < n) {
    std::size_t end = begin + 1;
    if (bins <= kMaxBins) {
      while (bin_start_[bin + 1] == bin_start_[bin]) ++bin;               // skip empty bins
      while (bin < bins && bin_start_[bin + 1] > bin_start_[bin]) ++bin;  // the run
      end = bin_start_[bin];
    } else {
      while (end < n && rows_[end].elevation - rows_[end - 1].elevation <= row_gap) ++end;
    }
    ++num_rows;
    // Decoded packets and KITTI files list a ring's returns in azimuth order, so a row is
    // usually sorted already (or reversed): check before sorting.
    const auto row_begin = rows_.begin() + static_cast<std::ptrdiff_t>(begin);
    const auto row_end = rows_.begin() + static_cast<std::ptrdiff_t>(end);
    auto by_azimuth = [](const RowPoint& a, const RowPoint& b) { return a.azimuth < b.azimuth; };
    if (!std::is_sorted(row_begin, row_end, by_azimuth)) {
      auto reversed = [](const RowPoint& a, const RowPoint& b) { return a.azimuth > b.azimuth; };
      if (std::is_sorted(row_begin, row_end, reversed)) {
        std::reverse(row_begin, row_end);
      } else {
        std::sort(row_begin, row_end, by_azimuth);
      }
    }
    for (std::size_t k = begin + 1; k < end; ++k) {
      const float step = rows_[k].azimuth - rows_[k - 1].azimuth;
      if (step <= max_gap) {
        ++steps;
        step_sum += step;
      }
    }
    for (std::size_t k = begin + 1; k + 1 < end; ++k) {
      const RowPoint& a = rows_[k - 1];
      const RowPoint& b = rows_[k];
      const RowPoint& c = rows_[k + 1];
      if (b.azimuth - a.azimuth > max_gap || c.azimuth - b.azimuth > max_gap) continue;
      ++triplets;
      ++both_sides;
      const double d = std::abs(b.range - 0.5 * (a.range + c.range));
      second_diff += d;
      if (d > params_.jump_m) ++jumps;
    }
    begin = end;
  }
  f[kFeatRows] = static_cast<float>(num_rows);
  f[kFeatPointsPerRow] = static_cast<float>(nd / static_cast<double>(num_rows));
  if (steps > 0) {
    f[kFeatAzimuthFill] = static_cast<float>(step_sum / static_cast<double>(steps) /
                                             (params_.azimuth_resolution_deg * kDegToRad));
  }
  f[kFeatRowNeighbours] = static_cast<float>(both_sides / nd);
  if (triplets > 0) {
    f[kFeatJumpFraction] = static_cast<float>(jumps / static_cast<double>(triplets));
    f[kFeatMeanSecondDiff] = static_cast<float>(second_diff / static_cast<double>(triplets));
  }

  // Intensity.
  double isum = 0.0, isq = 0.0;
  float imax = intensities_[0];
  for (const float v : intensities_) {
    isum += v;
    isq += static_cast<double>(v) * v;
    imax = std::max(imax, v);
  }
  const double imean = isum / nd;
  f[kFeatIntensityMean] = static_cast<float>(imean);
  f[kFeatIntensityStd] = static_cast<float>(std::sqrt(std::max(0.0, isq / nd - imean * imean)));
  f[kFeatIntensityMax] = imax;
  // The k-th smallest values, exactly as a sort would place them.
  const std::size_t ranks[3] = {std::min(n - 1, static_cast<std::size_t>(0.1 * nd)),
                                std::min(n - 1, static_cast<std::size_t>(0.5 * nd)),
                                std::min(n - 1, static_cast<std::size_t>(0.9 * nd))};
  float quantiles[3];
  selectRanks(intensities_, ranks, 3, quantiles, &bucket_values_);
  f[kFeatIntensityQ10] = quantiles[0];
  f[kFeatIntensityQ50] = quantiles[1];
  f[kFeatIntensityQ90] = quantiles[2];
  return f;
}

void ObjectFeatureExtractor::computeAll(const LabeledCloud& foreground,
                                        const std::vector<DetectedObject>& objects,
                                        std::vector<ObjectFeatureVector>* features) {
  indexForeground(foreground);
  features->clear();
  features->reserve(objects.size());
  for (const DetectedObject& o : objects) features->push_back(compute(foreground, o));
}

}  // namespace core
}  // namespace urban_detection
