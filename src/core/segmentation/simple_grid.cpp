#include "urban_detection/core/segmentation/simple_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "urban_detection/core/common/grid_cells_sse2.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif
#if defined(__SSE2__) && defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define UD_SIMPLE_GRID_AVX2 1
#endif

namespace urban_detection {
namespace core {

const GridCell SimpleGrid::kEmptyCell = GridCell();

namespace {

#if defined(UD_SIMPLE_GRID_AVX2)
bool cpuHasAvx2() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
}

// Pass 1 of SimpleGrid::build (cell index and height of every point) eight points at a time,
// for CPUs with AVX2 (chosen at run time: the library is built for baseline x86-64). The same
// float operations per lane as the SSE2 loop, so the same cells and heights; the row * side
// product is one pmulld here. Points [i, end), chunk starting at `begin`; returns the first
// point not done (fewer than eight left) and sets *invalid when a point had no cell.
__attribute__((target("avx2"))) std::size_t cellPassAvx2(const PointXYZIRT* pts, std::size_t i,
                                                         std::size_t end, std::size_t begin,
                                                         float org, float inv, float side_f,
                                                         int side, float z_offset_m,
                                                         float max_abs_height_m, std::int32_t* cc,
                                                         float* pz, bool* invalid) {
  const __m256 org8 = _mm256_set1_ps(org), inv8 = _mm256_set1_ps(inv);
  const __m256 side8 = _mm256_set1_ps(side_f), off8 = _mm256_set1_ps(z_offset_m);
  const __m256 maxh8 = _mm256_set1_ps(max_abs_height_m);
  const __m256 zero8 = _mm256_setzero_ps(), sign8 = _mm256_set1_ps(-0.0f);
  const __m256i sidei = _mm256_set1_epi32(side), ones = _mm256_set1_epi32(-1);
  __m256i any_invalid = _mm256_setzero_si256();
  for (; i + 8 <= end; i += 8) {
    // As in the SSE2 loop: the cache lines 128 points ahead (prefetches never fault).
    const std::uintptr_t ahead =
        reinterpret_cast<std::uintptr_t>(pts + i) + 128 * sizeof(PointXYZIRT);
    _mm_prefetch(reinterpret_cast<const char*>(ahead), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(ahead + 64), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(ahead + 128), _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(ahead + 192), _MM_HINT_T0);
    // Points i + k and i + k + 4 (k = 0..3) in the two 128-bit halves, then the 4 x 4
    // transpose of each half (no lambda here: it would not inherit the target attribute).
    const __m256 a = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(pts[i].data)),
                                          _mm_load_ps(pts[i + 4].data), 1);
    const __m256 b = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(pts[i + 1].data)),
                                          _mm_load_ps(pts[i + 5].data), 1);
    const __m256 c = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(pts[i + 2].data)),
                                          _mm_load_ps(pts[i + 6].data), 1);
    const __m256 d = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(pts[i + 3].data)),
                                          _mm_load_ps(pts[i + 7].data), 1);
    const __m256 t0 = _mm256_unpacklo_ps(a, b), t1 = _mm256_unpacklo_ps(c, d);
    const __m256 t2 = _mm256_unpackhi_ps(a, b), t3 = _mm256_unpackhi_ps(c, d);
    const __m256 x = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 y = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 z = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 fc = _mm256_mul_ps(_mm256_sub_ps(x, org8), inv8);
    const __m256 fr = _mm256_mul_ps(_mm256_sub_ps(y, org8), inv8);
    const __m256 h = _mm256_add_ps(z, off8);
    _mm256_storeu_ps(pz + i, h);
    const __m256 ok =
        _mm256_and_ps(_mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(fc, zero8, _CMP_GE_OQ),
                                                  _mm256_cmp_ps(fc, side8, _CMP_LT_OQ)),
                                    _mm256_and_ps(_mm256_cmp_ps(fr, zero8, _CMP_GE_OQ),
                                                  _mm256_cmp_ps(fr, side8, _CMP_LT_OQ))),
                      _mm256_cmp_ps(_mm256_andnot_ps(sign8, h), maxh8, _CMP_LE_OQ));
    const __m256i valid = _mm256_castps_si256(ok);
    const __m256i cell = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(fr), sidei),
                                          _mm256_cvttps_epi32(fc));
    any_invalid = _mm256_or_si256(any_invalid, _mm256_xor_si256(valid, ones));
    _mm256_storeu_si256(
        reinterpret_cast<__m256i*>(cc + (i - begin)),
        _mm256_or_si256(_mm256_and_si256(valid, cell), _mm256_xor_si256(valid, ones)));
  }
  *invalid = !_mm256_testz_si256(any_invalid, any_invalid);
  return i;
}
#endif

}  // namespace

