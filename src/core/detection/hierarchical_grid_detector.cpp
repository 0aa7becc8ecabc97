#include "urban_detection/core/detection/hierarchical_grid_detector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "urban_detection/core/common/grid_cells_sse2.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

namespace urban_detection {
namespace core {
namespace {

// Forward half of the 8-neighbourhood: each neighbouring pair is visited once.
constexpr int kForward[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};

// The grid -> slot maps are the only arrays that scale with the grid area; this bounds them
// to 64 Mi sub-cells (256 MB) so a typo in the extent cannot exhaust memory.
constexpr double kMaxDenseCells = 64.0 * 1024 * 1024;

// The psi test of two sub-cells through their keys (header of weighDensities()).
inline bool withinPsi(float za, float zb, float psi_max) {
  return std::fabs(za - zb) <= psi_max;
}

// Union-find root with path halving; inline, it runs for every link tried.
inline std::int32_t findRoot(std::int32_t* parent, std::int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Every union of this file links the larger root under the smaller and path halving only
// moves a parent to its own parent, so a parent is never larger than its child: one ascending
// pass makes every entry its root, where a findRoot() per entry would loop.
inline void flattenRoots(std::int32_t* parent, std::int32_t n) {
  for (std::int32_t s = 0; s < n; ++s) parent[s] = parent[parent[s]];
}

// The largest float <= t. For every float f (NaN included), f <= t compared in double holds
// exactly when f <= floatAtMost(t) in float: the psi tests run in float without a conversion.
float floatAtMost(double t) {
  float f = static_cast<float>(t);
  if (static_cast<double>(f) > t) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

const HierarchicalGridDetectorParams& checked(const HierarchicalGridDetectorParams& p) {
  const std::string err = validate(p);
  if (!err.empty()) throw std::invalid_argument("HierarchicalGridDetector: " + err);
  return p;
}

}  // namespace

std::string validate(const HierarchicalGridDetectorParams& p) {
  std::string error = checkFieldRanges(p);
  if (error.empty() && std::pow(2.0 * std::ceil(p.grid_half_extent_m / p.coarse_cell_m) * p.xi, 2) >
                           kMaxDenseCells) {
    error = "grid_half_extent_m / (coarse_cell_m / xi) gives more than " +
            std::to_string(kMaxDenseCells) +
            " sub-cells; enlarge coarse_cell_m or reduce grid_half_extent_m";
  }
  if (error.empty() && !(error = validate(p.weight)).empty()) error = "weight: " + error;
  if (error.empty() && !(error = validate(p.far_merge)).empty()) error = "far_merge: " + error;
  if (error.empty() && !(error = validate(p.group_split)).empty()) {
    error = "group_split: " + error;
  }
  return error;
}

HierarchicalGridDetector::HierarchicalGridDetector(const HierarchicalGridDetectorParams& params)
    : params_(checked(params)),
      weight_(params.weight, (params.grid_half_extent_m + params.coarse_cell_m) * M_SQRT2 + 1.0),
      far_merger_(params.far_merge),
      group_splitter_(params.group_split),
      dense_cell_m_(params.coarse_cell_m / params.xi),
      psi_max_f_(floatAtMost(params.psi_max_m)) {
  // An even number of super-cells with the sensor on a cell corner: cell borders lie on
  // multiples of W_S (and of W_S / xi), independent of the extent.
  const int half = static_cast<int>(std::ceil(params_.grid_half_extent_m / params_.coarse_cell_m));
  nc_ = 2 * half;
  nd_ = nc_ * params_.xi;
  origin_m_ = -half * params_.coarse_cell_m;
  coarse_.of.resize(nd_);
  for (int i = 0; i < nd_; ++i) coarse_.of[i] = i / params_.xi;
  coarse_.slot.assign(static_cast<std::size_t>(nc_) * nc_, -1);
  // The bridge tables give the probe margin, which sizes the padded sub-cell maps.
  buildBridgeTables();
  const std::size_t padded = static_cast<std::size_t>(stride_) * stride_;
  dense_.slot.assign(padded, -1);
  dense_.bits.assign((padded + 63) / 64, 0);
}

inline int HierarchicalGridDetector::directionBin(float x, float y) {
  // Pseudo-angle in [0, 4), monotonic in the true angle, without a trigonometric call.
  const float t = x / (std::fabs(x) + std::fabs(y));
  const float a = y >= 0.0f ? 1.0f - t : 3.0f + t;
  return std::min(kDirectionBins - 1, static_cast<int>(a * (kDirectionBins / 4)));
}

void HierarchicalGridDetector::buildBridgeTables() {
  // Per table (near, far, farthest), per direction bin (its centre direction u): the offsets
  // o beyond the 8-neighbourhood (which links anyway) that step 3 bridges: for the near and
  // far tables, 2 <= max(|o.x|, |o.y|) <= B + 1, o.u > 0 and |o x u| <= 1 sub-cell (ahead on
  // the line of sight, beside it by at most one sub-cell); the farthest table adds the ring
  // max(|o.x|, |o.y|) = 2 in all directions, half of it (the other half is the same pairs
  // seen from their other end). The roof table (kRoofTable, step 3b) is radial like the near
  // one, with B = roof_bridge_subcells.
  bridge_offsets_.clear();
  bridge_begin_.clear();
  const int reach[4] = {params_.radial_bridge_subcells + 1, params_.far_radial_bridge_subcells + 1,
                        params_.far_radial_bridge_subcells + 1, params_.roof_bridge_subcells + 1};
  for (int table = 0; table < 4; ++table) {
    for (int bin = 0; bin < kDirectionBins; ++bin) {
      bridge_begin_.push_back(static_cast<std::int32_t>(bridge_offsets_.size()));
      const double a = (bin + 0.5) * 4.0 / kDirectionBins;  // inverse of directionBin()
      const double t = a < 2.0 ? 1.0 - a : a - 3.0;
      double ux = t, uy = (a < 2.0 ? 1.0 : -1.0) * (1.0 - std::fabs(t));
      const double norm = std::hypot(ux, uy);
      ux /= norm;
      uy /= norm;
      const int r = std::max(reach[table], table == 2 ? 2 : 0);
      for (int oy = -r; oy <= r; ++oy) {
        for (int ox = -r; ox <= r; ++ox) {
          const int cheb = std::max(std::abs(ox), std::abs(oy));
          if (cheb < 2) continue;
          const double along = ox * ux + oy * uy, across = ox * uy - oy * ux;
          const bool radial =
              cheb <= reach[table] && along > 1e-9 && std::fabs(across) <= 1.0 + 1e-9;
          const bool ring = table == 2 && cheb == 2 && (oy > 0 || (oy == 0 && ox > 0));
          if (radial || ring) bridge_offsets_.push_back(CellXY{ox, oy});
        }
      }
    }
    bridge_begin_.push_back(static_cast<std::int32_t>(bridge_offsets_.size()));
  }
  // The sub-cell maps are padded by the largest probe offset on every side (sub-cells that
  // never hold a point), so every probe of steps 3, 3b and 4 is a flat offset without bounds
  // checks, at the grid's border as inside.
  probe_margin_ = 1;  // the 8-neighbourhood
  for (const CellXY& o : bridge_offsets_) {
    probe_margin_ = std::max({probe_margin_, std::abs(o.x), std::abs(o.y)});
  }
  stride_ = nd_ + 2 * probe_margin_;
  bridge_flat_.clear();
  for (const CellXY& o : bridge_offsets_) bridge_flat_.push_back(o.y * stride_ + o.x);
  // Probe rows of step 3: per table and direction bin, the four
  // forward neighbours, then that bin's bridge offsets, padded with offset 0 to the table's
  // longest row (so every row of a table has the same length and the probe loop the same
  // trip count), and a mask of the row's real entries.
  probe_flat_.clear();
  probe_mask_.clear();
  for (int table = 0; table < 3; ++table) {
    int longest = 0;
    for (int bin = 0; bin < kDirectionBins; ++bin) {
      const int b = table * (kDirectionBins + 1) + bin;
      longest = std::max(longest, bridge_begin_[b + 1] - bridge_begin_[b]);
    }
    probe_row_len_[table] = 4 + longest;
    probe_row_begin_[table] = static_cast<std::int32_t>(probe_flat_.size());
    // validate() bounds the reach to 9 sub-cells, which keeps every row well within 64 entries.
    if (4 + longest > 64) throw std::logic_error("HierarchicalGridDetector: probe row > 64");
    for (int bin = 0; bin < kDirectionBins; ++bin) {
      const int b = table * (kDirectionBins + 1) + bin;
      for (const auto& o : kForward) probe_flat_.push_back(o[1] * stride_ + o[0]);
      for (int k = bridge_begin_[b]; k < bridge_begin_[b + 1]; ++k) {
        probe_flat_.push_back(bridge_flat_[k]);
      }
      const int len = 4 + bridge_begin_[b + 1] - bridge_begin_[b];
      probe_flat_.resize(probe_flat_.size() + (4 + longest - len), 0);
      probe_mask_.push_back(len >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << len) - 1);
    }
  }
}

inline bool HierarchicalGridDetector::linked(std::int32_t a, std::int32_t b) const {
  return a == b || std::fabs(coarse_.zmax[a] - coarse_.zmax[b]) <= psi_max_f_;
}

void HierarchicalGridDetector::resetGrid() {
  for (const std::int32_t cell : dense_.cell) {
    dense_.slot[cell] = -1;
    dense_.bits[cell >> 6] = 0;  // only the last frame's sub-cells have bits set
  }
  for (const std::int32_t cell : coarse_.cell) coarse_.slot[cell] = -1;
  dense_.cell.clear();
  coarse_.cell.clear();
}

void HierarchicalGridDetector::roofBridges() {
  // Step 3b (header). A candidate ring must be a whole component of step 3 (a lone ring, or
  // rings on one flat surface): the z range of each component is taken before any roof bridge
  // is made, so a ring joined to a car does not make the car a candidate, and a car or a
  // pedestrian behind another car (not flat) is never one. Union-find roots are the smallest
  // slot of their component, so one ascending pass meets each root before its members.
  const std::int32_t nds = static_cast<std::int32_t>(dense_.cell.size());
  dense_.root_zmin.resize(nds);
  dense_.root_zmax.resize(nds);
  flattenRoots(dense_.parent.data(), nds);
  // Without a branch per sub-cell (whether it is dense and a root is data-dependent): a root
  // starts its range from its own, every sub-cell folds into its root's. A sub-cell that is
  // not dense is never linked, so it is its own root and only writes its own entry, which no
  // dense sub-cell reads.
  const float inf = std::numeric_limits<float>::infinity();
  for (std::int32_t s = 0; s < nds; ++s) {
    const std::int32_t root = dense_.parent[s];
    const bool own = root == s;
    dense_.root_zmin[root] = std::min(own ? inf : dense_.root_zmin[root], dense_.zmin[s]);
    dense_.root_zmax[root] = std::max(own ? -inf : dense_.root_zmax[root], dense_.zmax[s]);
  }
  const float step = static_cast<float>(params_.roof_max_step_m);
  const float range2 =
      static_cast<float>(params_.roof_bridge_range_m * params_.roof_bridge_range_m);
  const float dtheta = static_cast<float>(params_.ring_spacing_deg * M_PI / 180.0);
  const float origin = static_cast<float>(origin_m_);
  const float dcell = static_cast<float>(dense_cell_m_);
  // The flat dense sub-cells of flat components, listed without a branch per sub-cell.
  dense_.flat.resize(nds);
  std::int32_t nflat = 0;
  for (std::int32_t s = 0; s < nds; ++s) {
    const std::int32_t root = dense_.parent[s];
    dense_.flat[nflat] = s;
    nflat += (dense_.occupied[s] != 0) & (dense_.zmax[s] - dense_.zmin[s] <= step) &
             (dense_.root_zmax[root] - dense_.root_zmin[root] <= step);
  }
  dense_.flat.resize(nflat);
  // The rings b are few: from each, look back towards the sensor along its line of sight for
  // the sub-cells a it may join (the offsets of b's direction bin, negated).
  for (const std::int32_t b : dense_.flat) {
    const int ix = dense_.xy[b].x, iy = dense_.xy[b].y;
    const float cx = (ix + 0.5f) * dcell + origin, cy = (iy + 0.5f) * dcell + origin;
    const float db2 = cx * cx + cy * cy;
    if (db2 < dcell * dcell) continue;
    const float zb = dense_.zmax[b];
    const std::int32_t cb = dense_.coarse[b];
    if (coarse_.zmax[cb] - zb > step) continue;
    const float h = -zb;  // the sensor is at z = 0
    const float inv_d = 1.0f / std::sqrt(db2);
    const std::int32_t* begin =
        &bridge_begin_[kRoofTable * (kDirectionBins + 1) + directionBin(cx, cy)];
    const std::int32_t cell = dense_.cell[b];
    for (std::int32_t k = begin[0]; k < begin[1]; ++k) {
      const int ox = bridge_offsets_[k].x, oy = bridge_offsets_[k].y;
      const std::int32_t a_cell = cell - bridge_flat_[k];
      // Dense sub-cells only (the bit map of detect()), then their slot.
      if (!((dense_.bits[a_cell >> 6] >> (a_cell & 63)) & 1u)) continue;
      const std::int32_t a = dense_.slot[a_cell];
      const std::int32_t ca = dense_.coarse[a];
      if (std::fabs(zb - coarse_.zmax[ca]) > step || !linked(ca, cb)) continue;
      // Two rings land d^2 * dtheta / h apart on a horizontal surface h below the sensor at
      // distance d (small angles).
      const float ax = cx - ox * dcell, ay = cy - oy * dcell;
      const float da2 = ax * ax + ay * ay;
      const float along = (ox * cx + oy * cy) * inv_d * dcell;
      if (da2 > range2 || (h > 0.0f && along * h > dtheta * da2 + dcell * h)) continue;
      const std::int32_t ra = findRoot(dense_.parent.data(), a),
                         rb = findRoot(dense_.parent.data(), b);
      if (ra == rb) continue;
      dense_.parent[std::max(ra, rb)] = std::min(ra, rb);
      ++stats_.roof_bridges;
    }
  }
}

void HierarchicalGridDetector::linkCoarse() {
  // As at the dense level: the root of the super-cell whose links are made is kept, the psi
  // tests of its forward neighbours are a bit mask (an empty cell, slot -1, has a NaN Z_max),
  // then the links in the same order.
  const std::int32_t ncs = static_cast<std::int32_t>(coarse_.cell.size());
  coarse_.parent.resize(ncs);
  for (std::int32_t s = 0; s < ncs; ++s) coarse_.parent[s] = s;
  coarse_.key.resize(ncs + 1);
  coarse_.key[0] = std::numeric_limits<float>::quiet_NaN();
  std::copy(coarse_.zmax.begin(), coarse_.zmax.end(), coarse_.key.begin() + 1);
  const float* ckey = coarse_.key.data() + 1;
  std::int32_t* cparent = coarse_.parent.data();
  const float psi_max = psi_max_f_;
  std::int32_t croot = 0;
  auto uniteCoarse = [cparent, &croot](std::int32_t r) {
    r = findRoot(cparent, r);
    if (r == croot) return;
    if (r < croot) {
      cparent[croot] = r;
      croot = r;
    } else {
      cparent[r] = croot;
    }
  };
  std::int32_t forward_flat[4];
  for (int f = 0; f < 4; ++f) forward_flat[f] = kForward[f][1] * nc_ + kForward[f][0];
  for (std::int32_t s = 0; s < ncs; ++s) {
    const int cy = coarse_.cell[s] / nc_, cx = coarse_.cell[s] - cy * nc_;
    const float zs = ckey[s];
    croot = findRoot(cparent, s);
    if (cx >= 1 && cx < nc_ - 1 && cy < nc_ - 1) {
      const std::int32_t* here = coarse_.slot.data() + coarse_.cell[s];
      unsigned linked_forward = 0;
      for (int f = 0; f < 4; ++f) {
        linked_forward |=
            static_cast<unsigned>(std::fabs(zs - ckey[here[forward_flat[f]]]) <= psi_max) << f;
      }
      for (; linked_forward; linked_forward &= linked_forward - 1) {
        uniteCoarse(here[forward_flat[__builtin_ctz(linked_forward)]]);
      }
      continue;
    }
    for (const auto& o : kForward) {
      const int x = cx + o[0], y = cy + o[1];
      if (x < 0 || x >= nc_ || y >= nc_) continue;
      const std::int32_t r = coarse_.slot[y * nc_ + x];
      if (r >= 0 && linked(s, r)) uniteCoarse(r);
    }
  }
  for (std::int32_t s = 0; s < ncs; ++s) stats_.coarse_blobs += coarse_.parent[s] == s;
}

// Binning: every point goes to its sub-cell and, through it (buildCells()), to its super-cell.
std::int32_t HierarchicalGridDetector::binPoints(const LabeledCloud& foreground) {
  const std::size_t n = foreground.points.size();
  point_slot_.resize(n);
  const float origin = static_cast<float>(origin_m_);
  const float inv_dense = static_cast<float>(1.0 / dense_cell_m_);
  const float nd_f = static_cast<float>(nd_);
  const float max_abs_z = static_cast<float>(params_.max_abs_z_m);
  const LabeledPoint* points = foreground.points.data();
  // Two passes. The first computes each point's sub-cell (flat index of the padded map, or -1
  // outside the grid or the z range) into point_slot_ and prefetches its slot-map entry: the
  // map is 2.6 MB and the entries come from the outer caches, many at a time instead of one
  // dependent load per point. The second turns the sub-cells into slots in point order.
  std::int32_t* const point_cell = point_slot_.data();
  const std::int32_t* const slot_map_base = dense_.slot.data();
  // Sub-cell (0, 0) in the padded map.
  const std::int32_t pad_offset = probe_margin_ * stride_ + probe_margin_;
  std::size_t i = 0;
#if defined(__SSE2__)
  // Four points at a time: the same float operations as the scalar loop below (subtract,
  // multiply, ordered comparisons, truncation), so the same cells.
  {
    const GridCellsSse2 grid4(origin, inv_dense, nd_f, max_abs_z, stride_, pad_offset);
    for (; i + 4 <= n; i += 4) {
      __m128 x = _mm_loadu_ps(&points[i].x), y = _mm_loadu_ps(&points[i + 1].x);
      __m128 z = _mm_loadu_ps(&points[i + 2].x), w = _mm_loadu_ps(&points[i + 3].x);
      _MM_TRANSPOSE4_PS(x, y, z, w);
      // iy * stride_ + ix + pad_offset, rejected lanes -1.
      __m128i valid;
      const __m128i cell = grid4.cells(x, y, z, &valid);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(point_cell + i), cell);
      // (Entry -1 lies before the map; a prefetch never faults.)
      for (int j = 0; j < 4; ++j) __builtin_prefetch(slot_map_base + point_cell[i + j]);
    }
  }
#endif
  for (; i < n; ++i) {
    const LabeledPoint& p = points[i];
    const float fx = (p.x - origin) * inv_dense;
    const float fy = (p.y - origin) * inv_dense;
    if (fx >= 0.0f && fx < nd_f && fy >= 0.0f && fy < nd_f && std::fabs(p.z) <= max_abs_z) {
      const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);  // fx, fy < nd_ exactly
      point_cell[i] = iy * stride_ + ix + pad_offset;
    } else {
      point_cell[i] = -1;
    }
  }
  // Second pass, in point order: the slot of each point's sub-cell, a new one opened where
  // the sub-cell has none, and the slot's count and z range. A new sub-cell is not a branch
  // (about one point in seven opens one, unpredictably): every point writes the entry of the
  // next free slot and advances the free slot only when it opened it, so an existing slot's
  // point leaves a stale entry there that the next opening overwrites. Inside implies finite
  // (comparisons with NaN and inf fail), so the finiteness tests only run for the rejected
  // points.
  if (dense_.acc.size() < n + 1) dense_.acc.resize(n + 1);
  DenseAcc* const acc = dense_.acc.data();
  std::int32_t* const slot_map_w = dense_.slot.data();
  std::int32_t next_slot = 0;
  for (i = 0; i < n; ++i) {
    const std::int32_t cell = point_cell[i];
    const LabeledPoint& p = points[i];
    if (cell < 0) {
      if (!isFinitePoint(p)) {
        ++stats_.invalid_points;
      } else {
        ++stats_.outside_points;
      }
      continue;
    }
    const float z = p.z;
    const std::int32_t old_slot = slot_map_w[cell];
    const bool fresh = old_slot < 0;
    const std::int32_t slot = fresh ? next_slot : old_slot;
    next_slot += fresh;
    slot_map_w[cell] = slot;
    const DenseAcc e = acc[slot];  // stale when fresh: every field is replaced then
    DenseAcc u;
    u.zmax = fresh ? z : std::max(e.zmax, z);
    u.zmin = fresh ? z : std::min(e.zmin, z);
    u.count = (fresh ? 0u : e.count) + 1u;
    u.cell = cell;
    acc[slot] = u;
    point_cell[i] = slot;
  }
  return next_slot;
}

void HierarchicalGridDetector::buildCells(std::int32_t nds) {
  const DenseAcc* const acc = dense_.acc.data();
  // Per sub-cell, in slot order (the order of their first points): column and row, super-cell
  // (opened in the order of their first sub-cells), heights gathered to it. The column and row
  // come back from the flat index: (cell + 0.5) / stride_ in double is at least 0.5 / stride_ from
  // the next integer and exact to far better than that, so the truncation is the integer division.
  const double inv_stride = 1.0 / stride_;
  dense_.cell.resize(nds);
  dense_.xy.resize(nds);
  dense_.count.resize(nds);
  dense_.zmax.resize(nds);
  dense_.zmin.resize(nds);
  dense_.coarse.resize(nds);
  // A new super-cell is not a branch either (about one sub-cell in three opens one): every
  // sub-cell writes the next free super-cell's entries, which only advances when it opened it.
  coarse_.cell.resize(nds);
  coarse_.zmax.resize(nds);
  std::int32_t next_coarse = 0;
  for (std::int32_t s = 0; s < nds; ++s) {
    const DenseAcc& e = acc[s];
    const std::int32_t cell = e.cell;
    const int row = static_cast<int>((cell + 0.5) * inv_stride);
    const int ix = cell - row * stride_ - probe_margin_, iy = row - probe_margin_;
    dense_.cell[s] = cell;
    dense_.xy[s] = CellXY{ix, iy};
    dense_.count[s] = e.count;
    dense_.zmax[s] = e.zmax;
    dense_.zmin[s] = e.zmin;
    const int cx = coarse_.of[ix], cy = coarse_.of[iy];
    const std::int32_t ccell = cy * nc_ + cx;
    const std::int32_t old_cslot = coarse_.slot[ccell];
    const bool fresh = old_cslot < 0;
    const std::int32_t cslot = fresh ? next_coarse : old_cslot;
    next_coarse += fresh;
    coarse_.slot[ccell] = cslot;
    coarse_.cell[cslot] = ccell;
    const float zmax = coarse_.zmax[cslot];  // stale when fresh
    coarse_.zmax[cslot] = fresh ? e.zmax : std::max(zmax, e.zmax);
    dense_.coarse[s] = cslot;
  }
  coarse_.cell.resize(next_coarse);
  coarse_.zmax.resize(next_coarse);
  stats_.dense_cells = nds;
  stats_.coarse_cells = next_coarse;
}

// Dense level: weighted densities; dense sub-cells are the nodes of the components.
void HierarchicalGridDetector::weighDensities() {
  const std::int32_t nds = static_cast<std::int32_t>(dense_.cell.size());
  const float origin = static_cast<float>(origin_m_);
  dense_.occupied.assign(nds, 0);
  dense_.rho.resize(nds + 1);  // [0]: slot -1 (no sub-cell), see the ring of step 4
  dense_.rho[0] = 0.0f;
  float* const rho = dense_.rho.data() + 1;
  dense_.parent.resize(nds);
  const float thr = static_cast<float>(params_.dense_min_weighted_points);
  const float dcell = static_cast<float>(dense_cell_m_);
  const float bridge_range2 = static_cast<float>(params_.bridge_range_m * params_.bridge_range_m);
  const float gap_range2 =
      static_cast<float>(params_.gap_bridge_range_m * params_.gap_bridge_range_m);
  // Step 3's probe row of each sub-cell (its bridge table by sensor distance, its direction
  // bin) is chosen here, where the sub-cell's centre and distance are computed anyway: the
  // links below then start from a load instead of a division and a chain of compares.
  dense_.probe_of.resize(nds);
  for (std::int32_t s = 0; s < nds; ++s) {
    const int ix = dense_.xy[s].x, iy = dense_.xy[s].y;
    const float x = (ix + 0.5f) * dcell + origin, y = (iy + 0.5f) * dcell + origin;
    const float d2 = x * x + y * y;
    rho[s] = static_cast<float>(dense_.count[s]) * weight_(std::sqrt(d2));
    dense_.parent[s] = s;
    const int table = d2 > gap_range2 ? 2 : d2 > bridge_range2 ? 1 : 0;
    const int bin = directionBin(x, y);
    const int len = probe_row_len_[table];
    dense_.probe_of[s] = ProbeRow{
        probe_row_begin_[table] + bin * len, len,
        d2 < dcell * dcell ? std::uint64_t{0xf} : probe_mask_[table * kDirectionBins + bin]};
    if (rho[s] >= thr) {
      dense_.occupied[s] = 1;
      const std::int32_t cell = dense_.cell[s];
      dense_.bits[cell >> 6] |= std::uint64_t{1} << (cell & 63);
      ++stats_.dense_occupied;
    }
  }

  // The psi test of two sub-cells, with one load per candidate: key = Z_max of the sub-cell's
  // super-cell when the sub-cell is dense, NaN otherwise (every comparison with NaN fails).
  // |za - zb| <= psi_max is linked(): equal super-cells give 0 <= psi_max. Slot -1 (an empty
  // sub-cell) has a key too, NaN: a probe needs no test for it.
  dense_.key.resize(nds + 1);
  dense_.key[0] = std::numeric_limits<float>::quiet_NaN();
  for (std::int32_t s = 0; s < nds; ++s) {
    dense_.key[s + 1] = dense_.occupied[s] ? coarse_.zmax[dense_.coarse[s]]
                                           : std::numeric_limits<float>::quiet_NaN();
  }
}

// Step 3: connected components of the dense sub-cells (8-neighbourhood) whose super-cells are
// psi-linked, plus the radial bridges (header).
void HierarchicalGridDetector::linkDense() {
  const std::int32_t nds = static_cast<std::int32_t>(dense_.cell.size());
  const float psi_max = psi_max_f_;
  const float* key = dense_.key.data() + 1;
  const std::int32_t* slot_map = dense_.slot.data();
  // Dense sub-cells as one bit per grid cell (80 kB for the default grid, mostly cached, where
  // the slot map is 2.6 MB): most probes land on empty or near-empty sub-cells and end at the
  // bit; only the dense ones read the slot map and the key.
  const std::uint64_t* dense_bits = dense_.bits.data();
  auto denseBit = [dense_bits](std::int32_t cell) {
    return static_cast<unsigned>(dense_bits[cell >> 6] >> (cell & 63)) & 1u;
  };
  std::int32_t* parent = dense_.parent.data();
  // Root of the sub-cell whose links are being made: found once per sub-cell, not once per
  // link tried; a link can only replace it by a smaller root (roots stay the smallest slot).
  std::int32_t root = 0;
  auto unite = [parent, &root](std::int32_t r) {
    r = findRoot(parent, r);
    if (r == root) return false;
    if (r < root) {
      parent[root] = r;
      root = r;
    } else {
      parent[r] = root;
    }
    return true;
  };
  for (std::int32_t s = 0; s < nds; ++s) {
    if (!dense_.occupied[s]) continue;
    // One row of probes (the four forward neighbours, then the bridges of the sub-cell's table
    // and direction bin; only the forward ones for the sensor's own sub-cells), flat offsets
    // into the padded map: which of them are dense without branches, then the psi tests and
    // links of those in the row's order.
    const std::int32_t cell = dense_.cell[s];
    const std::int32_t* here = slot_map + cell;
    const float ks = key[s];
    root = findRoot(parent, s);
    const ProbeRow& probe = dense_.probe_of[s];
    const int len = probe.len;
    const std::int32_t* row = probe_flat_.data() + probe.begin;
    std::uint64_t dense_row = 0;
    for (int j = 0; j < len; ++j) {
      dense_row |= static_cast<std::uint64_t>(denseBit(cell + row[j])) << j;
    }
    for (dense_row &= probe.mask; dense_row; dense_row &= dense_row - 1) {
      const int j = __builtin_ctzll(dense_row);
      const std::int32_t r = here[row[j]];
      if (withinPsi(ks, key[r], psi_max) && unite(r) && j >= 4) ++stats_.bridges;
    }
  }
}

// Component index per sub-cell (near-empty ones borrow a dense neighbour's).
std::int32_t HierarchicalGridDetector::numberComponents() {
  const std::int32_t nds = static_cast<std::int32_t>(dense_.cell.size());
  const std::int32_t ncs = static_cast<std::int32_t>(coarse_.cell.size());
  const float psi_max = psi_max_f_;
  const float* rho = dense_.rho.data() + 1;
  const float* key = dense_.key.data() + 1;
  const std::int32_t* slot_map = dense_.slot.data();
  // Components are numbered in the order of first appearance of their sub-cells, which is the
  // order of the first point in the input, so ids do not depend on the grid layout.
  dense_.object.assign(nds, -1);
  comps_.root_object.assign(params_.dense_refinement ? nds : ncs, -1);
  std::int32_t ncomp = 0;
  if (params_.dense_refinement) {
    flattenRoots(dense_.parent.data(), nds);
  } else {
    flattenRoots(coarse_.parent.data(), ncs);
  }
  auto componentOf = [&](std::int32_t s) -> std::int32_t {
    const std::int32_t root =
        params_.dense_refinement ? dense_.parent[s] : coarse_.parent[dense_.coarse[s]];
    // A new component's number without a branch (about one sub-cell in ten starts one).
    const std::int32_t known = comps_.root_object[root];
    const bool fresh = known < 0;
    const std::int32_t c = fresh ? ncomp : known;
    comps_.root_object[root] = c;
    ncomp += fresh;
    return c;
  };
  // The 8-neighbourhood in the order of the original (dy, dx) loops: ties of rho keep the first.
  std::int32_t ring_flat[8];
  for (int dy = -1, m = 0; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx != 0 || dy != 0) ring_flat[m++] = dy * stride_ + dx;
    }
  }
  for (std::int32_t s = 0; s < nds; ++s) {
    if (!params_.dense_refinement || dense_.occupied[s]) {
      dense_.object[s] = componentOf(s);
      continue;
    }
    const float zs = coarse_.zmax[dense_.coarse[s]];
    const std::int32_t* here = slot_map + dense_.cell[s];
    // The first of the densest (rho >= 1 > -inf), by selects rather than branches.
    std::int32_t best = -1;
    float best_rho = -std::numeric_limits<float>::infinity();
    for (int m = 0; m < 8; ++m) {
      const std::int32_t r = here[ring_flat[m]];
      const float rho_r = rho[r];
      const bool take = withinPsi(zs, key[r], psi_max) & (rho_r > best_rho);
      best = take ? r : best;
      best_rho = take ? rho_r : best_rho;
    }
    if (best >= 0) dense_.object[s] = componentOf(best);
  }
  stats_.components = ncomp;
  return ncomp;
}

