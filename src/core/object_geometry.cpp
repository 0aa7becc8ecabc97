#include "urban_detection/core/object_geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace urban_detection {
namespace core {
namespace {

float cross(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Columns of the column hull (see ObjectGeometry::finish): point i goes to column
// min(int((along - lo) * scale), cols - 1), clamped to [0, cols - 1] before the conversion (the
// same column for every finite point; a guard for any other).
inline float columnOf(float along, float lo, float scale, float last_col) {
  float c = (along - lo) * scale;
  c = c < last_col ? c : last_col;  // minps order: a NaN gives last_col
  return c > 0.0f ? c : 0.0f;
}

// The across coordinate as an unsigned integer of the same order (-0 made +0 first).
inline std::uint32_t orderedBits(float across) {
  const float canonical = across + 0.0f;  // -0 + 0 = +0; not folded away (signed zeros)
  std::uint32_t u;
  std::memcpy(&u, &canonical, sizeof(u));
  return u ^ (static_cast<std::uint32_t>(static_cast<std::int32_t>(u) >> 31) | 0x80000000u);
}

// Folds point i, (along, across) = (a, b), into its column's low and high keys.
inline void foldPoint(std::uint32_t i, std::int32_t c, std::uint32_t ord, std::uint64_t* low,
                      std::uint64_t* high) {
  const std::uint64_t key = static_cast<std::uint64_t>(ord) << 32;
  low[c] = std::min(low[c], key | i);
  high[c] = std::max(high[c], key | static_cast<std::uint32_t>(~i));
}

// Pass 2 of ObjectGeometry::finish: the low and high keys of every column, points of even
// number into the *_even columns, odd into *_odd. kAlong = 0: along x, across y; 1: swapped.
template <int kAlong>
void binColumns(const Eigen::Vector2f* pts, std::size_t n, float lo, float scale, int cols,
                std::uint64_t* lo_even, std::uint64_t* lo_odd, std::uint64_t* hi_even,
                std::uint64_t* hi_odd) {
  const float last_col = static_cast<float>(cols - 1);
  std::size_t i = 0;
#if defined(__SSE2__)
  // Four points per step: their columns and ordered across bits computed side by side (the
  // same single-precision operations as columnOf and orderedBits, lane by lane), then four
  // scalar folds.
  static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "packed xy pairs");
  const float* f = n ? pts[0].data() : nullptr;
  const __m128 vlo = _mm_set1_ps(lo), vscale = _mm_set1_ps(scale), vlast = _mm_set1_ps(last_col);
  const __m128 zero = _mm_setzero_ps();
  const __m128i sign = _mm_set1_epi32(static_cast<int>(0x80000000u));
  alignas(16) std::int32_t col[4];
  alignas(16) std::uint32_t ord[4];
  for (; i + 4 <= n; i += 4) {
    const __m128 p01 = _mm_loadu_ps(f + 2 * i), p23 = _mm_loadu_ps(f + 2 * i + 4);
    const __m128 xs = _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 ys = _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(3, 1, 3, 1));
    const __m128 a = kAlong == 0 ? xs : ys, b = kAlong == 0 ? ys : xs;
    const __m128 c = _mm_max_ps(_mm_min_ps(_mm_mul_ps(_mm_sub_ps(a, vlo), vscale), vlast), zero);
    _mm_store_si128(reinterpret_cast<__m128i*>(col), _mm_cvttps_epi32(c));
    const __m128i bits = _mm_castps_si128(_mm_add_ps(b, zero));
    _mm_store_si128(reinterpret_cast<__m128i*>(ord),
                    _mm_xor_si128(bits, _mm_or_si128(_mm_srai_epi32(bits, 31), sign)));
    const std::uint32_t k = static_cast<std::uint32_t>(i);
    foldPoint(k, col[0], ord[0], lo_even, hi_even);
    foldPoint(k + 1, col[1], ord[1], lo_odd, hi_odd);
    foldPoint(k + 2, col[2], ord[2], lo_even, hi_even);
    foldPoint(k + 3, col[3], ord[3], lo_odd, hi_odd);
  }
#endif
  for (; i < n; ++i) {
    const float a = kAlong == 0 ? pts[i].x() : pts[i].y(),
                b = kAlong == 0 ? pts[i].y() : pts[i].x();
    const std::int32_t c = static_cast<std::int32_t>(columnOf(a, lo, scale, last_col));
    foldPoint(static_cast<std::uint32_t>(i), c, orderedBits(b), i & 1 ? lo_odd : lo_even,
              i & 1 ? hi_odd : hi_even);
  }
}

// Rotating calipers over the convex polygon h[0..n) (counter-clockwise): the minimum-area
// rectangle has a side on a hull edge; going round the edges, the vertices extreme along the
// edge, across it and against it only move forward, so all edges are tried in O(n). The yaw
// (an atan2) is computed once, for the best edge.
//
// Branch-light: which vertex is extreme, and whether an edge is the best so far, are
// data-dependent; as branches they mispredict about once per edge and caliper. Each caliper
// takes two steps as selects (a step that fails leaves it where it is, so a further step fails
// the same way) and only a third one as a loop, rarely entered; the best edge is kept as
// indices and its box recomputed at the end from the same floats by the same operations.
void calipers(const Eigen::Vector2f* h, std::size_t n, Eigen::Vector2f* center,
              Eigen::Vector2f* size, float* yaw_rad) {
  *center = Eigen::Vector2f::Zero();
  *size = Eigen::Vector2f::Zero();
  *yaw_rad = 0.0f;
  if (n == 0) return;
  *center = h[0];  // kept when every hull edge is degenerate (coincident points)
  // k + 1, or 0 after the last vertex; and t ? x : y; both as masks (as ternaries the compiler
  // may branch).
  auto next = [n](std::size_t k) {
    const std::size_t j = k + 1;
    return j & (std::size_t{0} - static_cast<std::size_t>(j != n));
  };
  auto pick = [](bool t, std::size_t x, std::size_t y) {
    return y ^ ((x ^ y) & (std::size_t{0} - static_cast<std::size_t>(t)));
  };
  auto dot = [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) { return a.dot(b); };
  // The edge direction and its normal (inward for a counter-clockwise polygon).
  auto axes = [&](std::size_t i, Eigen::Vector2f* u, Eigen::Vector2f* v) {
    const Eigen::Vector2f e = h[next(i)] - h[i];
    const float len = e.norm();
    *u = e / len;
    *v = Eigen::Vector2f(-u->y(), u->x());
    return len;
  };
  std::size_t a = 0, b = 0, c = 0;  // max along u, max along v (inward), min along u
  std::size_t best_i = n, best_a = 0, best_b = 0, best_c = 0;
  bool init = false;
  double best_area = std::numeric_limits<double>::infinity();
  const std::size_t steps = std::min<std::size_t>(n, 2);  // a caliper moves at most n per edge
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector2f u, v;
    if (axes(i, &u, &v) <= 0.0f) continue;
    float umax, vmax, umin;
    if (!init) {
      for (std::size_t k = 0; k < n; ++k) {
        if (dot(h[k], u) > dot(h[a], u)) a = k;
        if (dot(h[k], v) > dot(h[b], v)) b = k;
        if (dot(h[k], u) < dot(h[c], u)) c = k;
      }
      init = true;
      umax = dot(h[a], u);
      vmax = dot(h[b], v);
      umin = dot(h[c], u);
    } else {
      // Advance while the next vertex is at least as far (<= for the minimum); the projection
      // of the vertex reached is carried over. x > y ? x : y keeps y on ties, as the step does.
      umax = dot(h[a], u);
      vmax = dot(h[b], v);
      umin = dot(h[c], u);
      for (std::size_t s = 0; s < steps; ++s) {
        const float du = dot(h[next(a)], u), dv = dot(h[next(b)], v), dc = dot(h[next(c)], u);
        a = pick(du >= umax, next(a), a);
        b = pick(dv >= vmax, next(b), b);
        c = pick(dc <= umin, next(c), c);
        umax = umax > du ? umax : du;
        vmax = vmax > dv ? vmax : dv;
        umin = umin < dc ? umin : dc;
      }
      for (std::size_t s = steps; s < n && dot(h[next(a)], u) >= umax; ++s) {
        a = next(a);
        umax = dot(h[a], u);
      }
      for (std::size_t s = steps; s < n && dot(h[next(b)], v) >= vmax; ++s) {
        b = next(b);
        vmax = dot(h[b], v);
      }
      for (std::size_t s = steps; s < n && dot(h[next(c)], u) <= umin; ++s) {
        c = next(c);
        umin = dot(h[c], u);
      }
    }
    const float vmin = dot(h[i], v);
    const double area = static_cast<double>(umax - umin) * static_cast<double>(vmax - vmin);
    const bool better = area < best_area - 1e-12;
#if defined(__SSE2__)
    const __m128d keep = _mm_cmpnlt_sd(_mm_set_sd(area), _mm_set_sd(best_area - 1e-12));
    best_area = _mm_cvtsd_f64(
        _mm_or_pd(_mm_and_pd(keep, _mm_set_sd(best_area)), _mm_andnot_pd(keep, _mm_set_sd(area))));
#else
    best_area = better ? area : best_area;
#endif
    best_i = pick(better, i, best_i);
    best_a = pick(better, a, best_a);
    best_b = pick(better, b, best_b);
    best_c = pick(better, c, best_c);
  }
  if (best_i == n) return;
  Eigen::Vector2f u, v;
  axes(best_i, &u, &v);
  const float umax = dot(h[best_a], u), vmax = dot(h[best_b], v), umin = dot(h[best_c], u);
  const float vmin = dot(h[best_i], v);
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
  calipers(hull.data(), hull.size(), center, size, yaw_rad);
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
  // kHullTolerance of the exact hull, at O(n) cost instead of sorting every point.
  const bool along_x = (mxx - mnx) >= (mxy - mny);
  const float lo = along_x ? mnx : mny, len = along_x ? mxx - mnx : mxy - mny;
  const int cols = std::clamp(static_cast<int>(std::ceil(len / kHullTolerance)), 1, kMaxColumns);
  const float scale = len > 0.0f ? cols / len : 0.0f;
  // A column's extremes are kept as 64-bit keys: the across coordinate mapped to an unsigned
  // integer of the same order (sign bit flipped for >= 0, all bits for < 0; -0 is made +0
  // first, as float comparison treats them alike) in the high half, the point number in the
  // low half: the minimum key is the lowest point and, among equal ones, the first, as a
  // strict float comparison in point order would keep; the maximum key with the point number
  // complemented is the highest point, first among equals. One integer min or max per point
  // and column (a cmov), the point itself is read back only for the column's winner. Points
  // of even and odd number go to two sets of columns, merged when the candidates are read:
  // consecutive points often share a column, and two sets halve the chain of store-to-load
  // dependencies through it.
  const std::size_t ncols = static_cast<std::size_t>(cols);
  if (keys_.size() < 4 * ncols) keys_.resize(4 * ncols);
  std::uint64_t* lo_even = keys_.data();
  std::uint64_t* lo_odd = lo_even + ncols;
  std::uint64_t* hi_even = lo_odd + ncols;
  std::uint64_t* hi_odd = hi_even + ncols;
  // Empty-column sentinels: above (below) every key of a finite point, and naming point 0 (the
  // low half of kNoHigh complemented is 0), so reading a column's winner needs no branch.
  constexpr std::uint64_t kNoLow = std::uint64_t{0xffffffffu} << 32, kNoHigh = 0xffffffffu;
  std::fill(lo_even, hi_even, kNoLow);
  std::fill(hi_even, hi_odd + ncols, kNoHigh);
  if (along_x) {
    binColumns<0>(pts, n, lo, scale, cols, lo_even, lo_odd, hi_even, hi_odd);
  } else {
    binColumns<1>(pts, n, lo, scale, cols, lo_even, lo_odd, hi_even, hi_odd);
  }
  // The extremes along: the first points whose along coordinate is the box's minimum and
  // maximum (pass 1 found the values; min/max of floats are exact).
  const float hi = along_x ? mxx : mxy;
  auto ab = [along_x](const Eigen::Vector2f& q) {
    return along_x ? q : Eigen::Vector2f(q.y(), q.x());
  };
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
    return ab(pts[i]);
  };
  const Eigen::Vector2f first = firstWith(lo), last = firstWith(hi);
  // Andrew's monotone chain without sorting: with one candidate per column, each chain is
  // already ordered along the long side. Work in (along, across) coordinates.
  const std::size_t cand_size = 2 * ncols + 4;
  if (cand_.size() < cand_size) cand_.resize(cand_size);
  if (hull_.size() < cand_size) hull_.resize(cand_size);
  Eigen::Vector2f* cand = cand_.data();
  std::size_t nc = 0;
  cand[nc++] = first;
  for (std::size_t c = 0; c < ncols; ++c) {
    const std::uint64_t k = std::min(lo_even[c], lo_odd[c]);
    const bool used = k != kNoLow;
    cand[nc] = ab(pts[static_cast<std::uint32_t>(k)]);  // kept only if used
    nc += used;
  }
  cand[nc++] = last;
  const std::size_t lower_end = nc;
  cand[nc++] = last;
  for (std::size_t c = ncols; c-- > 0;) {
    const std::uint64_t k = std::max(hi_even[c], hi_odd[c]);
    const bool used = k != kNoHigh;
    cand[nc] = ab(pts[~static_cast<std::uint32_t>(k)]);
    nc += used;
  }
  cand[nc++] = first;
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
  const std::size_t nh = k - 1;  // 'first' again
  if (!along_x) {                // (y, x) is a reflection: restore x, y and counter-clockwise order
    for (std::size_t i = 0; i < nh; ++i) hull[i] = Eigen::Vector2f(hull[i].y(), hull[i].x());
    std::reverse(hull, hull + nh);
  }
  Eigen::Vector2f c, s;
  float yaw = 0.0f;
  calipers(hull, nh, &c, &s, &yaw);
  object->obb_center = Eigen::Vector3f(c.x(), c.y(), 0.5f * (mnz + mxz));
  object->obb_size = Eigen::Vector3f(s.x(), s.y(), mxz - mnz);
  object->obb_yaw_rad = yaw;
}

}  // namespace core
}  // namespace urban_detection
