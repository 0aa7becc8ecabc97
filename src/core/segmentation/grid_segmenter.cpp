#include "urban_detection/core/segmentation/grid_segmenter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

namespace urban_detection {
namespace core {

namespace {

SimpleGridParams gridParamsOf(const GridSegmenterParams& p) {
  SimpleGridParams g;
  g.cell_size_m = p.cell_size_m;
  g.max_range_m = p.max_range_m;
  return g;
}

// Per-point label of the points of an overhang candidate cell (step 5b) until it is resolved;
// never left in the output.
constexpr std::uint8_t kPendingLabel = 5;
// Step 4b: inside the Hough window a group at least this long (the shortest van, 4.5 m, less
// a cell at each end) is exempt from the field-of-view test (vehicle_fov_test_near).
constexpr double kVanMinLength_m = 3.5;
// Step 5b's height bins: 1 / kOverhangBinsPerM m each, 64 of them (the last one open).
constexpr float kOverhangBinsPerM = 8.0f;
// Step 5b: an overhang or a thin upright's top occupies at least this many bins (seen by two
// scan rings at least: one stray return is no structure).
constexpr int kMinUpperBins = 2;

// Calls f(i) for every i < n with labels[i] == kPendingLabel, in increasing order.
template <class F>
void forEachPending(const std::uint8_t* labels, std::size_t n, F&& f) {
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128i pending = _mm_set1_epi8(static_cast<char>(kPendingLabel));
  for (; i + 16 <= n; i += 16) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(labels + i));
    for (unsigned m = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(bytes, pending)));
         m != 0; m &= m - 1) {
      f(i + static_cast<std::size_t>(__builtin_ctz(m)));
    }
  }
#endif
  for (; i < n; ++i) {
    if (labels[i] == kPendingLabel) f(i);
  }
}

constexpr int kDr[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
constexpr int kDc[8] = {-1, 0, 1, -1, 1, -1, 0, 1};

}  // namespace

std::string validate(const GridSegmenterParams& p) {
  return checkFieldRanges(p);
}

void cellGroupExtent(const SimpleGrid& grid, const std::vector<std::int32_t>& cells, float* length,
                     float* width) {
  static const std::array<std::array<float, 2>, 8> dirs = [] {
    std::array<std::array<float, 2>, 8> d{};
    for (int k = 0; k < 8; ++k) {
      d[k] = {static_cast<float>(std::cos(k * M_PI / 8.0)),
              static_cast<float>(std::sin(k * M_PI / 8.0))};
    }
    return d;
  }();
  const int cols = grid.cols();
  float lo[8], hi[8];
  std::fill(lo, lo + 8, std::numeric_limits<float>::max());
  std::fill(hi, hi + 8, std::numeric_limits<float>::lowest());
  for (const std::int32_t c : cells) {
    const int r = grid.rowOf(c);
    const float x = static_cast<float>(c - r * cols), y = static_cast<float>(r);
    for (int d = 0; d < 8; ++d) {
      const float v = x * dirs[d][0] + y * dirs[d][1];
      lo[d] = std::min(lo[d], v);
      hi[d] = std::max(hi[d], v);
    }
  }
  *length = 0.0f;
  *width = std::numeric_limits<float>::max();
  for (int d = 0; d < 8; ++d) {
    *length = std::max(*length, hi[d] - lo[d] + 1.0f);
    *width = std::min(*width, hi[d] - lo[d] + 1.0f);
  }
}

GridSegmenter::GridSegmenter(const GridSegmenterParams& params)
    : params_(params), grid_(gridParamsOf(params)), hough_(params.hough) {
  const std::size_t n = grid_.numCells();
  cell_class_.assign(n, SegmentClass::kUnknown);
  wall_support_.assign(n, 0);
  ground_z_.assign(n, 0.0f);
  ground_state_.assign(n, kNoGround);
  fill_z_.assign(n, 0.0f);
  dense_.assign(n, kEmptyOrSparse);
  vehicle_state_.assign(n, 0);
  grow_queue_.resize(n);
  touched_.resize(n);
  // Terrain bit map of fillTerrain: a zero word of padding on both sides of each row, so
  // windows reaching past the grid's left and right edges read zeros.
  bit_words_ = static_cast<std::size_t>((grid_.cols() + 63) / 64 + 2);
  terrain_bits_.assign(bit_words_ * static_cast<std::size_t>(grid_.rows()), 0);
  terrain_near_.assign(terrain_bits_.size(), 0);
}

void GridSegmenter::setParams(const GridSegmenterParams& params) {
  const bool geometry_changed =
      params.cell_size_m != params_.cell_size_m || params.max_range_m != params_.max_range_m;
  params_ = params;
  hough_.setParams(params.hough);
  streaming_ = false;  // points binned with the old heights: the next cloud is binned afresh
  if (geometry_changed) *this = GridSegmenter(params);
}

void GridSegmenter::resetScratch() {
  // Reset only what the previous frame touched (the grid has 100k+ cells, a frame ~10k).
  for (const std::int32_t c : grid_.occupiedCells()) {
    cell_class_[c] = SegmentClass::kUnknown;
    wall_support_[c] = 0;
    dense_[c] = kEmptyOrSparse;
    vehicle_state_[c] = kVehicleNone;
  }
  for (std::size_t i = 0; i < touched_count_; ++i) ground_state_[touched_[i]] = kNoGround;
  touched_count_ = 0;
}

void GridSegmenter::addPoints(std::uint32_t revolution, const PointXYZIRT* points,
                              std::size_t count) {
  // A batch starting before the previous batch started starts the revolution over: a partial
  // revolution the decoder dropped (its seq is given again to the next one) or a stream that
  // restarted. Batches start at packet boundaries, whose first firings keep the packets' order;
  // within and across neighbouring packets point times may go back a little (packets stamped
  // on receipt arrive in bursts), so the previous batch's last point is no reference.
  const bool back_in_time = count > 0 && points[0].time < stream_batch_time_;
  if (!streaming_ || revolution != stream_revolution_ || back_in_time) {
    resetScratch();  // before the grid forgets the previous frame's cells
    grid_.begin(static_cast<float>(params_.sensor_height_m),
                static_cast<float>(params_.max_abs_height_m), grid_.appended());
    streaming_ = true;
    stream_segmented_ = false;
    stream_revolution_ = revolution;
    stream_checks_.clear();
    stream_batch_time_ = -std::numeric_limits<float>::infinity();
  }
  if (count == 0) return;
  stream_checks_.emplace_back(grid_.appended(), points[0]);
  stream_checks_.emplace_back(grid_.appended() + count - 1, points[count - 1]);
  stream_batch_time_ = points[0].time;
  grid_.append(points, count);
}