bool SimpleGrid::avx2Active() const {
#if defined(UD_SIMPLE_GRID_AVX2)
  return allow_avx2_ && cpuHasAvx2();
#else
  return false;
#endif
}

SimpleGrid::SimpleGrid(const SimpleGridParams& params) : params_(params) {
  // Guard against nonsense here too: callers validate, but a core class must not allocate
  // a multi-gigabyte grid or divide by zero on a bad value.
  const double cell = std::max(params_.cell_size_m, 0.01);
  const double range = std::clamp(params_.max_range_m, cell, 1000.0);
  params_.cell_size_m = cell;
  params_.max_range_m = range;
  side_ = std::max(1, static_cast<int>(std::ceil(2.0 * range / cell)));
  inv_cell_ = static_cast<float>(1.0 / cell);
  inv_side_ = 1.0 / side_;
  origin_m_ = static_cast<float>(-0.5 * side_ * cell);
  cell_m_ = static_cast<float>(cell);
  slot_.assign(static_cast<std::size_t>(side_) * side_, -1);
  occupied_.assign(slot_.size() + 1, kNoCell);
  occupied_cells_.assign(slot_.size() + 1, GridCell());
}

std::int32_t SimpleGrid::cellAt(float x_m, float y_m) const {
  // Written so that NaN fails the comparisons and lands in kNoCell.
  const float fc = (x_m - origin_m_) * inv_cell_;
  const float fr = (y_m - origin_m_) * inv_cell_;
  if (!(fc >= 0.0f && fc < static_cast<float>(side_) && fr >= 0.0f &&
        fr < static_cast<float>(side_))) {
    return kNoCell;
  }
  return static_cast<std::int32_t>(fr) * side_ + static_cast<std::int32_t>(fc);
}

void SimpleGrid::build(const CloudXYZIRT& cloud, float z_offset_m, float max_abs_height_m) {
  begin(z_offset_m, max_abs_height_m, cloud.size());
  append(cloud.points.data(), cloud.size());
  finish();
}

void SimpleGrid::begin(float z_offset_m, float max_abs_height_m, std::size_t expected_points) {
  for (std::size_t s = 0; s < num_occupied_; ++s) slot_[occupied_[s]] = -1;
  num_occupied_ = 0;
  point_slot_.clear();
  point_z_.clear();
  point_slot_.reserve(expected_points);
  point_z_.reserve(expected_points);
  z_offset_m_ = z_offset_m;
  max_abs_height_m_ = max_abs_height_m;
  run_ = Run();
  non_finite_ = 0;
  settled_ = false;
}

void SimpleGrid::settle() {
  if (settled_ || run_.cell == kNoCell) return;
  GridCell& cell = occupied_cells_[static_cast<std::size_t>(run_.slot)];
  settled_cell_ = cell;
  settled_ = true;
  cell.count += run_.count;
  cell.z_min = std::min(cell.z_min, run_.min);
  cell.z_max = std::max(cell.z_max, run_.max);
  cell.z_sum += run_.sum;
}

void SimpleGrid::unsettle() {
  if (!settled_) return;
  occupied_cells_[static_cast<std::size_t>(run_.slot)] = settled_cell_;
  settled_ = false;
}

void SimpleGrid::finish() {
  unsettle();
  settle();  // the open run into its cell, now for good
  settled_ = false;
  run_ = Run();
}

