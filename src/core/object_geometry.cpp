#include "urban_detection/core/object_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

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
  const Eigen::Vector2f* h = hull.data();
  auto next = [n](std::size_t k) { return k + 1 == n ? 0 : k + 1; };
  // Rotating calipers: the minimum-area rectangle has a side on a hull edge; going round the
  // (counter-clockwise) edges, the vertices extreme along the edge, across it and against it
  // only move forward, so all edges are tried in O(n). The yaw (an atan2) is computed once,
  // for the best edge.
  auto dot = [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) { return a.dot(b); };
  std::size_t a = 0, b = 0, c = 0;  // max along u, max along v (inward), min along u
  bool init = false, found = false;
  double best_area = std::numeric_limits<double>::infinity();
  Eigen::Vector2f best_u(0.0f, 0.0f);
  float best_lu = 0.0f, best_lv = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f e = h[next(i)] - h[i];
    const float len = e.norm();
    if (len <= 0.0f) continue;
    const Eigen::Vector2f u = e / len;
    const Eigen::Vector2f v(-u.y(), u.x());
    if (!init) {
      for (std::size_t k = 0; k < n; ++k) {
        if (dot(h[k], u) > dot(h[a], u)) a = k;
        if (dot(h[k], v) > dot(h[b], v)) b = k;
        if (dot(h[k], u) < dot(h[c], u)) c = k;
      }
      init = true;
    } else {
      for (std::size_t s = 0; s < n && dot(h[next(a)], u) >= dot(h[a], u); ++s) a = next(a);
      for (std::size_t s = 0; s < n && dot(h[next(b)], v) >= dot(h[b], v); ++s) b = next(b);
      for (std::size_t s = 0; s < n && dot(h[next(c)], u) <= dot(h[c], u); ++s) c = next(c);
    }
    const float umin = dot(h[c], u), umax = dot(h[a], u);
    const float vmin = dot(h[i], v), vmax = dot(h[b], v);
    const double area = static_cast<double>(umax - umin) * static_cast<double>(vmax - vmin);
    if (area < best_area - 1e-12) {
      best_area = area;
      *center = u * (0.5f * (umin + umax)) + v * (0.5f * (vmin + vmax));
      best_u = u;
      best_lu = umax - umin;
      best_lv = vmax - vmin;
      found = true;
    }
  }
  if (!found) return;
  float lu = best_lu, lv = best_lv;
  float yaw = std::atan2(best_u.y(), best_u.x());
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

void ObjectGeometry::compute(const LabeledCloud& cloud,
                             const std::vector<std::uint32_t>& cloud_positions,
                             DetectedObject* object) {
  compute(cloud, cloud_positions.data(), cloud_positions.size(), object);
}

void ObjectGeometry::compute(const LabeledCloud& cloud, const std::uint32_t* positions,
                             std::size_t n, DetectedObject* object, std::uint32_t* indices_out) {
  // Pass 1: centroid and axis-aligned box; the xy of the points are gathered contiguously.
  ObjectMoments m;
  pts_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const LabeledPoint& p = cloud.points[positions[i]];
    m.add(p.x, p.y, p.z);
    pts_[i] = Eigen::Vector2f(p.x, p.y);
    if (indices_out) indices_out[i] = p.index;
  }
  finish(m, pts_.data(), object);
}