bool GridSegmenter::streamMatches(const CloudXYZIRT& cloud) const {
  if (!streaming_ || cloud.header.seq != stream_revolution_ || grid_.appended() > cloud.size()) {
    return false;
  }
  auto same = [](const PointXYZIRT& a, const PointXYZIRT& b) {
    return std::memcmp(&a.x, &b.x, 3 * sizeof(float)) == 0 &&
           std::memcmp(&a.intensity, &b.intensity, sizeof(float)) == 0 && a.ring == b.ring &&
           std::memcmp(&a.time, &b.time, sizeof(float)) == 0;
  };
  for (const auto& check : stream_checks_) {
    if (!same(cloud.points[check.first], check.second)) return false;
  }
  return true;
}

void GridSegmenter::segment(const CloudXYZIRT& cloud, std::vector<SegmentClass>* labels) {
  last_used_stream_ = streamMatches(cloud);
  if (last_used_stream_) {
    // The scratch was reset when the stream began (or holds a segmentSoFar()'s); only the
    // points not added yet are left.
    if (stream_segmented_) resetScratch();
    const std::size_t done = grid_.appended();
    grid_.append(cloud.points.data() + done, cloud.size() - done);
    grid_.finish();
  } else {
    resetScratch();
    grid_.build(cloud, static_cast<float>(params_.sensor_height_m),
                static_cast<float>(params_.max_abs_height_m));
  }
  streaming_ = false;
  segmentBinned(cloud, labels);
}

void GridSegmenter::segmentSoFar(const CloudXYZIRT& cloud, std::vector<SegmentClass>* labels) {
  if (!streamMatches(cloud) || grid_.appended() != cloud.size()) {
    segment(cloud, labels);
    return;
  }
  last_used_stream_ = true;
  if (stream_segmented_) resetScratch();  // the previous segmentSoFar() of this stream
  stream_segmented_ = true;
  grid_.settle();
  segmentBinned(cloud, labels);
}

void GridSegmenter::segmentBinned(const CloudXYZIRT& cloud, std::vector<SegmentClass>* labels) {
  stats_ = SegmentationStats();
  stats_.cells_occupied = static_cast<std::uint32_t>(grid_.occupiedCells().size());

  const std::uint32_t min_pts =
      static_cast<std::uint32_t>(std::max(1, params_.min_points_per_cell));
  const ConstArrayView<std::int32_t> occupied = grid_.occupiedCells();
  const ConstArrayView<GridCell> stats = grid_.occupiedStats();
  // Per cell: clutter, or dense (and flat); per slot: the elevation the terrain growing
  // compares (the mean of a flat cell, the lowest point of a mixed one).
  const float flat = static_cast<float>(params_.ground_max_range_m);
  slot_elev_.resize(occupied.size());
  for (std::size_t s = 0; s < occupied.size(); ++s) {
    const std::int32_t c = occupied[s];
    const GridCell& cell = stats[s];
    if (cell.count < min_pts) {
      cell_class_[c] = SegmentClass::kClutter;
      continue;
    }
    const bool is_flat = cell.zRange() < flat;
    dense_[c] = is_flat ? kDenseFlat : kDense;
    slot_elev_[s] = is_flat ? cell.zMean() : cell.z_min;
  }

  growGround();
  fillTerrain();
  classifyCells();
  shortenVehicles();
  if (params_.hough.enabled) {
    stats_.hough = hough_.refine(grid_.rows(), grid_.cols(), grid_.params().cell_size_m,
                                 &cell_class_, &wall_support_);
  }

  // Per point: mixed cells are split by the height above the local ground, with the table of
  // split heights and classes by slot + 1 that classifyCells filled (see there). The Hough
  // refinement turned some short cells tall: same split, new class.
  if (params_.hough.enabled) {
    for (const std::int32_t c : hough_.relabeledCells()) {
      slot_label_[static_cast<std::size_t>(grid_.slotOf(c)) + 1].label =
          static_cast<std::uint32_t>(SegmentClass::kTall);
    }
  }
  const std::size_t n = cloud.size();
  labels->resize(n);
  const std::int32_t* pc = grid_.pointSlots().data();
  const float* pz = grid_.pointHeights().data();
  const SlotLabel* table = slot_label_.data();
  static_assert(sizeof(SegmentClass) == 1, "labels are written as bytes");
  static_assert(sizeof(SlotLabel) == 8, "slot table entries are loaded as 8 bytes");
  std::uint8_t* out = reinterpret_cast<std::uint8_t*>(labels->data());
  constexpr std::uint32_t kGroundLabel = static_cast<std::uint32_t>(SegmentClass::kGround);
  // counts[k]: points labelled k, for k = 1..4 (kUnknown is the rest); pending points (step 5b)
  // are counted once resolved.
  std::uint32_t counts[6] = {0, 0, 0, 0, 0, 0};
  std::size_t i = 0;
#if defined(__SSE2__)
  // 16 points per step: each point's 8-byte table entry is loaded and transposed into four
  // split heights and four classes; the compare and select are done four lanes at a time and
  // the labels packed to bytes, which are counted per class with byte compares (the byte
  // counters are folded into 64-bit sums before they can overflow).
  const __m128i ground4 = _mm_set1_epi32(static_cast<int>(kGroundLabel));
  __m128i acc[5], sums[5];
  for (int k = 1; k <= 4; ++k) {
    acc[k] = _mm_setzero_si128();
    sums[k] = _mm_setzero_si128();
  }
  auto four = [&](std::size_t j) {
    const __m128i e0 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(table + pc[j]));
    const __m128i e1 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(table + pc[j + 1]));
    const __m128i e2 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(table + pc[j + 2]));
    const __m128i e3 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(table + pc[j + 3]));
    const __m128 a = _mm_castsi128_ps(_mm_unpacklo_epi64(e0, e1));  // s0 l0 s1 l1
    const __m128 b = _mm_castsi128_ps(_mm_unpacklo_epi64(e2, e3));  // s2 l2 s3 l3
    const __m128 split4 = _mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0));
    const __m128i cls4 = _mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
    // Ordered compare, as the scalar `<`: NaN heights are never below.
    const __m128i below = _mm_castps_si128(_mm_cmplt_ps(_mm_loadu_ps(pz + j), split4));
    return _mm_or_si128(_mm_and_si128(below, ground4), _mm_andnot_si128(below, cls4));
  };
  std::size_t block = 0;
  for (; i + 16 <= n; i += 16) {
    // The per-point slots and heights (1 MB for a KITTI sweep, written by the grid build
    // before the cell passes) are requested 4 kB ahead; prefetches never fault.
    _mm_prefetch(reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(pc + i) + 4096),
                 _MM_HINT_T0);
    _mm_prefetch(reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(pz + i) + 4096),
                 _MM_HINT_T0);
    const __m128i lo = _mm_packs_epi32(four(i), four(i + 4));
    const __m128i hi = _mm_packs_epi32(four(i + 8), four(i + 12));
    const __m128i bytes = _mm_packus_epi16(lo, hi);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), bytes);
    for (int k = 1; k <= 4; ++k) {
      acc[k] = _mm_sub_epi8(acc[k], _mm_cmpeq_epi8(bytes, _mm_set1_epi8(static_cast<char>(k))));
    }
    if (++block == 255) {
      for (int k = 1; k <= 4; ++k) {
        sums[k] = _mm_add_epi64(sums[k], _mm_sad_epu8(acc[k], _mm_setzero_si128()));
        acc[k] = _mm_setzero_si128();
      }
      block = 0;
    }
  }
  for (int k = 1; k <= 4; ++k) {
    sums[k] = _mm_add_epi64(sums[k], _mm_sad_epu8(acc[k], _mm_setzero_si128()));
    counts[k] = static_cast<std::uint32_t>(_mm_cvtsi128_si32(sums[k]) +
                                           _mm_cvtsi128_si32(_mm_srli_si128(sums[k], 8)));
  }
