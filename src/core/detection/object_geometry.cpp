#include "urban_detection/core/detection/object_geometry.h"

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

// Column keys, both kept as maxima. High key of point i: ordered across bits above, ~i below:
// the maximum is the highest point, the first among equals. Low key: the same with the across
// bits complemented (kFlipHigh), so the maximum is the lowest point, again the first among
// equals. Every finite point's keys exceed kNoPoint, the empty column, whose point number
// (~ of the low half) is 0, so reading a column's winner needs no branch.
constexpr std::uint64_t kFlipHigh = std::uint64_t{0xffffffffu} << 32;
constexpr std::uint64_t kNoPoint = 0xffffffffu;
inline std::uint64_t highKey(std::uint32_t i, std::uint32_t ord) {
  return static_cast<std::uint64_t>(ord) << 32 | static_cast<std::uint32_t>(~i);
}
inline std::uint32_t pointOf(std::uint64_t key) {
  return ~static_cast<std::uint32_t>(key);
}

// A column: its low and high keys side by side.
struct ColumnKeys {
  std::uint64_t low, high;
};

inline void foldPoint(std::uint64_t high_key, ColumnKeys* column) {
  column->low = std::max(column->low, high_key ^ kFlipHigh);
  column->high = std::max(column->high, high_key);
}

// Pass 2 of ObjectGeometry::finish: the keys of every column, and the first points whose
// along coordinate equals `lo` and `hi` (n when there is none). kAlong = 0: along x, across y;
// 1: swapped.
template <int kAlong>
void binColumns(const Eigen::Vector2f* pts, std::size_t n, float lo, float hi, float scale,
                int cols, ColumnKeys* columns, std::size_t* first_lo, std::size_t* first_hi) {
  const float last_col = static_cast<float>(cols - 1);
  std::size_t i = 0;
  *first_lo = *first_hi = n;
#if defined(__SSE2__)
  // Four points per step: their columns and keys computed side by side (the same
  // single-precision operations as columnOf and orderedBits, lane by lane), then four scalar
  // folds. Points at either end along are rare: one predictable branch per step finds them.
  static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "packed xy pairs");
  static_assert(sizeof(ColumnKeys) == 16, "column keys of 16 bytes");
  const float* f = n ? pts[0].data() : nullptr;
  const __m128 vlo = _mm_set1_ps(lo), vhi = _mm_set1_ps(hi), vscale = _mm_set1_ps(scale);
  const __m128 vlast = _mm_set1_ps(last_col), zero = _mm_setzero_ps();
  const __m128i sign = _mm_set1_epi32(static_cast<int>(0x80000000u));
  const __m128i four = _mm_set1_epi32(4);
  __m128i not_i = _mm_setr_epi32(-1, -2, -3, -4);  // ~0, ~1, ~2, ~3
  char* base = reinterpret_cast<char*>(columns);
  alignas(16) std::uint32_t offset[4];
  alignas(16) std::uint64_t key[4];
  for (; i + 4 <= n; i += 4) {
    const __m128 p01 = _mm_loadu_ps(f + 2 * i), p23 = _mm_loadu_ps(f + 2 * i + 4);
    const __m128 xs = _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(2, 0, 2, 0));
    const __m128 ys = _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(3, 1, 3, 1));
    const __m128 a = kAlong == 0 ? xs : ys, b = kAlong == 0 ? ys : xs;
    const __m128 c = _mm_max_ps(_mm_min_ps(_mm_mul_ps(_mm_sub_ps(a, vlo), vscale), vlast), zero);
    _mm_store_si128(reinterpret_cast<__m128i*>(offset), _mm_slli_epi32(_mm_cvttps_epi32(c), 4));
    const __m128i bits = _mm_castps_si128(_mm_add_ps(b, zero));
    const __m128i ord = _mm_xor_si128(bits, _mm_or_si128(_mm_srai_epi32(bits, 31), sign));
    _mm_store_si128(reinterpret_cast<__m128i*>(key), _mm_unpacklo_epi32(not_i, ord));
    _mm_store_si128(reinterpret_cast<__m128i*>(key + 2), _mm_unpackhi_epi32(not_i, ord));
    not_i = _mm_sub_epi32(not_i, four);
    const unsigned at_lo = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpeq_ps(a, vlo)));
    const unsigned at_hi = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpeq_ps(a, vhi)));
    if (at_lo | at_hi) {
      if (at_lo && *first_lo == n) *first_lo = i + static_cast<std::size_t>(__builtin_ctz(at_lo));
      if (at_hi && *first_hi == n) *first_hi = i + static_cast<std::size_t>(__builtin_ctz(at_hi));
    }
    foldPoint(key[0], reinterpret_cast<ColumnKeys*>(base + offset[0]));
    foldPoint(key[1], reinterpret_cast<ColumnKeys*>(base + offset[1]));
    foldPoint(key[2], reinterpret_cast<ColumnKeys*>(base + offset[2]));
    foldPoint(key[3], reinterpret_cast<ColumnKeys*>(base + offset[3]));
  }