void ObjectGeometry::finish(const ObjectMoments& m, const Eigen::Vector2f* pts,
                            DetectedObject* object) {
  object->centroid.setZero();
  object->min_pt.setZero();
  object->max_pt.setZero();
  object->obb_center.setZero();
  object->obb_size.setZero();
  object->obb_yaw_rad = 0.0f;
  const std::size_t n = m.n;
  if (n == 0) return;
  const double inv = 1.0 / static_cast<double>(n);
  object->centroid = Eigen::Vector3f(static_cast<float>(m.sx * inv), static_cast<float>(m.sy * inv),
                                     static_cast<float>(m.sz * inv));
  const float mnx = m.min_x, mny = m.min_y, mnz = m.min_z;
  const float mxx = m.max_x, mxy = m.max_y, mxz = m.max_z;
  object->min_pt = Eigen::Vector3f(mnx, mny, mnz);
  object->max_pt = Eigen::Vector3f(mxx, mxy, mxz);

  // Pass 2: hull candidates. The points are binned in columns of width <= kHullTolerance along
  // the longer side of the box; each column keeps its two extreme points across (and the
  // global extremes along). A point between the two extremes of its column lies within one
  // column width of the segment joining them, so the hull of the candidates is within
  // kHullTolerance of the exact hull, at O(n) cost instead of sorting every point. The
  // extremes' coordinates are kept beside their indices: no dependent load per point.
  const bool along_x = (mxx - mnx) >= (mxy - mny);
  const float lo = along_x ? mnx : mny, len = along_x ? mxx - mnx : mxy - mny;
  const int cols = std::clamp(static_cast<int>(std::ceil(len / kHullTolerance)), 1, kMaxColumns);
  const float scale = len > 0.0f ? cols / len : 0.0f;
  // Per column the lowest and highest point across, as (along, across); an empty column keeps
  // the infinite sentinels (finite points always replace them). Branch-free selects: which
  // point is extreme is unpredictable.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Four float arrays per set of columns (along and across of the lowest point, of the
  // highest): consecutive points mostly fall in the same column, so a load often reads what
  // the previous point just stored, and a float load from a float store forwards on every CPU
  // (one from the upper half of a stored pair does not on all). The second half of the points
  // goes to a second set of columns in the same loop, so two independent chains of loads and
  // stores run side by side; merging keeps the first half's point on ties, i.e. the first
  // point with the extreme value, as one pass would.
  col_.resize(8 * static_cast<std::size_t>(cols));
  float* lo_a = col_.data();
  float* lo_b = lo_a + cols;
  float* hi_a = lo_b + cols;
  float* hi_b = hi_a + cols;
  float* lo_a2 = hi_b + cols;
  float* lo_b2 = lo_a2 + cols;
  float* hi_a2 = lo_b2 + cols;
  float* hi_b2 = hi_a2 + cols;
  std::fill(lo_b, lo_b + cols, kInf);
  std::fill(hi_b, hi_b + cols, -kInf);
  std::fill(lo_b2, lo_b2 + cols, kInf);
  std::fill(hi_b2, hi_b2 + cols, -kInf);
#if defined(__SSE2__)
  // m ? x : y per lane, m all ones or all zeros.
  auto select = [](__m128 m, __m128 x, __m128 y) {
    return _mm_or_ps(_mm_and_ps(m, x), _mm_andnot_ps(m, y));
  };
#endif
  auto bin = [&](auto along_x_tag) {
    constexpr bool kAlongX = decltype(along_x_tag)::value;
    auto put = [&](const Eigen::Vector2f& q, float* la, float* lb, float* ha, float* hb) {
      const float a = kAlongX ? q.x() : q.y(), b = kAlongX ? q.y() : q.x();
      const int c = std::min(static_cast<int>((a - lo) * scale), cols - 1);
#if defined(__SSE2__)
      // Selects by mask: the compiler turns the scalar selects below into branches, which
      // mispredict (whether a point is its column's extreme is data-dependent).
      const __m128 va = _mm_set_ss(a), vb = _mm_set_ss(b);
      const __m128 l_b = _mm_load_ss(lb + c), h_b = _mm_load_ss(hb + c);
      const __m128 is_lo = _mm_cmplt_ss(vb, l_b), is_hi = _mm_cmpgt_ss(vb, h_b);
      _mm_store_ss(la + c, select(is_lo, va, _mm_load_ss(la + c)));
      _mm_store_ss(lb + c, select(is_lo, vb, l_b));
      _mm_store_ss(ha + c, select(is_hi, va, _mm_load_ss(ha + c)));
      _mm_store_ss(hb + c, select(is_hi, vb, h_b));
#else
      const bool is_lo = b < lb[c];
      const bool is_hi = b > hb[c];
      la[c] = is_lo ? a : la[c];
      lb[c] = is_lo ? b : lb[c];
      ha[c] = is_hi ? a : ha[c];
      hb[c] = is_hi ? b : hb[c];
#endif
    };
    const std::size_t half = n / 2;
    const Eigen::Vector2f* second = pts + half;
    for (std::size_t i = 0; i < half; ++i) {
      put(pts[i], lo_a, lo_b, hi_a, hi_b);
      put(second[i], lo_a2, lo_b2, hi_a2, hi_b2);
    }
    if (n % 2) put(pts[n - 1], lo_a2, lo_b2, hi_a2, hi_b2);
    for (int c = 0; c < cols; ++c) {
#if defined(__SSE2__)
      const __m128 l_b = _mm_load_ss(lo_b + c), l_b2 = _mm_load_ss(lo_b2 + c);
      const __m128 h_b = _mm_load_ss(hi_b + c), h_b2 = _mm_load_ss(hi_b2 + c);
      const __m128 is_lo = _mm_cmplt_ss(l_b2, l_b), is_hi = _mm_cmpgt_ss(h_b2, h_b);
      _mm_store_ss(lo_a + c, select(is_lo, _mm_load_ss(lo_a2 + c), _mm_load_ss(lo_a + c)));
      _mm_store_ss(lo_b + c, select(is_lo, l_b2, l_b));
      _mm_store_ss(hi_a + c, select(is_hi, _mm_load_ss(hi_a2 + c), _mm_load_ss(hi_a + c)));
      _mm_store_ss(hi_b + c, select(is_hi, h_b2, h_b));
#else
      const bool is_lo = lo_b2[c] < lo_b[c];
      const bool is_hi = hi_b2[c] > hi_b[c];
      lo_a[c] = is_lo ? lo_a2[c] : lo_a[c];
      lo_b[c] = is_lo ? lo_b2[c] : lo_b[c];
      hi_a[c] = is_hi ? hi_a2[c] : hi_a[c];
      hi_b[c] = is_hi ? hi_b2[c] : hi_b[c];
#endif
    }
  };
  if (along_x) {
    bin(std::true_type());
  } else {
    bin(std::false_type());
  }
  // The extremes along: the first points whose along coordinate is the box's minimum and
  // maximum (pass 1 found the values; min/max of floats are exact).
  const float hi = along_x ? mxx : mxy;
  auto firstWith = [&](float value) {
    std::size_t i = 0;
#if defined(__SSE2__)
    // Four points (eight floats) per step, comparing the along lanes only; the first equal
    // point is the same as the scalar loop's.
    static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "packed xy pairs");
    const float* f = pts[0].data();
    const __m128 v = _mm_set1_ps(value);
    const int lanes = along_x ? 0x55 : 0xaa;
    for (; i + 4 <= n; i += 4) {
      const int m = (_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(f + 2 * i), v)) |
                     _mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(f + 2 * i + 4), v)) << 4) &
                    lanes;
      if (m) {
        i += static_cast<std::size_t>(__builtin_ctz(static_cast<unsigned>(m)) / 2);
        break;
      }
    }