#endif
  for (; i < n; ++i) {
    const SlotLabel& e = table[pc[i]];
    const std::uint32_t label = pz[i] < e.split_z ? kGroundLabel : e.label;
    out[i] = static_cast<std::uint8_t>(label);
    ++counts[label];
  }
  if (!overhang_slots_.empty()) resolveOverhangs(cloud, out, counts);
  counts[0] = static_cast<std::uint32_t>(n) - counts[1] - counts[2] - counts[3] - counts[4];
  stats_.points_unknown = counts[static_cast<int>(SegmentClass::kUnknown)];
  stats_.points_non_finite = static_cast<std::uint32_t>(grid_.nonFinitePoints());
  stats_.points_clutter = counts[static_cast<int>(SegmentClass::kClutter)];
  stats_.points_ground = counts[static_cast<int>(SegmentClass::kGround)];
  stats_.points_tall = counts[static_cast<int>(SegmentClass::kTall)];
  stats_.points_short = counts[static_cast<int>(SegmentClass::kShort)];
}

// Region growing of the terrain from ground cells around the sensor. A flat cell joins when
// its mean elevation is within ground_max_step_m of the cell it is reached from, and then
// propagates further; a cell holding ground and object returns joins through its lowest point
// but does not propagate, so the growing cannot climb a car body or a wall cell by cell.
//
// Speed (same visiting order and float operations as the plain breadth-first search): each
// queue entry carries its row, ground height and hop count, so a dequeued cell needs no
// division and no per-cell lookups; a neighbour is first tested on two byte maps (ground state,
// then dense_: empty or sparse / dense / dense and flat) and only a dense one reads its
// elevation, precomputed per slot in segment(); the eight neighbours are unrolled, with bounds
// checks only for cells on the grid's border.
void GridSegmenter::growGround() {
  const float step = static_cast<float>(params_.ground_max_step_m);
  const float seed_h = static_cast<float>(params_.seed_max_abs_height_m);
  const float tol = static_cast<float>(params_.ground_tolerance_m);
  const float seed_r2 = static_cast<float>(params_.seed_radius_m * params_.seed_radius_m);
  const int rows = grid_.rows(), cols = grid_.cols();

  const ConstArrayView<std::int32_t> occupied = grid_.occupiedCells();
  // Every cell given a terrain here is also set in fillTerrain's bit map (bit k + 64 of its
  // row: one zero word of padding left of each row).
  std::uint64_t* bits = terrain_bits_.data();
  const std::size_t bit_words = bit_words_;
  auto markTerrain = [bits, bit_words](int r, int k) {
    bits[static_cast<std::size_t>(r) * bit_words + ((k + 64) >> 6)] |= std::uint64_t{1}
                                                                       << ((k + 64) & 63);
  };
  // Each cell is queued and touched at most once per frame: both buffers hold numCells().
  QueueEntry* queue = grow_queue_.data();
  std::int32_t* touched = touched_.data() + touched_count_;
  std::uint8_t* state = ground_state_.data();
  const std::uint8_t* dense = dense_.data();
  float* ground_z = ground_z_.data();
  const float* elev = slot_elev_.data();
  std::size_t tail = 0;
  for (std::size_t s = 0; s < occupied.size(); ++s) {
    // Dense, flat (then elev is the mean) and close to z = 0, near the sensor.
    const std::int32_t c = occupied[s];
    if (dense[c] != kDenseFlat || std::fabs(elev[s]) > seed_h) continue;
    float x, y;
    grid_.cellCenter(c, &x, &y);
    if (x * x + y * y > seed_r2) continue;
    const int r = grid_.rowOf(c);
    state[c] = kReached;
    ground_z[c] = elev[s];
    markTerrain(r, c - r * cols);
    *touched++ = c;
    queue[tail++] = QueueEntry{c, elev[s], r, 0};
  }
  std::uint32_t reached = static_cast<std::uint32_t>(tail);
  const int max_hops =
      std::min(250, static_cast<int>(params_.ground_max_gap_m / grid_.params().cell_size_m));
  for (std::size_t head = 0; head < tail; ++head) {
    const QueueEntry q = queue[head];
    const int r = q.row, k = q.cell - q.row * cols;
    const float g = q.ground_z;
    const int hop = q.hops;
    // One neighbour (the visiting order decides which neighbour reaches a cell first, hence
    // its ground height).
    auto visit = [&](int dr, int dc) {
      const std::int32_t nc = q.cell + dr * cols + dc;
      if (state[nc] != kNoGround) return;
      const std::uint8_t dn = dense[nc];
      if (dn == kEmptyOrSparse) {
        // Empty and sparse cells carry the terrain across the gaps between far rings and
        // through shadows, for a limited distance; sparse cells keep it for their points.
        if (hop >= max_hops) return;
        state[nc] = kBridged;
        ground_z[nc] = g;
        markTerrain(r + dr, k + dc);
        *touched++ = nc;
        queue[tail++] = QueueEntry{nc, g, r + dr, hop + 1};
        return;
      }
      const bool is_flat = dn == kDenseFlat;
      const float e = elev[grid_.slotOf(nc)];
      if (std::fabs(e - g) >= step) return;
      state[nc] = kReached;
      markTerrain(r + dr, k + dc);
      // The lowest point of a mixed cell is its ground unless it lies clearly above the terrain
      // it was reached from: then the base was not sampled (a wall hit above its foot at range)
      // and that point belongs to the object.
      const float gz = !is_flat && e - g > tol ? g : e;
      ground_z[nc] = gz;
      *touched++ = nc;
      ++reached;
      if (is_flat) queue[tail++] = QueueEntry{nc, gz, r + dr, 0};
    };
    if (r > 0 && r < rows - 1 && k > 0 && k < cols - 1) {
      visit(-1, -1);
      visit(-1, 0);
      visit(-1, 1);
      visit(0, -1);
      visit(0, 1);
      visit(1, -1);
      visit(1, 0);
      visit(1, 1);
    } else {
      for (int d = 0; d < 8; ++d) {
        const int nr = r + kDr[d], nk = k + kDc[d];
        if (nr >= 0 && nr < rows && nk >= 0 && nk < cols) visit(kDr[d], kDc[d]);
      }
    }
  }
  touched_count_ = static_cast<std::size_t>(touched - touched_.data());
  stats_.cells_ground_reached = reached;
}