// Per component: size and extent (on the sub-cells it covers) for the filters.
std::size_t HierarchicalGridDetector::filterComponents(std::int32_t ncomp) {
  const std::int32_t nds = static_cast<std::int32_t>(dense_.cell.size());
  const float* rho = dense_.rho.data() + 1;
  comps_.count.assign(ncomp, 0);
  comps_.rho.assign(ncomp, 0.0f);
  comps_.box.resize(4 * static_cast<std::size_t>(ncomp));
  for (std::int32_t c = 0; c < ncomp; ++c) {
    comps_.box[4 * c] = comps_.box[4 * c + 1] = std::numeric_limits<std::int32_t>::max();
    comps_.box[4 * c + 2] = comps_.box[4 * c + 3] = -1;
  }
  for (std::int32_t s = 0; s < nds; ++s) {
    const std::int32_t c = dense_.object[s];
    if (c < 0) {
      stats_.noise_points += dense_.count[s];
      continue;
    }
    comps_.count[c] += dense_.count[s];
    comps_.rho[c] += rho[s];
    const std::int32_t ix = dense_.xy[s].x, iy = dense_.xy[s].y;
    std::int32_t* box = &comps_.box[4 * static_cast<std::size_t>(c)];
    box[0] = std::min(box[0], ix);
    box[1] = std::min(box[1], iy);
    box[2] = std::max(box[2], ix);
    box[3] = std::max(box[3], iy);
  }
  comps_.output.assign(ncomp, -1);
  std::size_t nobj = 0;
  const double max_extent_cells = params_.max_extent_m / dense_cell_m_;
  const float min_rho = static_cast<float>(params_.min_weighted_points);
  for (std::int32_t c = 0; c < ncomp; ++c) {
    const std::int32_t* box = &comps_.box[4 * static_cast<std::size_t>(c)];
    if (comps_.count[c] < static_cast<std::uint32_t>(params_.min_points) ||
        comps_.rho[c] < min_rho) {
      ++stats_.dropped_small;
    } else if (box[2] - box[0] + 1 > max_extent_cells || box[3] - box[1] + 1 > max_extent_cells) {
      ++stats_.dropped_large;
    } else {
      comps_.output[c] = static_cast<std::int32_t>(nobj++);
    }
  }
  return nobj;
}