#endif
  for (; i < n; ++i) {
    const float a = kAlong == 0 ? pts[i].x() : pts[i].y(),
                b = kAlong == 0 ? pts[i].y() : pts[i].x();
    const std::int32_t c = static_cast<std::int32_t>(columnOf(a, lo, scale, last_col));
    foldPoint(highKey(static_cast<std::uint32_t>(i), orderedBits(b)), columns + c);
    if (a == lo && *first_lo == n) *first_lo = i;
    if (a == hi && *first_hi == n) *first_hi = i;
  }
}

#if !defined(__SSE2__)
// One chain of Andrew's monotone chain: appends the candidates c[0..m) to the stack
// hull[0..k) (k >= 1), first popping the top hull[k-1] while k >= bottom + 2 and
// cross(hull[k-2], hull[k-1], c) <= 0 (the same float operations as cross()); returns the new
// k. The two top points are kept in registers: the point just pushed is the next top, and a pop
// reloads only the one below the new top.
inline std::size_t chain(const Eigen::Vector2f* c, std::size_t m, Eigen::Vector2f* hull,
                         std::size_t k, std::size_t bottom) {
  float ax = hull[k - 1].x(), ay = hull[k - 1].y();  // top
  float ox = 0.0f, oy = 0.0f;                        // the point below it, when k >= 2
  if (k >= 2) {
    ox = hull[k - 2].x();
    oy = hull[k - 2].y();
  }
  const std::size_t min_k = bottom + 2;
  for (std::size_t i = 0; i < m; ++i) {
    const float bx = c[i].x(), by = c[i].y();
    while (k >= min_k && (ax - ox) * (by - oy) - (ay - oy) * (bx - ox) <= 0.0f) {
      --k;
      ax = ox;
      ay = oy;
      const Eigen::Vector2f& o = hull[k >= 2 ? k - 2 : 0];
      ox = o.x();
      oy = o.y();
    }
    hull[k++] = c[i];
    ox = ax;
    oy = ay;
    ax = bx;
    ay = by;
  }
  return k;
}
#endif

#if defined(__SSE2__)
// The two chains of Andrew's monotone chain (lower and upper; each starts from one point that
// stays), interleaved so that their dependency chains overlap, and without a branch for the
// usual number of pops (0, 1 or 2; 3 or more take a branch). A chain is a stack S[0..k) whose
// four bottom entries are NaN sentinels: a turn test against a sentinel is false, no pop, as
// the plain chain does not test with fewer than two points. Its top four entries are mirrored
// in registers, x and y apart (lane j holds S[k-1-j]), so the three tests that decide 0, 1, 2
// or more pops run in lanes 0, 1, 2 of one vector: pop while cross(S[k-2], S[k-1], b) <= 0
// pops S[k-1] exactly when the tests of (S[k-2], S[k-1]), (S[k-3], S[k-2]), (S[k-4], S[k-3])
// against b are true in that order. Lane j computes cross(S[k-2-j], S[k-1-j], b) with the same
// float operations as cross(); one test per lane costs a third of the instructions of three
// tests in lanes 0 and 1.
struct Chain {
  Eigen::Vector2f* s;
  std::size_t k;
  __m128 x, y;  // lane j: S[k-1-j] (j = 0..3)
};