// Occupied cells the growing did not reach (under a car roof, a bush, behind an occluder) take
// the mean ground elevation of the nearest ring of cells with a terrain estimate, up to
// terrain_fill_iterations cells away. Searching around the few unreached cells is much cheaper
// than dilating the whole terrain map. Most of these cells (facades, far vegetation) have no
// terrain within the search radius at all, so the nearest non-empty ring is found first on a
// bit map of the terrain cells (one 64-bit window per row), and only that ring is then summed,
// in the same row-major order as a plain ring scan. A second bit map, the terrain bits ORed
// over the 2 * terrain_fill_iterations + 1 rows around each row, answers "no terrain within
// the search radius" with one window per cell (the cell's own bit is clear: it has no
// terrain), and only the other cells look for their nearest ring, row pair by row pair.
void GridSegmenter::fillTerrain() {
  const int rows = grid_.rows(), cols = grid_.cols();
  const int max_ring = params_.terrain_fill_iterations;
  fill_cells_.clear();
  // Sum of the terrain of ring `ring` around (r, k), row by row, left to right.
  auto ringSum = [&](int r, int k, int ring, float* sum) {
    int cnt = 0;
    const int r0 = std::max(0, r - ring), r1 = std::min(rows - 1, r + ring);
    const int k0 = std::max(0, k - ring), k1 = std::min(cols - 1, k + ring);
    for (int rr = r0; rr <= r1; ++rr) {
      const bool edge_row = rr == r - ring || rr == r + ring;
      const int step = edge_row ? 1 : std::max(1, 2 * ring);
      for (int kk = edge_row ? k0 : k - ring; kk <= k1; kk += step) {
        if (kk < k0) continue;
        const std::int32_t nc = rr * cols + kk;
        const std::uint8_t st = ground_state_[nc];
        if (st == kReached || st == kBridged) {
          *sum += ground_z_[nc];
          ++cnt;
        }
      }
    }
    return cnt;
  };
  // terrain_bits_ holds the cells growGround gave a terrain (all kReached / kBridged so far).
  const bool use_bits = max_ring >= 1 && max_ring <= kMaxBitRing;
  const bool sparse_ground = params_.ground_in_sparse_cells;
  const std::uint64_t window_mask = (std::uint64_t{1} << (2 * max_ring + 1)) - 1;
  const std::size_t bw = bit_words_;
  if (use_bits) {
    // The OR over the rows r - max_ring .. r + max_ring, for every r, with three ORs per word
    // instead of 2 * max_ring + 1: the rows, padded with max_ring zero rows on both sides, are cut
    // into blocks of 2 * max_ring + 1; `fwd` ORs each block from its start, `bwd` from its end.
    // A window of that many rows is either one whole block or the end of one block and the start
    // of the next: bwd at its first row | fwd at its last row.
    const int span = 2 * max_ring + 1;
    const int total = rows + 2 * max_ring;  // padded rows; padded row v is row v - max_ring
    const std::size_t words = static_cast<std::size_t>(total) * bw;
    near_fwd_.resize(words);
    near_bwd_.resize(words);
    zero_row_.assign(bw, 0);
    auto rowBits = [&](int v) {
      const int rr = v - max_ring;
      return rr < 0 || rr >= rows ? zero_row_.data()
                                  : terrain_bits_.data() + static_cast<std::size_t>(rr) * bw;
    };
    for (int v = 0; v < total; ++v) {
      const std::uint64_t* w = rowBits(v);
      std::uint64_t* f = near_fwd_.data() + static_cast<std::size_t>(v) * bw;
      if (v % span == 0) {
        std::copy(w, w + bw, f);
      } else {
        const std::uint64_t* prev = f - bw;  // the previous padded row (v >= 1 here)
        for (std::size_t i = 0; i < bw; ++i) f[i] = prev[i] | w[i];
      }
    }
    for (int v = total - 1; v >= 0; --v) {
      const std::uint64_t* w = rowBits(v);
      std::uint64_t* b = near_bwd_.data() + static_cast<std::size_t>(v) * bw;
      if (v % span == span - 1 || v == total - 1) {
        std::copy(w, w + bw, b);
      } else {
        for (std::size_t i = 0; i < bw; ++i) b[i] = b[i + bw] | w[i];
      }
    }
    for (int r = 0; r < rows; ++r) {
      // Rows r - max_ring .. r + max_ring are padded rows r .. r + 2 * max_ring.
      std::uint64_t* near = terrain_near_.data() + static_cast<std::size_t>(r) * bw;
      const std::uint64_t* b = near_bwd_.data() + static_cast<std::size_t>(r) * bw;
      const std::uint64_t* f = near_fwd_.data() + static_cast<std::size_t>(r + 2 * max_ring) * bw;
      for (std::size_t i = 0; i < bw; ++i) near[i] = b[i] | f[i];
    }
  }
  // Terrain bits of columns k - max_ring .. k + max_ring of row rr of `map`.
  auto window = [&](const std::vector<std::uint64_t>& map, int rr, int k) -> std::uint64_t {
    if (rr < 0 || rr >= rows) return 0;
    const int start = k - max_ring + 64;
    const int word = start >> 6, shift = start & 63;
    const std::uint64_t* w = map.data() + static_cast<std::size_t>(rr) * bw;
    std::uint64_t v = w[word] >> shift;
    if (shift != 0) v |= w[word + 1] << (64 - shift);
    return v & window_mask;
  };
  for (const std::int32_t c : grid_.occupiedCells()) {
    if (ground_state_[c] != kNoGround ||
        (!sparse_ground && cell_class_[c] == SegmentClass::kClutter)) {
      continue;
    }
    const int r = grid_.rowOf(c), k = grid_.colOf(c);
    int first_ring = 1, last_ring = max_ring;
    if (use_bits) {
      if (window(terrain_near_, r, k) == 0) continue;     // no terrain within max_ring
      std::uint64_t inner = window(terrain_bits_, r, k);  // rows strictly inside the ring
      int found = 0;
      for (int ring = 1; ring <= max_ring && found == 0; ++ring) {
        const std::uint64_t full = ((std::uint64_t{1} << (2 * ring + 1)) - 1) << (max_ring - ring);
        const std::uint64_t sides =
            (std::uint64_t{1} << (max_ring - ring)) | (std::uint64_t{1} << (max_ring + ring));
        const std::uint64_t edges =
            window(terrain_bits_, r - ring, k) | window(terrain_bits_, r + ring, k);
        if ((edges & full) | (inner & sides)) found = ring;
        inner |= edges;
      }
      if (found == 0) continue;
      // The ring's terrain cells are the set bits of its rows' windows (edge rows: columns
      // k - found .. k + found, the rows between: those two columns), summed in row-major order
      // from the bits, as ringSum would visit them.
      const std::uint64_t full = ((std::uint64_t{1} << (2 * found + 1)) - 1) << (max_ring - found);
      const std::uint64_t sides =
          (std::uint64_t{1} << (max_ring - found)) | (std::uint64_t{1} << (max_ring + found));
      float sum = 0.0f;
      int cnt = 0;
      for (int rr = r - found; rr <= r + found; ++rr) {
        std::uint64_t m =
            window(terrain_bits_, rr, k) & (rr == r - found || rr == r + found ? full : sides);
        for (; m != 0; m &= m - 1) {
          sum += ground_z_[rr * cols + k - max_ring + __builtin_ctzll(m)];
          ++cnt;
        }
      }
      fill_cells_.push_back(c);
      fill_z_[c] = sum / static_cast<float>(cnt);
      continue;
    }
    for (int ring = first_ring; ring <= last_ring; ++ring) {
      float sum = 0.0f;
      const int cnt = ringSum(r, k, ring, &sum);
      if (cnt > 0) {
        fill_cells_.push_back(c);
        fill_z_[c] = sum / static_cast<float>(cnt);
        break;
      }
    }
  }
  // Cleared whole (a few kB): cheaper than finding the row and column of every set bit.
  std::fill(terrain_bits_.begin(), terrain_bits_.end(), std::uint64_t{0});
  // Applied afterwards so that filled cells do not feed each other within one frame.
  for (const std::int32_t c : fill_cells_) {
    ground_z_[c] = fill_z_[c];
    ground_state_[c] = kFilled;
    touched_[touched_count_++] = c;
  }
}