#endif
    while (i + 1 < n && (along_x ? pts[i].x() : pts[i].y()) != value) ++i;
    return Eigen::Vector2f(along_x ? pts[i] : Eigen::Vector2f(pts[i].y(), pts[i].x()));
  };
  const Eigen::Vector2f first = firstWith(lo), last = firstWith(hi);
  // Andrew's monotone chain without sorting: with one candidate per column, each chain is
  // already ordered along the long side. Work in (along, across) coordinates.
  cand_.resize(2 * static_cast<std::size_t>(cols) + 4);
  Eigen::Vector2f* cand = cand_.data();
  std::size_t nc = 0;
  cand[nc++] = first;
  for (int c = 0; c < cols; ++c) {
    cand[nc] = Eigen::Vector2f(lo_a[c], lo_b[c]);  // kept only if the column has a point
    nc += lo_b[c] < kInf;
  }
  cand[nc++] = last;
  const std::size_t lower_end = nc;
  cand[nc++] = last;
  for (int c = cols; c-- > 0;) {
    cand[nc] = Eigen::Vector2f(hi_a[c], hi_b[c]);
    nc += hi_b[c] > -kInf;
  }
  cand[nc++] = first;
  hull_.resize(nc);
  Eigen::Vector2f* hull = hull_.data();
  std::size_t k = 0;
  for (std::size_t i = 0; i < lower_end; ++i) {  // lower chain, first .. last
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], cand[i]) <= 0.0f) --k;
    hull[k++] = cand[i];
  }
  const std::size_t t = k + 1;  // upper chain, last .. first ('last' is on top)
  for (std::size_t i = lower_end + 1; i < nc; ++i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], cand[i]) <= 0.0f) --k;
    hull[k++] = cand[i];
  }
  hull_.resize(k - 1);  // 'first' again
  if (!along_x) {       // (y, x) is a reflection: restore x, y and counter-clockwise order
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