inline __m128 shiftDown(__m128 v) {  // lane j <- lane j + 1, lane 3 <- 0
  return _mm_castsi128_ps(_mm_srli_si128(_mm_castps_si128(v), 4));
}
inline __m128 shiftUp(__m128 v) {  // lane j <- lane j - 1, lane 0 <- 0
  return _mm_castsi128_ps(_mm_slli_si128(_mm_castps_si128(v), 4));
}
inline __m128 toLane3(float f) {
  return _mm_castsi128_ps(_mm_slli_si128(_mm_castps_si128(_mm_set_ss(f)), 12));
}

// Mirrors the top four entries of c->s[0..c->k) in c->x, c->y.
inline void loadTop(Chain* c) {
  const Eigen::Vector2f* t = c->s + c->k - 4;
  c->x = _mm_setr_ps(t[3].x(), t[2].x(), t[1].x(), t[0].x());
  c->y = _mm_setr_ps(t[3].y(), t[2].y(), t[1].y(), t[0].y());
}

void startChain(Eigen::Vector2f* s, const Eigen::Vector2f& bottom, Chain* c) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 4; ++i) s[i] = Eigen::Vector2f(nan, nan);
  s[4] = bottom;
  c->s = s;
  c->k = 5;
  loadTop(c);
}

inline void pushChain(const Eigen::Vector2f& point, Chain* c) {
  const __m128 bx = _mm_set1_ps(point.x()), by = _mm_set1_ps(point.y());
  const __m128 ox = shiftDown(c->x), oy = shiftDown(c->y);  // lane j: S[k-2-j]
  // (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x), a = S[k-1-j], o = S[k-2-j]
  const __m128 cr = _mm_sub_ps(_mm_mul_ps(_mm_sub_ps(c->x, ox), _mm_sub_ps(by, oy)),
                               _mm_mul_ps(_mm_sub_ps(c->y, oy), _mm_sub_ps(bx, ox)));
  const __m128 t = _mm_cmple_ps(cr, _mm_setzero_ps());
  const int tests = _mm_movemask_ps(t) & 7;
  std::size_t k = c->k;
  if (tests == 7) {  // three pops or more: the plain loop on the stack
    Eigen::Vector2f* s = c->s;
    k -= 3;
    while (cross(s[k - 2], s[k - 1], point) <= 0.0f) --k;
    s[k++] = point;
    c->k = k;
    loadTop(c);
    return;
  }
  // pops: 0 (t1 false), 1 (t1, not t2), 2 (t1, t2, not t3). Lanes 1..3 of the new top: pops 0:
  // S[k-1..k-3] (shifted up); 1: S[k-2..k-4] (as they are); 2: S[k-3..k-5] (shifted down,
  // S[k-5] from the stack). Lane 0: the point.
  const std::size_t pops = static_cast<std::size_t>((tests & 1) + ((tests & 3) == 3));
  // Masks of pops >= 1 (m1), pops == 2 (m2), pops == 1 (only1).
  const __m128 m1 = _mm_shuffle_ps(t, t, 0);
  const __m128 m2 = _mm_and_ps(m1, _mm_shuffle_ps(t, t, _MM_SHUFFLE(1, 1, 1, 1)));
  const __m128 only1 = _mm_xor_ps(m1, m2);
  const Eigen::Vector2f& below = c->s[k - 5];
  const __m128 x2 = _mm_or_ps(ox, toLane3(below.x())), y2 = _mm_or_ps(oy, toLane3(below.y()));
  const __m128 x = _mm_or_ps(_mm_or_ps(_mm_and_ps(m2, x2), _mm_and_ps(only1, c->x)),
                             _mm_andnot_ps(m1, shiftUp(c->x)));
  const __m128 y = _mm_or_ps(_mm_or_ps(_mm_and_ps(m2, y2), _mm_and_ps(only1, c->y)),
                             _mm_andnot_ps(m1, shiftUp(c->y)));
  k -= pops;
  c->s[k] = point;
  c->k = k + 1;
  c->x = _mm_move_ss(x, bx);
  c->y = _mm_move_ss(y, by);
}
#endif