void GridSegmenter::classifyCells() {
  const float flat = static_cast<float>(params_.ground_max_range_m);
  const float tol = static_cast<float>(params_.ground_tolerance_m);
  const float tall_h = static_cast<float>(params_.tall_min_height_m);
  const float tall_range = static_cast<float>(params_.tall_min_range_m);
  const float terrain_offset = static_cast<float>(params_.terrain_max_offset_m);
  const float step = static_cast<float>(params_.ground_max_step_m);
  const bool curb_cells = params_.curb_cells_ground;
  // A neighbour reached by the terrain growing has its ground at `z_top` (within the tolerance).
  // Reached cells keep their ground in this pass, so the visiting order does not matter.
  const int rows = grid_.rows(), cols = grid_.cols();
  auto upperLevelIsGround = [&](std::int32_t c, float z_top) {
    const int r = grid_.rowOf(c), k = c - r * cols;
    for (int d = 0; d < 8; ++d) {
      const int nr = r + kDr[d], nk = k + kDc[d];
      if (nr < 0 || nr >= rows || nk < 0 || nk >= cols) continue;
      const std::int32_t n = nr * cols + nk;
      if (ground_state_[n] == kReached && std::fabs(ground_z_[n] - z_top) < tol) return true;
    }
    return false;
  };
  const float sensor_h = static_cast<float>(params_.sensor_height_m);
  const float tan_top = static_cast<float>(std::tan(params_.fov_top_elevation_deg * M_PI / 180.0));
  const float half_diag = static_cast<float>(params_.cell_size_m * M_SQRT1_2);
  const ConstArrayView<std::int32_t> occupied = grid_.occupiedCells();
  const ConstArrayView<GridCell> stats = grid_.occupiedStats();
  // Also the per-point pass's table, by slot + 1 (the grid's per-point index), so that a point
  // without a cell reads the sentinel entry 0 (never ground, kUnknown): the split height (points
  // below it are ground) and the class of each cell. The per-point loop is then two lookups in
  // small tables and a compare without a branch (consecutive points often change cells, at
  // range almost always, so a branch on the cell mispredicts). "No split" is -inf, not
  // lowest(): a point without a cell may have z = -inf, which must not compare below it.
  // Ground-bearing short and tall cells are split; clutter (sparse) cells too when
  // ground_in_sparse_cells is set.
  const bool sparse_ground = params_.ground_in_sparse_cells;
  const float vehicle_h = static_cast<float>(params_.vehicle_max_height_m);
  vehicle_cells_.clear();
  // Step 5b's candidates: tall by their top, with a terrain estimate, near enough.
  const bool overhangs = params_.overhang_min_gap_m > 0.0 || params_.thin_max_width_m > 0.0;
  const float overhang_r2 =
      static_cast<float>(params_.overhang_max_range_m * params_.overhang_max_range_m);
  overhang_slots_.clear();
  constexpr float kNoSplit = -std::numeric_limits<float>::infinity();
  slot_label_.resize(occupied.size() + 1);
  slot_label_[0] = SlotLabel{kNoSplit, static_cast<std::uint32_t>(SegmentClass::kUnknown)};
  SlotLabel* table = slot_label_.data() + 1;
  for (std::size_t s = 0; s < occupied.size(); ++s) {
    const std::int32_t c = occupied[s];
    if (cell_class_[c] == SegmentClass::kClutter) {
      const bool split = sparse_ground && ground_state_[c] != kNoGround;
      table[s] = SlotLabel{split ? ground_z_[c] + tol : kNoSplit,
                           static_cast<std::uint32_t>(SegmentClass::kClutter)};
      continue;
    }
    const GridCell& cell = stats[s];
    const std::uint8_t state = ground_state_[c];
    // Without any terrain estimate the plane below the sensor is the reference.
    const float g = state != kNoGround ? ground_z_[c] : 0.0f;
    SegmentClass cls = SegmentClass::kShort;
    if (cell.z_max - g > tall_h || cell.zRange() > tall_range) {
      cls = SegmentClass::kTall;
      if (cell.z_max - g <= vehicle_h && cell.zRange() <= vehicle_h) {
        vehicle_state_[c] = kVehicleCandidate;
        vehicle_cells_.push_back(c);
      }
    } else if (cell.z_max - g < tol) {
      cls = SegmentClass::kGround;
    } else if (state != kReached && cell.zRange() < flat &&
               std::fabs(cell.zMean() - g) < terrain_offset) {
      // A flat patch the growing did not reach, close to the surrounding terrain (paper: the
      // neighbours' elevation within an allowed range): ground at its own elevation.
      cls = SegmentClass::kGround;
      if (state == kNoGround) touched_[touched_count_++] = c;
      ground_state_[c] = kFilled;
      ground_z_[c] = cell.zMean();
    } else if (curb_cells && state == kReached && cell.zRange() < step &&
               std::fabs(cell.z_min - g) < step && cell.z_max - g < step &&
               upperLevelIsGround(c, cell.z_max)) {
      // A step in the ground inside one cell (a kerb between road and sidewalk): the terrain
      // of a flat cell is its mean, between the two levels, so the upper level would lie above
      // the tolerance and become a thin short strip along every kerb. It is ground when both
      // levels are: the span is a step the terrain growing accepts and the top is the ground
      // of a neighbouring cell (the sidewalk). The low edge of a car or a bench has no ground
      // at its top next to it and stays short.
      cls = SegmentClass::kGround;
    } else {
      cls = SegmentClass::kShort;
      // Seen up to the upper edge of the field of view: the structure may be much taller than
      // what is visible (paper Fig. 3). The nearest point of the cell gives the largest angle.
      float x, y;
      grid_.cellCenter(c, &x, &y);
      const float d = std::max(0.0f, std::sqrt(x * x + y * y) - half_diag);
      wall_support_[c] = cell.z_max - sensor_h >= d * tan_top ? 1 : 0;
    }
    cell_class_[c] = cls;
    // A ground cell is never split; the others keep the state and ground read above.
    const bool split =
        (cls == SegmentClass::kShort || cls == SegmentClass::kTall) && state != kNoGround;
    table[s] = SlotLabel{split ? g + tol : kNoSplit, static_cast<std::uint32_t>(cls)};
    if (overhangs && cls == SegmentClass::kTall && state != kNoGround && cell.z_max - g > tall_h) {
      float x, y;
      grid_.cellCenter(c, &x, &y);
      if (x * x + y * y <= overhang_r2) {
        table[s].label = kPendingLabel;
        overhang_slots_.push_back(static_cast<std::int32_t>(s));
      }
    }
  }
}

