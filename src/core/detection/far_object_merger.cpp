#include "urban_detection/core/detection/far_object_merger.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "urban_detection/core/common/param_rules.h"

namespace urban_detection {
namespace core {

namespace {

// [min, max] of the projection of an object's oriented box on the unit
// direction `d`; `ax` = (cos yaw, sin yaw) of the box.
Eigen::Vector2f project(const DetectedObject& o, const Eigen::Vector2f& ax,
                        const Eigen::Vector2f& d) {
  const Eigen::Vector2f ay(-ax.y(), ax.x());
  const float centre = o.obb_center.head<2>().dot(d);
  const float half =
      0.5f * (o.obb_size.x() * std::fabs(ax.dot(d)) + o.obb_size.y() * std::fabs(ay.dot(d)));
  return Eigen::Vector2f(centre - half, centre + half);
}

float intervalGap(const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return std::max(0.0f, std::max(a.x(), b.x()) - std::min(a.y(), b.y()));
}

}  // namespace

std::string validate(const FarObjectMergerParams& p) {
  const std::string error = checkFieldRanges(p);
  if (!error.empty()) return error;
  return orderMessage("max_width_m", p.max_width_m, "max_length_m", p.max_length_m, "m");
}

FarObjectMerger::FarObjectMerger(const FarObjectMergerParams& params) : params_(params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument(error);
}

std::uint32_t FarObjectMerger::find(std::uint32_t a) {
  while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
  return a;
}

// The detectors copy `index` from the foreground in its order, and
// extractForeground() writes the foreground in cloud order, so the indices are
// sorted and a binary search finds a point. A foreground in any other order
// (hand-made clouds) is searched linearly: only the few points of far candidate
// objects are looked up. An object's points mostly come in runs of consecutive
// positions, so `hint` (the position after the previous point's) is tried first; it
// is taken only where the binary search would stop too on a sorted foreground (the
// first point with this index: the one before it has a smaller one).
std::int32_t FarObjectMerger::positionOf(const LabeledCloud& foreground, std::uint32_t index,
                                         std::size_t hint) const {
  const auto& pts = foreground.points;
  if (hint < pts.size() && pts[hint].index == index && (hint == 0 || pts[hint - 1].index < index)) {
    return static_cast<std::int32_t>(hint);
  }
  auto it = std::lower_bound(pts.begin(), pts.end(), index,
                             [](const LabeledPoint& p, std::uint32_t i) { return p.index < i; });
  if (it != pts.end() && it->index == index) return static_cast<std::int32_t>(it - pts.begin());
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (pts[k].index == index) return static_cast<std::int32_t>(k);
  }
  return -1;
}

// Positions in `foreground` of the points of far object k (far_[slot]), looked up
// once per apply() on first use; false when one is not in `foreground`.
bool FarObjectMerger::positionsOf(const LabeledCloud& foreground,
                                  const std::vector<DetectedObject>& objects, std::size_t slot) {
  FarObject& f = far_info_[slot];
  if (f.state == FarObject::kUnknown) {
    f.begin = static_cast<std::uint32_t>(far_positions_.size());
    f.state = FarObject::kFound;
    std::size_t hint = 0;
    for (const std::uint32_t index : objects[far_[slot]].indices) {
      const std::int32_t pos = positionOf(foreground, index, hint);
      if (pos < 0) {
        f.state = FarObject::kMissing;
        break;
      }
      far_positions_.push_back(static_cast<std::uint32_t>(pos));
      hint = static_cast<std::size_t>(pos) + 1;
    }
    f.end = static_cast<std::uint32_t>(far_positions_.size());
  }
  return f.state == FarObject::kFound;
}

// True when the groups of roots ra and rb, joined, fit the vehicle box; leaves
// the joined group's members in members_ and its geometry in trial_.
bool FarObjectMerger::fits(const LabeledCloud& foreground,
                           const std::vector<DetectedObject>& objects, std::uint32_t ra,
                           std::uint32_t rb) {
  members_.clear();
  positions_.clear();
  bool found = true;
  for (std::size_t slot = 0; slot < far_.size(); ++slot) {
    const std::uint32_t r = find(far_[slot]);
    if (r != ra && r != rb) continue;
    members_.push_back(far_[slot]);
    found = found && positionsOf(foreground, objects, slot);
    if (!found) continue;
    const FarObject& f = far_info_[slot];
    positions_.insert(positions_.end(), far_positions_.begin() + f.begin,
                      far_positions_.begin() + f.end);
  }
  if (!found) return false;  // not from this foreground: leave the objects alone
  geometry_.compute(foreground, positions_, &trial_);
  return trial_.obb_size.x() <= params_.max_length_m && trial_.obb_size.y() <= params_.max_width_m;
}

std::size_t FarObjectMerger::apply(const LabeledCloud& foreground,
                                   std::vector<DetectedObject>* objects) {
  if (params_.max_gap_m <= 0.0 || objects->size() < 2) return 0;
  const std::size_t n = objects->size();
  far_.clear();
  const double min_range2 = params_.min_range_m * params_.min_range_m;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3f& c = (*objects)[k].centroid;
    if (double(c.x()) * c.x() + double(c.y()) * c.y() >= min_range2) {
      far_.push_back(static_cast<std::uint32_t>(k));
    }
  }
  if (far_.size() < 2) return 0;
  pairs_.clear();
  const float max_gap = static_cast<float>(params_.max_gap_m);
  const float max_z_gap = static_cast<float>(params_.max_z_gap_m);
  const float max_across = static_cast<float>(params_.max_across_gap_m);
  const float min_overlap = static_cast<float>(params_.min_across_overlap);
  // Per far object once: its box axes (the yaw's cosine and sine), a bound on the half
  // extent of its box along any direction (half its diagonal), and the fields the first pair
  // tests read, in arrays of their own (see below).
  const std::size_t nf = far_.size();
  far_info_.resize(nf);
  far_positions_.clear();
  FarArrays& fa = far_arrays_;
  for (std::vector<float>* v : {&fa.min_z, &fa.max_z, &fa.centroid_x, &fa.centroid_y}) {
    v->resize(nf);
  }
  for (std::vector<double>* v : {&fa.center_x, &fa.center_y, &fa.radius}) v->resize(nf);
  fa.near.resize(nf);
  for (std::size_t i = 0; i < nf; ++i) {
    const DetectedObject& o = (*objects)[far_[i]];
    FarObject& f = far_info_[i];
    f.axis = Eigen::Vector2f(std::cos(o.obb_yaw_rad), std::sin(o.obb_yaw_rad));
    fa.radius[i] = 0.5 * std::sqrt(static_cast<double>(o.obb_size.x()) * o.obb_size.x() +
                                   static_cast<double>(o.obb_size.y()) * o.obb_size.y());
    fa.min_z[i] = o.min_pt.z();
    fa.max_z[i] = o.max_pt.z();
    fa.centroid_x[i] = o.centroid.x();
    fa.centroid_y[i] = o.centroid.y();
    fa.center_x[i] = o.obb_center.x();
    fa.center_y[i] = o.obb_center.y();
    f.state = FarObject::kUnknown;
  }
  const double max_gap_m = params_.max_gap_m, max_across_gap_m = params_.max_across_gap_m;
  for (std::size_t i = 0; i < nf; ++i) {
    // First the two cheap tests for every later object j, without a branch (most pairs fail
    // them, unpredictably) and over arrays (the compiler may vectorise the loop; the same
    // float and double operations either way): the gap between the z ranges, and the
    // distance of the box centres. Along and across two orthogonal unit directions, the gaps
    // are at least the distance of the box centres along them minus both half diagonals:
    // boxes whose centres are farther apart than that allows (with 1 cm to spare for
    // rounding) cannot pass the tests below, which are left for the few near pairs. (Not when
    // the line of sight to the midpoint of the centroids is shorter than 1 mm: its direction
    // is then not scaled to unit length.)
    const float min_z = fa.min_z[i], max_z = fa.max_z[i];
    const float centroid_x = fa.centroid_x[i], centroid_y = fa.centroid_y[i];
    const double center_x = fa.center_x[i], center_y = fa.center_y[i], radius = fa.radius[i];
    for (std::size_t j = i + 1; j < nf; ++j) {
      const float z_gap = std::max(min_z, fa.min_z[j]) - std::min(max_z, fa.max_z[j]);
      const float mx = 0.5f * (centroid_x + fa.centroid_x[j]);
      const float my = 0.5f * (centroid_y + fa.centroid_y[j]);
      const double dx = center_x - fa.center_x[j], dy = center_y - fa.center_y[j];
      const double reach = radius + fa.radius[j] + 0.01;
      const double reach_along = reach + max_gap_m, reach_across = reach + max_across_gap_m;
      const bool apart =
          dx * dx + dy * dy > reach_along * reach_along + reach_across * reach_across;
      fa.near[j] = (z_gap <= max_z_gap) & !(apart & (mx * mx + my * my > 2e-6f));
    }
    const DetectedObject& a = (*objects)[far_[i]];
    const FarObject& fi = far_info_[i];
    for (std::size_t j = i + 1; j < nf; ++j) {
      if (!fa.near[j]) continue;
      const DetectedObject& b = (*objects)[far_[j]];
      const FarObject& fj = far_info_[j];
      // Gaps between the two oriented boxes along and across the line of sight
      // to the pair's midpoint (0 where their projections overlap).
      const Eigen::Vector2f mid = 0.5f * (a.centroid.head<2>() + b.centroid.head<2>());
      const Eigen::Vector2f u = mid / std::max(mid.norm(), 1e-3f), v(-u.y(), u.x());
      const float along = intervalGap(project(a, fi.axis, u), project(b, fj.axis, u));
      const Eigen::Vector2f pa = project(a, fi.axis, v), pb = project(b, fj.axis, v);
      const float across = intervalGap(pa, pb);
      // Overlap across the line of sight, as a fraction of the narrower piece: a cabin lies
      // behind its body, a neighbour beside it.
      const float overlap = std::min(pa.y(), pb.y()) - std::max(pa.x(), pb.x());
      const float narrower = std::min(pa.y() - pa.x(), pb.y() - pb.x());
      const bool behind = across > 0.0f || overlap >= min_overlap * narrower;
      if (along <= max_gap && across <= max_across && behind) {
        pairs_.push_back({std::hypot(along, across), far_[i], far_[j]});
      }
    }
  }
  if (pairs_.empty()) return 0;
  std::stable_sort(pairs_.begin(), pairs_.end(),
                   [](const Pair& x, const Pair& y) { return x.gap < y.gap; });
  parent_.resize(n);
  for (std::size_t k = 0; k < n; ++k) parent_[k] = static_cast<std::uint32_t>(k);
  std::size_t joins = 0;
  for (const Pair& pr : pairs_) {
    const std::uint32_t ra = find(pr.a), rb = find(pr.b);
    if (ra == rb || !fits(foreground, *objects, ra, rb)) continue;
    parent_[std::max(ra, rb)] = std::min(ra, rb);  // the first member keeps its place
    ++joins;
  }
  if (joins == 0) return 0;

  // Rebuild: each group at the place of its first member, points in the
  // members' order.
  // A root is grouped when another far object has it as its root: marked in one pass over
  // the far objects (a search of them per root cost a find() per pair).
  grouped_.assign(n, 0);
  for (const std::uint32_t m : far_) {
    const std::uint32_t r = find(m);
    if (r != m) grouped_[r] = 1;
  }
  out_.clear();
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t r = find(static_cast<std::uint32_t>(k));
    if (r != k) continue;
    DetectedObject& obj = (*objects)[k];
    if (grouped_[k]) {
      fits(foreground, *objects, static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k));
      indices_.clear();
      for (const std::uint32_t m : members_) {
        const auto& idx = (*objects)[m].indices;
        indices_.insert(indices_.end(), idx.begin(), idx.end());
      }
      trial_.indices.swap(indices_);
      out_.push_back(std::move(trial_));
      trial_ = DetectedObject();
    } else {
      out_.push_back(std::move(obj));
    }
  }
  objects->swap(out_);
  for (std::size_t k = 0; k < objects->size(); ++k) {
    (*objects)[k].id = static_cast<std::uint32_t>(k + 1);
  }
  return joins;
}

}  // namespace core
}  // namespace urban_detection