// Edge i of the polygon h[0..n) (to h[i + 1], the last one to h[0]): its length len[i] and
// unit direction (ux[i], uy[i]) = e / len[i] (not finite when len[i] is 0), by the operations
// of Eigen's e.norm() and e / len. Computed for all edges before the calipers, four per step:
// one square root and two divisions per edge were the calipers' longest instructions, and
// packed they cost what one scalar one does (IEEE square root and division are exact to the
// last bit either way).
void edgeAxes(const Eigen::Vector2f* h, std::size_t n, float* ux, float* uy, float* len) {
  std::size_t i = 0;
#if defined(__SSE2__)
  static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float), "packed xy pairs");
  const float* f = n ? h[0].data() : nullptr;
  for (; i + 5 <= n; i += 4) {  // edges i .. i + 3 read points i .. i + 4
    const __m128 p01 = _mm_loadu_ps(f + 2 * i), p23 = _mm_loadu_ps(f + 2 * i + 4);
    const __m128 q01 = _mm_loadu_ps(f + 2 * i + 2), q23 = _mm_loadu_ps(f + 2 * i + 6);
    const __m128 ex = _mm_sub_ps(_mm_shuffle_ps(q01, q23, _MM_SHUFFLE(2, 0, 2, 0)),
                                 _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(2, 0, 2, 0)));
    const __m128 ey = _mm_sub_ps(_mm_shuffle_ps(q01, q23, _MM_SHUFFLE(3, 1, 3, 1)),
                                 _mm_shuffle_ps(p01, p23, _MM_SHUFFLE(3, 1, 3, 1)));
    const __m128 l = _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(ex, ex), _mm_mul_ps(ey, ey)));
    _mm_storeu_ps(len + i, l);
    _mm_storeu_ps(ux + i, _mm_div_ps(ex, l));
    _mm_storeu_ps(uy + i, _mm_div_ps(ey, l));
  }