// A truck, bus or van is taller than tall_min_height_m but lower than vehicle_max_height_m. Its
// cells (tall ones at most vehicle_max_height_m high, and the short ones of its lower body)
// form a group of non-ground cells that fits a vehicle box, touches no higher tall cell and is
// seen whole (its top below the upper edge of the field of view); walls, hedges, facades cut by
// the field of view and tree canopies are longer, higher, joined to higher structure or may be
// any height. The group's extent is
// measured along 8 directions 22.5 deg apart (cell centres in cell units, plus one cell): the
// longest is its length, the shortest its width (within ~2 % of an oriented box's).
void GridSegmenter::shortenVehicles() {
  if (!(params_.vehicle_max_height_m > 0.0) || vehicle_cells_.empty()) return;
  const int rows = grid_.rows(), cols = grid_.cols();
  const float max_len = static_cast<float>(params_.vehicle_max_length_m / params_.cell_size_m);
  const float max_wid = static_cast<float>(params_.vehicle_max_width_m / params_.cell_size_m);
  const float min_len = static_cast<float>(kVanMinLength_m / params_.cell_size_m);
  const ConstArrayView<GridCell> stats = grid_.occupiedStats();
  const float sensor_h = static_cast<float>(params_.sensor_height_m);
  const float tan_top = static_cast<float>(std::tan(params_.fov_top_elevation_deg * M_PI / 180.0));
  const float half_diag = static_cast<float>(params_.cell_size_m * M_SQRT1_2);
  // [m] half side of the Hough window, where the field-of-view test is left to step 5 (0: none)
  const float hough_window = params_.hough.enabled && !params_.vehicle_fov_test_near
                                 ? static_cast<float>(params_.hough.max_range_m)
                                 : 0.0f;
  for (const std::int32_t seed : vehicle_cells_) {
    if (vehicle_state_[seed] != kVehicleCandidate) continue;
    // The group: breadth first over 8-neighbours that are candidates or short.
    bool touches_higher = false;
    vehicle_group_.clear();
    vehicle_group_.push_back(seed);
    vehicle_state_[seed] = kVehicleGrouped;
    for (std::size_t head = 0; head < vehicle_group_.size(); ++head) {
      const std::int32_t c = vehicle_group_[head];
      const int r = grid_.rowOf(c), k = c - r * cols;
      for (int d = 0; d < 8; ++d) {
        const int nr = r + kDr[d], nk = k + kDc[d];
        if (nr < 0 || nr >= rows || nk < 0 || nk >= cols) continue;
        const std::int32_t nc = nr * cols + nk;
        const std::uint8_t st = vehicle_state_[nc];
        if (st == kVehicleCandidate) {
          vehicle_state_[nc] = kVehicleGrouped;
          vehicle_group_.push_back(nc);
        } else if (st == kVehicleNone) {
          if (cell_class_[nc] == SegmentClass::kShort) {
            vehicle_state_[nc] = kVehicleShort;
            vehicle_group_.push_back(nc);
          } else if (cell_class_[nc] == SegmentClass::kTall) {
            touches_higher = true;
          }
        }
      }
    }
    if (touches_higher) continue;
    float len, wid;
    cellGroupExtent(grid_, vehicle_group_, &len, &wid);
    if (!(len <= max_len && wid <= max_wid)) continue;
    // Inside the Hough window the field-of-view test is left to step 5 for groups as long as a
    // van; a pole, a post or a trunk seen to the upper edge keeps it.
    const bool near_exempt = hough_window > 0.0f && len >= min_len;
    // Its height must be known: where most tops are at the upper edge of the field of view
    // (classifyCells' wall-support test) the structure may be any height, e.g. a facade beyond
    // the Hough window seen up to ~2.5 m.
    std::size_t tall = 0, cut = 0;
    for (const std::int32_t c : vehicle_group_) {
      if (vehicle_state_[c] != kVehicleGrouped) continue;
      ++tall;
      float x, y;
      grid_.cellCenter(c, &x, &y);
      if (near_exempt && std::fabs(x) <= hough_window && std::fabs(y) <= hough_window) continue;
      const float dist = std::max(0.0f, std::sqrt(x * x + y * y) - half_diag);
      cut += stats[grid_.slotOf(c)].z_max - sensor_h >= dist * tan_top ? 1 : 0;
    }
    if (2 * cut > tall) continue;
    for (const std::int32_t c : vehicle_group_) {
      if (vehicle_state_[c] != kVehicleGrouped) continue;
      const std::int32_t s = grid_.slotOf(c);
      cell_class_[c] = SegmentClass::kShort;
      slot_label_[static_cast<std::size_t>(s) + 1].label =
          static_cast<std::uint32_t>(SegmentClass::kShort);
      // As any short cell: a top at the upper edge of the field of view supports walls.
      float x, y;
      grid_.cellCenter(c, &x, &y);
      const float dist = std::max(0.0f, std::sqrt(x * x + y * y) - half_diag);
      wall_support_[c] = stats[s].z_max - sensor_h >= dist * tan_top ? 1 : 0;
    }
  }
}