// Output. One pass scatters every point to its object (a counting sort), writing its index and
// xy contiguously per object and accumulating the object's moments (pass 1 of the geometry) on
// the way, so the cloud is read once, sequentially. The objects vector is resized, not cleared,
// so the index vectors keep their capacity between frames.
void HierarchicalGridDetector::emitObjects(const LabeledCloud& foreground, std::int32_t ncomp,
                                           std::size_t nobj, std::vector<DetectedObject>* objects) {
  const std::size_t n = foreground.points.size();
  const std::int32_t nds = static_cast<std::int32_t>(dense_.cell.size());
  objects->resize(nobj);
  objects_.begin.assign(nobj + 1, 0);
  for (std::int32_t c = 0; c < ncomp; ++c) {
    if (comps_.output[c] >= 0) objects_.begin[comps_.output[c] + 1] = comps_.count[c];
  }
  objects_.index_out.resize(nobj);
  objects_.xy_out.resize(nobj);
  for (std::size_t k = 0; k < nobj; ++k) {
    objects_.begin[k + 1] += objects_.begin[k];
    // A reused object must not keep the class a later stage gave it in an earlier frame.
    (*objects)[k].category = ObjectCategory::kUnknown;
    (*objects)[k].class_confidence = 0.0f;
    (*objects)[k].indices.resize(objects_.begin[k + 1] - objects_.begin[k]);
    objects_.index_out[k] = (*objects)[k].indices.data();
  }
  objects_.xy.resize(objects_.begin[nobj]);
  for (std::size_t k = 0; k < nobj; ++k)
    objects_.xy_out[k] = objects_.xy.data() + objects_.begin[k];
  objects_.moments.assign(nobj, ObjectMoments());
  // Output object per sub-cell slot + 1 (slot -1, a point in no sub-cell, gives -1).
  comps_.slot_object.resize(nds + 1);
  comps_.slot_object[0] = -1;
  for (std::int32_t s = 0; s < nds; ++s) {
    comps_.slot_object[s + 1] = dense_.object[s] < 0 ? -1 : comps_.output[dense_.object[s]];
  }
  // In scan order consecutive points mostly belong to the same object: a run of them is
  // accumulated in registers (the same additions in the same order), not through the object's
  // moments and cursors in memory, whose store-to-load latency would chain point to point.
  const std::int32_t* object_of = comps_.slot_object.data() + 1;
  const std::int32_t* point_slot = point_slot_.data();
  for (std::size_t i = 0; i < n;) {
    const std::int32_t k = object_of[point_slot[i]];
    if (k < 0) {
      ++i;
      continue;
    }
    ObjectMoments m = objects_.moments[k];
    Eigen::Vector2f* xy = objects_.xy_out[k];
    std::uint32_t* index = objects_.index_out[k];
    do {
      const LabeledPoint& p = foreground.points[i];
      m.add(p.x, p.y, p.z);
      *xy++ = Eigen::Vector2f(p.x, p.y);
      *index++ = p.index;
    } while (++i < n && object_of[point_slot[i]] == k);
    objects_.moments[k] = m;
    objects_.xy_out[k] = xy;
    objects_.index_out[k] = index;
  }
  for (std::size_t k = 0; k < nobj; ++k) {
    DetectedObject& obj = (*objects)[k];
    obj.id = static_cast<std::uint32_t>(k + 1);
    geometry_.finish(objects_.moments[k], objects_.xy.data() + objects_.begin[k], &obj);
  }
}

void HierarchicalGridDetector::detect(const LabeledCloud& foreground,
                                      std::vector<DetectedObject>* objects) {
  stats_ = HierarchicalGridStats();
  stats_.input_points = foreground.points.size();
  resetGrid();
  buildCells(binPoints(foreground));
  // The coarse blobs are the objects without the dense refinement; with it, the coarse level
  // only contributes Z_max and the psi test (linked()) to the links of the dense level, whose
  // components are the objects, so the blobs are not built.
  if (!params_.dense_refinement) linkCoarse();
  weighDensities();
  if (params_.dense_refinement) {
    linkDense();
    if (params_.roof_bridge_subcells > 0) roofBridges();
  }
  const std::int32_t ncomp = numberComponents();
  const std::size_t nobj = filterComponents(ncomp);
  emitObjects(foreground, ncomp, nobj, objects);
  // Step 6 (far_object_merger.h).
  stats_.far_joins = far_merger_.apply(foreground, objects);
  // Step 7 (group_splitter.h).
  stats_.group_splits = group_splitter_.apply(foreground, objects);
  stats_.objects = objects->size();
}

}  // namespace core
}  // namespace urban_detection