#endif
  for (; i < n; ++i) {
    const std::size_t j = i + 1 < n ? i + 1 : 0;
    const float ex = h[j].x() - h[i].x(), ey = h[j].y() - h[i].y();
    len[i] = std::sqrt(ex * ex + ey * ey);
    ux[i] = ex / len[i];
    uy[i] = ey / len[i];
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
// `scratch` holds at least 3 * n floats.
void calipers(const Eigen::Vector2f* h, std::size_t n, float* scratch, Eigen::Vector2f* center,
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
  // Projection of vertex k on (dx, dy): the same products and sum as Eigen's dot().
  auto proj = [h](std::size_t k, float dx, float dy) { return h[k].x() * dx + h[k].y() * dy; };
  float* const edge_ux = scratch;
  float* const edge_uy = scratch + n;
  float* const edge_len = scratch + 2 * n;
  edgeAxes(h, n, edge_ux, edge_uy, edge_len);
  std::size_t a = 0, b = 0, c = 0;  // max along u, max along v (inward), min along u
  std::size_t best_i = n, best_a = 0, best_b = 0, best_c = 0;
  bool init = false;
  double best_area = std::numeric_limits<double>::infinity();
  const std::size_t steps = 3;  // taken as selects; a caliper moves at most n per edge
  const bool third_step = n >= 3;
  // Index k advanced by up to three steps along (dx, dy), see below.
  auto advance = [&](std::size_t k, float dx, float dy, auto farther) {
    const std::size_t k1 = next(k), k2 = next(k1), k3 = next(k2);
    const float d0 = proj(k, dx, dy), d1 = proj(k1, dx, dy), d2 = proj(k2, dx, dy);
    const float d3 = proj(k3, dx, dy);
    const bool s3 = third_step && farther(d3, d2);
    return pick(farther(d1, d0), pick(farther(d2, d1), pick(s3, k3, k2), k1), k);
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (edge_len[i] <= 0.0f) continue;
    const float ux = edge_ux[i], uy = edge_uy[i];
    const float vx = -uy, vy = ux;  // inward normal of a counter-clockwise polygon
    float umax, vmax, umin;
    if (!init) {  // the first vertices with the largest (smallest) projections
      umax = umin = proj(0, ux, uy);
      vmax = proj(0, vx, vy);
      for (std::size_t k = 1; k < n; ++k) {
        const float du = proj(k, ux, uy), dv = proj(k, vx, vy);
        a = pick(du > umax, k, a);
        b = pick(dv > vmax, k, b);
        c = pick(du < umin, k, c);
        umax = du > umax ? du : umax;
        vmax = dv > vmax ? dv : vmax;
        umin = du < umin ? du : umin;
      }
      init = true;
    } else {
      // Advance while the next vertex is at least as far (<= for the minimum). The first three
      // steps of each caliper are decided together from the projections of the vertex it is at
      // (d0) and of the next three (d1, d2, d3), all loaded as soon as the caliper's index is
      // known: step s is taken when the steps before it are and d[s] >= d[s-1] (after a failed
      // step, the next one would test the same two vertices again). So the index, carried from
      // edge to edge, waits for one load-project-compare per edge, not one per step; and a
      // caliper rarely moves more than three vertices per edge (the loops below, branches).
      // (n >= 2 here: an edge of nonzero length has two vertices; a third step only when
      // n >= 3, as a caliper moves at most n vertices.) The projection of the vertex reached
      // is recomputed from its index, off that chain, with the same operations.
      a = advance(a, ux, uy, [](float d, float prev) { return d >= prev; });
      b = advance(b, vx, vy, [](float d, float prev) { return d >= prev; });
      c = advance(c, ux, uy, [](float d, float prev) { return d <= prev; });
      umax = proj(a, ux, uy);
      vmax = proj(b, vx, vy);
      umin = proj(c, ux, uy);
      for (std::size_t s = steps; s < n && proj(next(a), ux, uy) >= umax; ++s) {
        a = next(a);
        umax = proj(a, ux, uy);
      }
      for (std::size_t s = steps; s < n && proj(next(b), vx, vy) >= vmax; ++s) {
        b = next(b);
        vmax = proj(b, vx, vy);
      }
      for (std::size_t s = steps; s < n && proj(next(c), ux, uy) <= umin; ++s) {
        c = next(c);
        umin = proj(c, ux, uy);
      }
    }
    const float vmin = proj(i, vx, vy);
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
  const float ux = edge_ux[best_i], uy = edge_uy[best_i];
  const Eigen::Vector2f u(ux, uy), v(-uy, ux);
  const float umax = proj(best_a, ux, uy), vmax = proj(best_b, v.x(), v.y());
  const float umin = proj(best_c, ux, uy), vmin = proj(best_i, v.x(), v.y());
  *center = u * (0.5f * (umin + umax)) + v * (0.5f * (vmin + vmax));
  float lu = umax - umin, lv = vmax - vmin;
  float yaw = std::atan2(uy, ux);
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
  std::vector<float> scratch(3 * hull.size());
  calipers(hull.data(), hull.size(), scratch.data(), center, size, yaw_rad);
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
  // A column's extremes are kept as 64-bit keys (see highKey): one integer maximum per point,
  // column and side (a cmov); the point itself is read back only for the column's winner.
  // (A second set of columns for every other point, splitting the store-to-load chains of
  // consecutive points in one column, measured no faster and costs a merge per column.)
  // The extremes along are the first points whose along coordinate is the box's minimum and
  // maximum (pass 1 found the values; min/max of floats are exact).
  const std::size_t ncols = static_cast<std::size_t>(cols);
  if (keys_.size() < 2 * ncols) keys_.resize(2 * ncols);
  ColumnKeys* columns = reinterpret_cast<ColumnKeys*>(keys_.data());
#if defined(__SSE2__)
  const __m128i empty = _mm_set1_epi64x(static_cast<long long>(kNoPoint));
  for (std::size_t c = 0; c < ncols; ++c) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(columns + c), empty);
  }
#else
  std::fill(columns, columns + ncols, ColumnKeys{kNoPoint, kNoPoint});
#endif
  const float hi = along_x ? mxx : mxy;
  std::size_t first_lo, first_hi;
  if (along_x) {
    binColumns<0>(pts, n, lo, hi, scale, cols, columns, &first_lo, &first_hi);
  } else {
    binColumns<1>(pts, n, lo, hi, scale, cols, columns, &first_lo, &first_hi);
  }
  auto ab = [along_x](const Eigen::Vector2f& q) {
    return along_x ? q : Eigen::Vector2f(q.y(), q.x());
  };
  // (None equal only if the moments were not of these points; the last point then stands in.)
  const Eigen::Vector2f first = ab(pts[std::min(first_lo, n - 1)]);
  const Eigen::Vector2f last = ab(pts[std::min(first_hi, n - 1)]);
  // Andrew's monotone chain without sorting: with one candidate per column, each chain is
  // already ordered along the long side. Work in (along, across) coordinates.
  const std::size_t cand_size = 2 * ncols + 4;
  if (cand_.size() < cand_size) cand_.resize(cand_size);
  if (hull_.size() < cand_size) hull_.resize(cand_size);
  Eigen::Vector2f* cand = cand_.data();
  std::size_t nc = 0;
  cand[nc++] = first;
  for (std::size_t c = 0; c < ncols; ++c) {
    const std::uint64_t k = columns[c].low;
    cand[nc] = ab(pts[pointOf(k)]);  // kept only if the column has a point
    nc += k != kNoPoint;
  }
  cand[nc++] = last;
  const std::size_t lower_end = nc;
  cand[nc++] = last;
  for (std::size_t c = ncols; c-- > 0;) {
    const std::uint64_t k = columns[c].high;
    cand[nc] = ab(pts[pointOf(k)]);
    nc += k != kNoPoint;
  }
  cand[nc++] = first;
#if defined(__SSE2__)
  // The lower chain (first .. last) and the upper chain (last .. first; as a continuation of
  // the lower one it never pops 'last') on their own stacks, interleaved; then the upper one's
  // points above 'last' are appended to the lower one's, without 'first' again.
  if (hull_.size() < cand_size + 8) hull_.resize(cand_size + 8);
  Chain lower, upper;
  startChain(hull_.data(), cand[0], &lower);
  startChain(hull_.data() + 4 + lower_end, last, &upper);
  const Eigen::Vector2f* lc = cand + 1;
  const Eigen::Vector2f* uc = cand + lower_end + 1;
  const std::size_t nl = lower_end - 1, nu = nc - lower_end - 1;
  std::size_t i = 0;
  for (; i < std::min(nl, nu); ++i) {
    pushChain(lc[i], &lower);
    pushChain(uc[i], &upper);
  }
  for (; i < nl; ++i) pushChain(lc[i], &lower);
  for (; i < nu; ++i) pushChain(uc[i], &upper);
  Eigen::Vector2f* hull = hull_.data() + 4;
  const std::size_t nlow = lower.k - 4;
  std::copy(upper.s + 5, upper.s + upper.k - 1, hull + nlow);
  const std::size_t nh = nlow + (upper.k - 6);
#else
  Eigen::Vector2f* hull = hull_.data();
  std::size_t k = 0;
  hull[k++] = cand[0];
  k = chain(cand + 1, lower_end - 1, hull, k, 0);  // lower chain, first .. last
  // Upper chain, last .. first: 'last' is on top and stays (pops need two points above it).
  k = chain(cand + lower_end + 1, nc - lower_end - 1, hull, k, k - 1);
  const std::size_t nh = k - 1;  // 'first' again
#endif
  if (!along_x) {  // (y, x) is a reflection: restore x, y and counter-clockwise order
    for (std::size_t i = 0; i < nh; ++i) hull[i] = Eigen::Vector2f(hull[i].y(), hull[i].x());
    std::reverse(hull, hull + nh);
  }
  Eigen::Vector2f c, s;
  float yaw = 0.0f;
  if (axes_.size() < 3 * nh) axes_.resize(3 * nh);
  calipers(hull, nh, axes_.data(), &c, &s, &yaw);
  object->obb_center = Eigen::Vector3f(c.x(), c.y(), 0.5f * (mnz + mxz));
  object->obb_size = Eigen::Vector3f(s.x(), s.y(), mxz - mnz);
  object->obb_yaw_rad = yaw;
}

}  // namespace core
}  // namespace urban_detection