// Step 5b. The candidate cells' points carry kPendingLabel after the per-point pass (unless
// step 4b made their cell short); their heights above the split are binned per slot (and the
// xy box of the points above tall_min_height_m kept), each slot's cut (or thin upright) is
// found on its bins, and the points are labelled short below the cut or beside the upright,
// tall otherwise. Only the pending points are visited (found 16 label bytes at a time), twice.
void GridSegmenter::resolveOverhangs(const CloudXYZIRT& cloud, std::uint8_t* labels,
                                     std::uint32_t* counts) {
  const std::size_t n = cloud.size();
  const std::size_t slots = slot_label_.size();
  overhang_mask_.resize(slots);
  overhang_upper_mask_.resize(slots);
  overhang_cut_.resize(slots);
  overhang_box_.resize(4 * slots);
  overhang_upright_.resize(slots);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  bool any = false;
  for (const std::int32_t slot : overhang_slots_) {
    const std::size_t s = static_cast<std::size_t>(slot) + 1;
    if (slot_label_[s].label != kPendingLabel) continue;
    overhang_mask_[s] = 0;
    overhang_upper_mask_[s] = 0;
    float* box = &overhang_box_[4 * s];
    box[0] = box[1] = kInf;
    box[2] = box[3] = -kInf;
    any = true;
  }
  if (!any) return;
  const std::int32_t* pc = grid_.pointSlots().data();
  const float* pz = grid_.pointHeights().data();
  const SlotLabel* table = slot_label_.data();
  const PointXYZIRT* pts = cloud.points.data();
  std::uint64_t* mask = overhang_mask_.data();
  std::uint64_t* upper_mask = overhang_upper_mask_.data();
  float* boxes = overhang_box_.data();
  const float tall_h = static_cast<float>(params_.tall_min_height_m);
  const float tol = static_cast<float>(params_.ground_tolerance_m);
  const float upper = tall_h - tol;  // above the split: more than tall_h above the ground
  const bool thin = params_.thin_max_width_m > 0.0;
  forEachPending(labels, n, [&](std::size_t i) {
    const std::int32_t s = pc[i];
    const float d = pz[i] - table[s].split_z;  // >= 0: the point is not ground
    const int bin = std::min(63, static_cast<int>(d * kOverhangBinsPerM));
    mask[s] |= std::uint64_t{1} << bin;
    if (thin && d > upper) {
      upper_mask[s] |= std::uint64_t{1} << bin;
      float* box = boxes + 4 * s;
      box[0] = std::min(box[0], pts[i].x);
      box[1] = std::min(box[1], pts[i].y);
      box[2] = std::max(box[2], pts[i].x);
      box[3] = std::max(box[3], pts[i].y);
    }
  });
  const int gap_bins =
      static_cast<int>(std::ceil(params_.overhang_min_gap_m * kOverhangBinsPerM - 1e-6));
  const float thin_w = static_cast<float>(params_.thin_max_width_m);
  const float min_h = static_cast<float>(params_.overhang_min_height_m);
  constexpr float kThinMargin = 0.1f;  // [m] see thin_max_width_m
  for (const std::int32_t slot : overhang_slots_) {
    const std::size_t s = static_cast<std::size_t>(slot) + 1;
    if (slot_label_[s].label != kPendingLabel) continue;
    const std::uint64_t m = mask[s];
    float cut = -kInf;  // none: no point lies below it
    overhang_cut_[s] = -kInf;
    overhang_upright_[s] = 0;
    if (m == 0) continue;  // no point above the split (a tolerance above tall_min_height_m)
    int top = __builtin_ctzll(m);
    while (gap_bins > 0 && top < 63) {
      const std::uint64_t rest = m >> (top + 1);
      if (rest == 0) break;
      const int next = top + 1 + __builtin_ctzll(rest);
      if (next - top - 1 >= gap_bins) {
        const float c = static_cast<float>(top + 1) / kOverhangBinsPerM;
        if (tol + c <= tall_h && tol + c >= min_h &&
            __builtin_popcountll(m >> next) >= kMinUpperBins) {
          cut = c;
        }
        break;
      }
      top = next;
    }
    overhang_cut_[s] = cut;
    // A thin upright: the points beside its box, widened by the margin, are short.
    float* box = boxes + 4 * s;
    const bool upright = thin && cut == -kInf &&
                         __builtin_popcountll(upper_mask[s]) >= kMinUpperBins &&
                         box[2] - box[0] <= thin_w && box[3] - box[1] <= thin_w;
    overhang_upright_[s] = upright ? 1 : 0;
    box[0] -= kThinMargin;
    box[1] -= kThinMargin;
    box[2] += kThinMargin;
    box[3] += kThinMargin;
  }
  const std::uint8_t* upright = overhang_upright_.data();
  const float* cut = overhang_cut_.data();
  constexpr std::uint8_t kShortLabel = static_cast<std::uint8_t>(SegmentClass::kShort);
  constexpr std::uint8_t kTallLabel = static_cast<std::uint8_t>(SegmentClass::kTall);
  forEachPending(labels, n, [&](std::size_t i) {
    const std::int32_t s = pc[i];
    const float d = pz[i] - table[s].split_z;
    const float* box = boxes + 4 * s;
    const bool beside =
        upright[s] && d <= upper &&
        !(pts[i].x >= box[0] && pts[i].x <= box[2] && pts[i].y >= box[1] && pts[i].y <= box[3]);
    const std::uint8_t label = d < cut[s] || beside ? kShortLabel : kTallLabel;
    labels[i] = label;
    ++counts[label];
  });
}

