#include "urban_detection/core/object_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace urban_detection {
namespace core {
namespace {

float cross(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

}  // namespace

void convexHull2d(std::vector<Eigen::Vector2f>* points, std::vector<Eigen::Vector2f>* hull) {
  std::vector<Eigen::Vector2f>& p = *points;
  hull->clear();
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  const std::size_t n = p.size();
  if (n < 3) {
    hull->assign(p.begin(), p.end());
    return;
  }
  hull->resize(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {  // lower hull
    while (k >= 2 && cross((*hull)[k - 2], (*hull)[k - 1], p[i]) <= 0.0f) --k;
    (*hull)[k++] = p[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {  // upper hull
    while (k >= t && cross((*hull)[k - 2], (*hull)[k - 1], p[i]) <= 0.0f) --k;
    (*hull)[k++] = p[i];
  }
  hull->resize(k - 1);  // the last point repeats the first
}

void minAreaRectangle(const std::vector<Eigen::Vector2f>& hull, Eigen::Vector2f* center,
                      Eigen::Vector2f* size, float* yaw_rad) {
  *center = Eigen::Vector2f::Zero();
  *size = Eigen::Vector2f::Zero();
  *yaw_rad = 0.0f;
  if (hull.empty()) return;
  *center = hull[0];  // kept when every hull edge is degenerate (coincident points)
  const std::size_t n = hull.size();
  // Rotating calipers: the minimum-area rectangle has a side on a hull edge; going round the
  // (counter-clockwise) edges, the vertices extreme along the edge, across it and against it
  // only move forward, so all edges are tried in O(n).
  auto dot = [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) { return a.dot(b); };
  std::size_t a = 0, b = 0, c = 0;  // max along u, max along v (inward), min along u
  bool init = false;
  double best_area = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f e = hull[(i + 1) % n] - hull[i];
    const float len = e.norm();
    if (len <= 0.0f) continue;
    const Eigen::Vector2f u = e / len;
    const Eigen::Vector2f v(-u.y(), u.x());
    if (!init) {
      for (std::size_t k = 0; k < n; ++k) {
        if (dot(hull[k], u) > dot(hull[a], u)) a = k;
        if (dot(hull[k], v) > dot(hull[b], v)) b = k;
        if (dot(hull[k], u) < dot(hull[c], u)) c = k;
      }
      init = true;
    } else {
      for (std::size_t s = 0; s < n && dot(hull[(a + 1) % n], u) >= dot(hull[a], u); ++s) {
        a = (a + 1) % n;
      }
      for (std::size_t s = 0; s < n && dot(hull[(b + 1) % n], v) >= dot(hull[b], v); ++s) {
        b = (b + 1) % n;
      }
      for (std::size_t s = 0; s < n && dot(hull[(c + 1) % n], u) <= dot(hull[c], u); ++s) {
        c = (c + 1) % n;
      }
    }
    const float umin = dot(hull[c], u), umax = dot(hull[a], u);
    const float vmin = dot(hull[i], v), vmax = dot(hull[b], v);
    const double area = static_cast<double>(umax - umin) * static_cast<double>(vmax - vmin);
    if (area < best_area - 1e-12) {
      best_area = area;
      *center = u * (0.5f * (umin + umax)) + v * (0.5f * (vmin + vmax));
      float lu = umax - umin, lv = vmax - vmin;
      float yaw = std::atan2(u.y(), u.x());
      if (lv > lu) {
        std::swap(lu, lv);
        yaw += static_cast<float>(M_PI / 2);
      }
      // Normalise to (-pi/2, pi/2]: a box is symmetric under a half turn.
      while (yaw > static_cast<float>(M_PI / 2)) yaw -= static_cast<float>(M_PI);
      while (yaw <= -static_cast<float>(M_PI / 2)) yaw += static_cast<float>(M_PI);
      *size = Eigen::Vector2f(lu, lv);
      *yaw_rad = yaw;
    }
  }
}

void ObjectGeometry::compute(const LabeledCloud& cloud,
                             const std::vector<std::uint32_t>& cloud_positions,
                             DetectedObject* object) {
  compute(cloud, cloud_positions.data(), cloud_positions.size(), object);
}

void ObjectGeometry::compute(const LabeledCloud& cloud, const std::uint32_t* positions,
                             std::size_t n, DetectedObject* object, std::uint32_t* indices_out) {
  object->centroid.setZero();
  object->min_pt.setZero();
  object->max_pt.setZero();
  object->obb_center.setZero();
  object->obb_size.setZero();
  object->obb_yaw_rad = 0.0f;
  if (n == 0) return;

  // Pass 1: centroid and axis-aligned box; the xy of the points are gathered contiguously.
  double sx = 0.0, sy = 0.0, sz = 0.0;
  float mnx = std::numeric_limits<float>::max(), mny = mnx, mnz = mnx;
  float mxx = -mnx, mxy = -mnx, mxz = -mnx;
  pts_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const LabeledPoint& p = cloud.points[positions[i]];
    sx += p.x;
    sy += p.y;
    sz += p.z;
    mnx = std::min(mnx, p.x);
    mny = std::min(mny, p.y);
    mnz = std::min(mnz, p.z);
    mxx = std::max(mxx, p.x);
    mxy = std::max(mxy, p.y);
    mxz = std::max(mxz, p.z);
    pts_[i] = Eigen::Vector2f(p.x, p.y);
    if (indices_out) indices_out[i] = p.index;
  }
  const double inv = 1.0 / static_cast<double>(n);
  object->centroid = Eigen::Vector3f(static_cast<float>(sx * inv), static_cast<float>(sy * inv),
                                     static_cast<float>(sz * inv));
  object->min_pt = Eigen::Vector3f(mnx, mny, mnz);
  object->max_pt = Eigen::Vector3f(mxx, mxy, mxz);

  // Pass 2: hull candidates. The points are binned in columns of width <= kHullTolerance along
  // the longer side of the box; each column keeps its two extreme points across (and the
  // global extremes along). A point between the two extremes of its column lies within one
  // column width of the segment joining them, so the hull of the candidates is within
  // kHullTolerance of the exact hull, at O(n) cost instead of sorting every point.
  const bool along_x = (mxx - mnx) >= (mxy - mny);
  const float lo = along_x ? mnx : mny, len = along_x ? mxx - mnx : mxy - mny;
  const int cols = std::clamp(static_cast<int>(std::ceil(len / kHullTolerance)), 1, kMaxColumns);
  const float scale = len > 0.0f ? cols / len : 0.0f;
  col_lo_.assign(cols, -1);
  col_hi_.assign(cols, -1);
  std::int32_t first = 0, last = 0;
  auto bin = [&](auto along_x_tag) {
    constexpr bool kAlongX = decltype(along_x_tag)::value;
    auto a_of = [](const Eigen::Vector2f& q) { return kAlongX ? q.x() : q.y(); };
    auto b_of = [](const Eigen::Vector2f& q) { return kAlongX ? q.y() : q.x(); };
    float a_first = a_of(pts_[0]), a_last = a_first;
    for (std::size_t i = 0; i < n; ++i) {
      const float a = a_of(pts_[i]), b = b_of(pts_[i]);
      const int c = std::min(static_cast<int>((a - lo) * scale), cols - 1);
      std::int32_t& l = col_lo_[c];
      std::int32_t& h = col_hi_[c];
      const std::int32_t ii = static_cast<std::int32_t>(i);
      if (l < 0 || b < b_of(pts_[l])) l = ii;
      if (h < 0 || b > b_of(pts_[h])) h = ii;
      if (a < a_first) {
        a_first = a;
        first = ii;
      }
      if (a > a_last) {
        a_last = a;
        last = ii;
      }
    }
  };
  if (along_x) {
    bin(std::true_type());
  } else {
    bin(std::false_type());
  }
  // Andrew's monotone chain without sorting: with one candidate per column, each chain is
  // already ordered along the long side. Work in (along, across) coordinates.
  auto ab = [along_x](const Eigen::Vector2f& q) {
    return along_x ? q : Eigen::Vector2f(q.y(), q.x());
  };
  cand_.clear();
  cand_.push_back(ab(pts_[first]));
  for (int c = 0; c < cols; ++c) {
    if (col_lo_[c] >= 0) cand_.push_back(ab(pts_[col_lo_[c]]));
  }
  cand_.push_back(ab(pts_[last]));
  const std::size_t lower_end = cand_.size();
  cand_.push_back(ab(pts_[last]));
  for (int c = cols; c-- > 0;) {
    if (col_hi_[c] >= 0) cand_.push_back(ab(pts_[col_hi_[c]]));
  }
  cand_.push_back(ab(pts_[first]));
  hull_.clear();
  for (std::size_t i = 0; i < lower_end; ++i) {  // lower chain, first .. last
    while (hull_.size() >= 2 && cross(hull_[hull_.size() - 2], hull_.back(), cand_[i]) <= 0.0f) {
      hull_.pop_back();
    }
    hull_.push_back(cand_[i]);
  }
  const std::size_t t = hull_.size() + 1;  // upper chain, last .. first ('last' is on top)
  for (std::size_t i = lower_end + 1; i < cand_.size(); ++i) {
    while (hull_.size() >= t && cross(hull_[hull_.size() - 2], hull_.back(), cand_[i]) <= 0.0f) {
      hull_.pop_back();
    }
    hull_.push_back(cand_[i]);
  }
  hull_.pop_back();  // 'first' again
  if (!along_x) {  // (y, x) is a reflection: restore x, y and counter-clockwise order
    for (Eigen::Vector2f& q : hull_) q = Eigen::Vector2f(q.y(), q.x());
    std::reverse(hull_.begin(), hull_.end());
  }
  Eigen::Vector2f c, s;
  float yaw = 0.0f;
  minAreaRectangle(hull_, &c, &s, &yaw);
  object->obb_center = Eigen::Vector3f(c.x(), c.y(), 0.5f * (mnz + mxz));
  object->obb_size = Eigen::Vector3f(s.x(), s.y(), mxz - mnz);
  object->obb_yaw_rad = yaw;
}

}  // namespace core
}  // namespace urban_detection