void SimpleGrid::append(const PointXYZIRT* points, std::size_t count) {
  unsettle();
  const std::size_t base = point_slot_.size();
  const std::size_t n = count;
  const float z_offset_m = z_offset_m_, max_abs_height_m = max_abs_height_m_;
  point_slot_.resize(base + n);
  point_z_.resize(base + n);
  // Two passes per chunk of points, so the chunk's cell indices stay in L1 between them:
  //  1. cell index and height of every point, without branches (SSE2, four points at a time,
  //     or AVX2, eight, when the CPU has it: the points are 32-byte records, read as 16-byte
  //     x y z _ rows and transposed). A single bounds test per point also rejects NaN
  //     (ordered comparisons with NaN are false) and inf/1e30 (outside the grid), exactly as
  //     the scalar expression does.
  //  2. slots and statistics: consecutive returns of a laser mostly fall in the same cell
  //     (~1 cm apart at 10 m; about 6 points per run on KITTI sweeps), so they are accumulated
  //     in registers over such runs and written once per run. The per-cell sum is the sum of
  //     the run sums, in point order: this defines the float result of the mean. A cell gets
  //     its slot when its first run starts, so slots follow the order of first touch.
  const float org = origin_m_, inv = inv_cell_, side_f = static_cast<float>(side_);
  const int side = side_;
  const bool use_avx2 = avx2Active();
  constexpr std::size_t kChunk = 1024;
#if defined(__SSE2__)
  constexpr std::uintptr_t kPrefetchBytes = 128 * sizeof(PointXYZIRT);  // 4 kB ahead
#endif
  chunk_cell_.resize(kChunk);
  std::int32_t* cc = chunk_cell_.data();
  std::int32_t* slot_of = slot_.data();
  // Indices below are local to the appended points; a run open at the end of the previous
  // append (or left open at this one's end) continues, so any split of a cloud into appends
  // gives build()'s floats.
  std::int32_t* ps = point_slot_.data() + base;
  float* pz = point_z_.data() + base;
  const PointXYZIRT* pts = points;
  std::int32_t* occ = occupied_.data();
  GridCell* occ_stats = occupied_cells_.data();
  std::int32_t num_occ = static_cast<std::int32_t>(num_occupied_);
  std::int32_t run_cell = run_.cell, run_slot = run_.slot;
  std::uint32_t run_count = run_.count;
  float run_min = run_.min, run_max = run_.max, run_sum = run_.sum;
  std::size_t non_finite = 0;  // among the points without a cell (only they can be)
  auto flush = [&]() {
    if (run_cell == kNoCell) return;
    GridCell& cell = occ_stats[run_slot];
    cell.count += run_count;
    cell.z_min = std::min(cell.z_min, run_min);
    cell.z_max = std::max(cell.z_max, run_max);
    cell.z_sum += run_sum;
  };
  auto cellOf = [&](const PointXYZIRT& p, float* z_out) {
    const float fc = (p.x - org) * inv;
    const float fr = (p.y - org) * inv;
    const float z = p.z + z_offset_m;
    *z_out = z;
    if (!(fc >= 0.0f && fc < side_f && fr >= 0.0f && fr < side_f &&
          std::fabs(z) <= max_abs_height_m)) {
      return kNoCell;
    }
    return static_cast<std::int32_t>(fr) * side + static_cast<std::int32_t>(fc);
  };
  // Slot of cell c, given one when it is new. Without a branch on newness (about a third of
  // the runs start a new cell, in no predictable pattern): the next slot's entries are written
  // for every run and kept only when the cell is new.
  auto slotFor = [&](std::int32_t c) {
    const std::int32_t old = slot_of[c];
    const std::int32_t is_new = old < 0;
    const std::int32_t slot = is_new ? num_occ : old;
    slot_of[c] = slot;
    occ[num_occ] = c;
    occ_stats[num_occ] = GridCell();
    num_occ += is_new;
    return slot;
  };
  // One point of pass 2 (cc holds the cell indices of the current chunk).
  std::size_t chunk_begin = 0;
  auto step = [&](std::size_t j) {
    const std::int32_t c = cc[j - chunk_begin];
    if (c == kNoCell) {
      ps[j] = 0;
      non_finite += !isFinitePoint(pts[j]);
      return;
    }
    const float z = pz[j];
    if (c == run_cell) {
      ++run_count;
      run_min = std::min(run_min, z);
      run_max = std::max(run_max, z);
      run_sum += z;
    } else {
      flush();
      run_cell = c;
      run_slot = slotFor(c);
      run_count = 1;
      run_min = run_max = run_sum = z;
    }
    ps[j] = run_slot + 1;
  };
  for (std::size_t begin = 0; begin < n; begin += kChunk) {
    const std::size_t end = std::min(n, begin + kChunk);
    chunk_begin = begin;
    std::size_t i = begin;
#if defined(__SSE2__)
    const GridCellsSse2 grid4(org, inv, side_f, max_abs_height_m, side, 0);
    const __m128 off4 = _mm_set1_ps(z_offset_m);
    const __m128i ones = _mm_set1_epi32(-1);
    __m128i any_invalid = _mm_setzero_si128();
#if defined(UD_SIMPLE_GRID_AVX2)
    if (use_avx2) {
      bool invalid = false;
      i = cellPassAvx2(pts, i, end, begin, org, inv, side_f, side, z_offset_m, max_abs_height_m, cc,
                       pz, &invalid);
      if (invalid) any_invalid = ones;
    }
#endif
    for (; i + 4 <= end; i += 4) {
      // The cloud (32 bytes a point, megabytes a sweep) mostly comes from memory: the hardware
      // prefetcher alone leaves this loop waiting for it (it streams within 4 kB pages only),
      // so the two cache lines 128 points ahead are requested here (prefetches never fault).
      const std::uintptr_t ahead = reinterpret_cast<std::uintptr_t>(pts + i) + kPrefetchBytes;
      _mm_prefetch(reinterpret_cast<const char*>(ahead), _MM_HINT_T0);
      _mm_prefetch(reinterpret_cast<const char*>(ahead + 64), _MM_HINT_T0);
      __m128 x = _mm_load_ps(pts[i].data), y = _mm_load_ps(pts[i + 1].data);
      __m128 z = _mm_load_ps(pts[i + 2].data), w = _mm_load_ps(pts[i + 3].data);
      _MM_TRANSPOSE4_PS(x, y, z, w);
      const __m128 h = _mm_add_ps(z, off4);
      _mm_storeu_ps(pz + i, h);
      __m128i valid;
      const __m128i cell = grid4.cells(x, y, h, &valid);
      any_invalid = _mm_or_si128(any_invalid, _mm_xor_si128(valid, ones));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(cc + (i - begin)), cell);
    }
    bool chunk_valid = _mm_movemask_epi8(any_invalid) == 0;
#else
    bool chunk_valid = false;
#endif
    for (; i < end; ++i) {
      cc[i - begin] = cellOf(pts[i], &pz[i]);
      chunk_valid = chunk_valid && cc[i - begin] != kNoCell;
    }
    std::size_t j = begin;
#if defined(__SSE2__)
    // Pass 2 is bound by its own dependency chains and hardly touches memory; meanwhile the
    // next chunk's points are requested, two cache lines per step, so that pass 1 of the next
    // chunk finds them in the caches instead of waiting for memory (prefetches never fault).
    const char* pf = reinterpret_cast<const char*>(pts + end);
    const char* const pf_end = reinterpret_cast<const char*>(pts + std::min(n, end + kChunk));
    // Run by run, while every point of the chunk has a cell (invalid points, which do not end a
    // run, take the point-by-point path below): the run's length within the next eight points
    // comes from one compare of their cells, and its points are added in one fixed sequence
    // of eight, the lanes past the run contributing -0.0f (x + -0.0f == x for every x, so the
    // sum is the same float as the point-by-point one). No branch depends on the run length
    // below eight, where the point-by-point path mispredicts about once per run (KITTI runs
    // are ~5 points).
    if (chunk_valid) {
      const __m128i lanes_lo = _mm_setr_epi32(0, 1, 2, 3), lanes_hi = _mm_setr_epi32(4, 5, 6, 7);
      const __m128 neg_zero = _mm_set1_ps(-0.0f);
      constexpr float kInf = std::numeric_limits<float>::infinity();
      const __m128 big = _mm_set1_ps(kInf), small = _mm_set1_ps(-kInf);
      alignas(16) float lane_z[8];
      while (j + 8 <= end) {
        if (pf < pf_end) {
          _mm_prefetch(pf, _MM_HINT_T0);
          _mm_prefetch(pf + 64, _MM_HINT_T0);
          pf += 128;
        }
        const std::int32_t c = cc[j - begin];
        if (c != run_cell) {
          flush();
          run_cell = c;
          run_slot = slotFor(c);
          run_count = 0;
          run_min = kInf;
          run_max = -kInf;
          run_sum = -0.0f;
        }
        const __m128i c4 = _mm_set1_epi32(c);
        const __m128i* cj = reinterpret_cast<const __m128i*>(cc + (j - begin));
        const unsigned same =
            static_cast<unsigned>(
                _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_loadu_si128(cj), c4)))) |
            static_cast<unsigned>(
                _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_loadu_si128(cj + 1), c4))))
                << 4;
        const int len = __builtin_ctz(~same);  // 1..8: lane 0 is c itself
        const __m128i len4 = _mm_set1_epi32(len);
        const __m128 in_lo = _mm_castsi128_ps(_mm_cmpgt_epi32(len4, lanes_lo));
        const __m128 in_hi = _mm_castsi128_ps(_mm_cmpgt_epi32(len4, lanes_hi));
        const __m128 z_lo = _mm_loadu_ps(pz + j), z_hi = _mm_loadu_ps(pz + j + 4);
        _mm_store_ps(lane_z, _mm_or_ps(_mm_and_ps(in_lo, z_lo), _mm_andnot_ps(in_lo, neg_zero)));
        _mm_store_ps(lane_z + 4,
                     _mm_or_ps(_mm_and_ps(in_hi, z_hi), _mm_andnot_ps(in_hi, neg_zero)));
        for (int l = 0; l < 8; ++l) run_sum += lane_z[l];
        __m128 lo = _mm_min_ps(_mm_or_ps(_mm_and_ps(in_lo, z_lo), _mm_andnot_ps(in_lo, big)),
                               _mm_or_ps(_mm_and_ps(in_hi, z_hi), _mm_andnot_ps(in_hi, big)));
        __m128 hi = _mm_max_ps(_mm_or_ps(_mm_and_ps(in_lo, z_lo), _mm_andnot_ps(in_lo, small)),
                               _mm_or_ps(_mm_and_ps(in_hi, z_hi), _mm_andnot_ps(in_hi, small)));
        lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(1, 0, 3, 2)));
        hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(1, 0, 3, 2)));
        lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(2, 3, 0, 1)));
        hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(2, 3, 0, 1)));
        run_min = std::min(run_min, _mm_cvtss_f32(lo));
        run_max = std::max(run_max, _mm_cvtss_f32(hi));
        run_count += static_cast<std::uint32_t>(len);
        // All eight slots are written; the lanes past the run are rewritten by the next run.
        const __m128i slot4 = _mm_set1_epi32(run_slot + 1);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(ps + j), slot4);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(ps + j + 4), slot4);
        j += static_cast<std::size_t>(len);
      }
    }
    // Four points at a time while they all continue the current run (near the sensor runs
    // are tens of points long): min and max over the four, the sum still point by point.
    // Valid heights are finite, so the order of min / max does not matter.
    for (; j + 4 <= end; j += 4) {
      const __m128i c4 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(cc + (j - begin)));
      if (run_cell == kNoCell ||
          _mm_movemask_epi8(_mm_cmpeq_epi32(c4, _mm_set1_epi32(run_cell))) != 0xFFFF) {
        for (std::size_t k = j; k < j + 4; ++k) step(k);
        continue;
      }
      const __m128 z4 = _mm_loadu_ps(pz + j);
      __m128 lo = _mm_min_ps(z4, _mm_shuffle_ps(z4, z4, _MM_SHUFFLE(1, 0, 3, 2)));
      __m128 hi = _mm_max_ps(z4, _mm_shuffle_ps(z4, z4, _MM_SHUFFLE(1, 0, 3, 2)));
      lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(2, 3, 0, 1)));
      hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(2, 3, 0, 1)));
      run_min = std::min(run_min, _mm_cvtss_f32(lo));
      run_max = std::max(run_max, _mm_cvtss_f32(hi));
      run_sum += pz[j];
      run_sum += pz[j + 1];
      run_sum += pz[j + 2];
      run_sum += pz[j + 3];
      run_count += 4;
      _mm_storeu_si128(reinterpret_cast<__m128i*>(ps + j), _mm_set1_epi32(run_slot + 1));
    }
#endif
    for (; j < end; ++j) step(j);
#if defined(__SSE2__)
    for (; pf < pf_end; pf += 64) _mm_prefetch(pf, _MM_HINT_T0);
#endif
  }
  num_occupied_ = static_cast<std::size_t>(num_occ);
  run_ = Run{run_cell, run_slot, run_count, run_min, run_max, run_sum};
  non_finite_ += non_finite;
}

}  // namespace core
}  // namespace urban_detection