void extractForeground(const CloudXYZIRT& cloud, const std::vector<SegmentClass>& labels,
                       LabeledCloud* foreground) {
  foreground->header = cloud.header;
  foreground->sensor_origin_ = cloud.sensor_origin_;
  foreground->sensor_orientation_ = cloud.sensor_orientation_;
  const std::size_t n = std::min(cloud.size(), labels.size());
  // Size the output once (a count over the label bytes is cheap and vectorised), then write
  // the points in place: PCL's push_back also rewrites width/height per point.
  std::size_t shorts = 0;
  for (std::size_t i = 0; i < n; ++i) shorts += labels[i] == SegmentClass::kShort;
  foreground->points.resize(shorts);
  LabeledPoint* out = foreground->points.data();
  std::size_t m = 0;
  auto take = [&](std::size_t i) {
    const PointXYZIRT& p = cloud[i];
    if (!isFinitePoint(p)) return;
    LabeledPoint& q = out[m++];
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    q.data[3] = 1.0f;
    q.intensity = p.intensity;
    q.label = static_cast<std::uint32_t>(SegmentClass::kShort);
    q.index = static_cast<std::uint32_t>(i);
  };
  // The short points are a few percent of a sweep, in runs: 16 labels are compared at a time
  // and only the set bits visited (same points in the same order as the plain loop, with one
  // branch per 16 labels instead of one per label).
  const std::uint8_t* lab = reinterpret_cast<const std::uint8_t*>(labels.data());
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128i short16 = _mm_set1_epi8(static_cast<char>(SegmentClass::kShort));
  for (; i + 16 <= n; i += 16) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(lab + i));
    for (unsigned bits = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(bytes, short16)));
         bits != 0; bits &= bits - 1) {
      take(i + static_cast<std::size_t>(__builtin_ctz(bits)));
    }
  }
#endif
  for (; i < n; ++i) {
    if (lab[i] == static_cast<std::uint8_t>(SegmentClass::kShort)) take(i);
  }
  foreground->points.resize(m);  // non-finite short points (not from segment()) dropped
  foreground->width = static_cast<std::uint32_t>(m);
  foreground->height = 1;
  foreground->is_dense = true;
}

void buildLabeledCloud(const CloudXYZIRT& cloud, const std::vector<SegmentClass>& labels,
                       LabeledCloud* labeled) {
  labeled->clear();
  labeled->header = cloud.header;
  labeled->sensor_origin_ = cloud.sensor_origin_;
  labeled->sensor_orientation_ = cloud.sensor_orientation_;
  const std::size_t n = cloud.size();
  labeled->resize(n);
  bool dense = true;
  for (std::size_t i = 0; i < n; ++i) {
    LabeledPoint& q = (*labeled)[i];
    q.x = cloud[i].x;
    q.y = cloud[i].y;
    q.z = cloud[i].z;
    q.intensity = cloud[i].intensity;
    q.label = static_cast<std::uint32_t>(i < labels.size() ? labels[i] : SegmentClass::kUnknown);
    q.index = static_cast<std::uint32_t>(i);
    dense = dense && isFinitePoint(cloud[i]);
  }
  if (cloud.height > 1 && cloud.width * cloud.height == n) {
    labeled->width = cloud.width;
    labeled->height = cloud.height;
  } else {
    labeled->width = static_cast<std::uint32_t>(n);
    labeled->height = 1;
  }
  labeled->is_dense = dense;
}

}  // namespace core
}  // namespace urban_detection
