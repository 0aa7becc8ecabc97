#include "urban_detection/core/hierarchical_grid_detector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace urban_detection {
namespace core {
namespace {

// The grid -> slot maps are the only arrays that scale with the grid area; this bounds them
// to 64 Mi sub-cells (256 MB) so a typo in the extent cannot exhaust memory.
constexpr double kMaxDenseCells = 64.0 * 1024 * 1024;

const HierarchicalGridDetectorParams& checked(const HierarchicalGridDetectorParams& p) {
  const std::string err = validate(p);
  if (!err.empty()) throw std::invalid_argument("HierarchicalGridDetector: " + err);
  return p;
}

}  // namespace

std::string validate(const HierarchicalGridDetectorParams& p) {
  std::ostringstream err;
  if (!(p.coarse_cell_m >= 0.05 && p.coarse_cell_m <= 10.0)) {
    err << "coarse_cell_m must be in [0.05, 10] m, got " << p.coarse_cell_m;
  } else if (p.xi < 1 || p.xi > 8) {
    err << "xi must be in [1, 8], got " << p.xi;
  } else if (!(p.grid_half_extent_m >= 1.0 && p.grid_half_extent_m <= 500.0)) {
    err << "grid_half_extent_m must be in [1, 500] m, got " << p.grid_half_extent_m;
  } else if (std::pow(2.0 * std::ceil(p.grid_half_extent_m / p.coarse_cell_m) * p.xi, 2) >
             kMaxDenseCells) {
    err << "grid_half_extent_m / (coarse_cell_m / xi) gives more than " << kMaxDenseCells
        << " sub-cells; enlarge coarse_cell_m or reduce grid_half_extent_m";
  } else if (!(p.max_abs_z_m > 0.0)) {
    err << "max_abs_z_m must be > 0 m, got " << p.max_abs_z_m;
  } else if (!(p.psi_max_m >= 0.0 && p.psi_max_m <= 100.0)) {
    err << "psi_max_m must be in [0, 100] m, got " << p.psi_max_m;
  } else if (!(p.min_split_height_span_m >= 0.0 && p.min_split_height_span_m <= 10.0)) {
    err << "min_split_height_span_m must be in [0, 10] m, got " << p.min_split_height_span_m;
  } else if (p.min_gap_subcells < 1) {
    err << "min_gap_subcells must be >= 1, got " << p.min_gap_subcells;
  } else if (!(p.max_split_range_m >= 0.0)) {
    err << "max_split_range_m must be >= 0 m, got " << p.max_split_range_m;
  } else if (!(p.dense_min_weighted_points >= 0.0 && p.dense_min_weighted_points <= 1e6)) {
    err << "dense_min_weighted_points must be in [0, 1e6], got " << p.dense_min_weighted_points;
  } else if (p.min_points < 1) {
    err << "min_points must be >= 1, got " << p.min_points;
  } else if (!(p.max_extent_m > 0.0)) {
    err << "max_extent_m must be > 0 m, got " << p.max_extent_m;
  } else if (p.weight.coefficients.empty() || p.weight.coefficients.size() > 16) {
    err << "weight.coefficients must have 1..16 entries, got " << p.weight.coefficients.size();
  } else if (!std::all_of(p.weight.coefficients.begin(), p.weight.coefficients.end(),
                          [](double c) { return std::isfinite(c); })) {
    err << "weight.coefficients must be finite";
  } else if (!(p.weight.max_weight >= 1.0 && p.weight.max_weight <= 1e6)) {
    err << "weight.max_weight must be in [1, 1e6], got " << p.weight.max_weight;
  } else if (!(p.weight.full_density_distance_m >= 0.0 &&
               p.weight.max_distance_m > p.weight.full_density_distance_m &&
               p.weight.max_distance_m <= 1000.0)) {
    err << "weight distances need 0 <= full_density_distance_m < max_distance_m <= 1000 m, got "
        << p.weight.full_density_distance_m << " and " << p.weight.max_distance_m;
  }
  return err.str();
}

HierarchicalGridDetector::HierarchicalGridDetector(const HierarchicalGridDetectorParams& params)
    : params_(checked(params)),
      weight_(params.weight, (params.grid_half_extent_m + params.coarse_cell_m) * M_SQRT2 + 1.0),
      dense_cell_m_(params.coarse_cell_m / params.xi) {
  // An even number of super-cells with the sensor on a cell corner: cell borders lie on
  // multiples of W_S (and of W_S / xi), independent of the extent.
  const int half = static_cast<int>(std::ceil(params_.grid_half_extent_m / params_.coarse_cell_m));
  nc_ = 2 * half;
  nd_ = nc_ * params_.xi;
  origin_m_ = -half * params_.coarse_cell_m;
  buildMasks();
  dense_slot_.assign(static_cast<std::size_t>(nd_) * nd_, -1);
  coarse_slot_.assign(static_cast<std::size_t>(nc_) * nc_, -1);
}

void HierarchicalGridDetector::buildMasks() {
  // Sub-cell (lx, ly) of a super-cell is bit ly * xi + lx.
  const int xi = params_.xi;
  auto bit = [xi](int lx, int ly) { return std::uint64_t{1} << (ly * xi + lx); };
  full_mask_ = 0;
  for (int ly = 0; ly < xi; ++ly) {
    for (int lx = 0; lx < xi; ++lx) full_mask_ |= bit(lx, ly);
  }
  for (int k = 0; k < xi; ++k) {
    column_mask_[k] = row_mask_[k] = 0;
    for (int j = 0; j < xi; ++j) {
      column_mask_[k] |= bit(k, j);
      row_mask_[k] |= bit(j, k);
    }
  }
  // facing_[(dy + 1) * 3 + dx + 1]: sub-cells on the side facing the neighbour (dx, dy): a
  // column or row for edge neighbours, the corner sub-cell for diagonal ones.
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      std::uint64_t m = 0;
      for (int ly = 0; ly < xi; ++ly) {
        for (int lx = 0; lx < xi; ++lx) {
          const bool okx = dx == 0 || (dx > 0 ? lx == xi - 1 : lx == 0);
          const bool oky = dy == 0 || (dy > 0 ? ly == xi - 1 : ly == 0);
          if (okx && oky) m |= bit(lx, ly);
        }
      }
      facing_[(dy + 1) * 3 + dx + 1] = m;
    }
  }
  // Interior separating lines, columns first, each ordered from the centre outwards.
  separators_.clear();
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<int> ks;
    for (int k = 1; k + 1 < xi; ++k) ks.push_back(k);
    std::stable_sort(ks.begin(), ks.end(), [xi](int a, int b) {
      return std::abs(2 * a - (xi - 1)) < std::abs(2 * b - (xi - 1));
    });
    for (const int k : ks) {
      Separator sep{0, 0, 0};
      for (int ly = 0; ly < xi; ++ly) {
        for (int lx = 0; lx < xi; ++lx) {
          const int v = axis == 0 ? lx : ly;
          (v < k ? sep.side_a : v > k ? sep.side_b : sep.line) |= bit(lx, ly);
        }
      }
      separators_.push_back(sep);
    }
  }
}

int HierarchicalGridDetector::find(std::vector<std::int32_t>* parent, std::int32_t i) const {
  std::vector<std::int32_t>& p = *parent;
  while (p[i] != i) {
    p[i] = p[p[i]];  // path halving
    i = p[i];
  }
  return i;
}

bool HierarchicalGridDetector::linked(std::int32_t a, std::int32_t b) const {
  return a == b || std::fabs(coarse_zmax_[a] - coarse_zmax_[b]) <= params_.psi_max_m;
}

bool HierarchicalGridDetector::spansTouch(std::uint64_t a, std::uint64_t b, int dx,
                                          int dy) const {
  if (dx != 0 && dy != 0) return true;  // diagonal: reaching the shared corner is enough
  if ((a == full_mask_) || (b == full_mask_)) return true;
  // Columns (for a neighbour above/below) or rows (left/right) each part occupies, as bits.
  const int xi = params_.xi;
  std::uint32_t sa = 0, sb = 0;
  for (int k = 0; k < xi; ++k) {
    const std::uint64_t line = dy != 0 ? column_mask_[k] : row_mask_[k];
    if (a & line) sa |= 1u << k;
    if (b & line) sb |= 1u << k;
  }
  return ((sa | (sa << 1) | (sa >> 1)) & sb) != 0;
}

int HierarchicalGridDetector::gapBetween(std::int32_t node_a, std::int32_t node_b, int dx,
                                         int dy) const {
  // Empty sub-cell columns (rows) between the dense boxes of part a and of part b, b lying in
  // the super-cell at offset (dx, dy) of a's. A lower bound of the Chebyshev gap between any
  // dense sub-cell of a and any of b, so a cut is never made where the exact gap is smaller.
  const PartBox& a = part_box_[node_a];
  const PartBox& b = part_box_[node_b];
  const int xi = params_.xi;
  int gap = -1;
  if (dx > 0) gap = std::max(gap, xi + b.min_x - a.max_x - 1);
  if (dx < 0) gap = std::max(gap, xi + a.min_x - b.max_x - 1);
  if (dy > 0) gap = std::max(gap, xi + b.min_y - a.max_y - 1);
  if (dy < 0) gap = std::max(gap, xi + a.min_y - b.max_y - 1);
  return gap;
}

bool HierarchicalGridDetector::computeUnsplittable(std::int32_t c) const {
  if (coarse_zmax_[c] - coarse_zmin_[c] < params_.min_split_height_span_m) return true;  // thin
  const int cx = coarse_cell_[c] % nc_, cy = coarse_cell_[c] / nc_;
  const double x = (cx + 0.5) * params_.coarse_cell_m + origin_m_;
  const double y = (cy + 0.5) * params_.coarse_cell_m + origin_m_;
  return x * x + y * y > params_.max_split_range_m * params_.max_split_range_m;  // far
}

void HierarchicalGridDetector::resetGrid() {
  for (const std::int32_t cell : dense_cell_) dense_slot_[cell] = -1;
  for (const std::int32_t cell : coarse_cell_) coarse_slot_[cell] = -1;
  dense_cell_.clear();
  coarse_cell_.clear();
}

void HierarchicalGridDetector::detect(const LabeledCloud& foreground,
                                      std::vector<DetectedObject>* objects) {
  stats_ = HierarchicalGridStats();
  const std::size_t n = foreground.points.size();
  stats_.input_points = n;
  resetGrid();
  dense_count_.clear();
  dense_xy_.clear();
  dense_zmin_.clear();
  dense_zmax_.clear();
  dense_coarse_.clear();
  coarse_zmax_.clear();
  coarse_zmin_.clear();
  point_slot_.resize(n);

  // --- Binning: every point goes to its sub-cell and, through it, to its super-cell. -------
  const float origin = static_cast<float>(origin_m_);
  const float inv_dense = static_cast<float>(1.0 / dense_cell_m_);
  const float nd_f = static_cast<float>(nd_);
  const float max_abs_z = static_cast<float>(params_.max_abs_z_m);
  const int xi = params_.xi;
  for (std::size_t i = 0; i < n; ++i) {
    const LabeledPoint& p = foreground.points[i];
    point_slot_[i] = -1;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      ++stats_.invalid_points;
      continue;
    }
    const float fx = (p.x - origin) * inv_dense;
    const float fy = (p.y - origin) * inv_dense;
    if (!(fx >= 0.0f && fx < nd_f && fy >= 0.0f && fy < nd_f) || std::fabs(p.z) > max_abs_z) {
      ++stats_.outside_points;
      continue;
    }
    const int ix = std::min(static_cast<int>(fx), nd_ - 1);
    const int iy = std::min(static_cast<int>(fy), nd_ - 1);
    const std::int32_t cell = iy * nd_ + ix;
    std::int32_t slot = dense_slot_[cell];
    if (slot < 0) {
      slot = static_cast<std::int32_t>(dense_cell_.size());
      dense_slot_[cell] = slot;
      dense_cell_.push_back(cell);
      dense_xy_.push_back(CellXY{ix, iy});
      dense_count_.push_back(0);
      const std::int32_t ccell = (iy / xi) * nc_ + ix / xi;
      std::int32_t cslot = coarse_slot_[ccell];
      if (cslot < 0) {
        cslot = static_cast<std::int32_t>(coarse_cell_.size());
        coarse_slot_[ccell] = cslot;
        coarse_cell_.push_back(ccell);
        coarse_zmax_.push_back(-std::numeric_limits<float>::infinity());
        coarse_zmin_.push_back(std::numeric_limits<float>::infinity());
      }
      dense_coarse_.push_back(cslot);
      dense_zmin_.push_back(p.z);
      dense_zmax_.push_back(p.z);
    }
    ++dense_count_[slot];
    dense_zmax_[slot] = std::max(dense_zmax_[slot], p.z);
    dense_zmin_[slot] = std::min(dense_zmin_[slot], p.z);
    point_slot_[i] = slot;
  }
  const std::int32_t nds = static_cast<std::int32_t>(dense_cell_.size());
  const std::int32_t ncs = static_cast<std::int32_t>(coarse_cell_.size());
  // Heights per sub-cell, gathered to the super-cells once (fewer dependent loads per point).
  for (std::int32_t t = 0; t < nds; ++t) {
    const std::int32_t c = dense_coarse_[t];
    coarse_zmax_[c] = std::max(coarse_zmax_[c], dense_zmax_[t]);
    coarse_zmin_[c] = std::min(coarse_zmin_[c], dense_zmin_[t]);
  }
  stats_.dense_cells = nds;
  stats_.coarse_cells = ncs;

  // --- Coarse level: psi links between 8-neighbouring super-cells -> blobs. -----------------
  coarse_parent_.resize(ncs);
  for (std::int32_t s = 0; s < ncs; ++s) coarse_parent_[s] = s;
  static constexpr int kForward[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};  // each pair once
  for (std::int32_t s = 0; s < ncs; ++s) {
    const int cx = coarse_cell_[s] % nc_, cy = coarse_cell_[s] / nc_;
    for (const auto& o : kForward) {
      const int x = cx + o[0], y = cy + o[1];
      if (x < 0 || x >= nc_ || y >= nc_) continue;
      const std::int32_t r = coarse_slot_[y * nc_ + x];
      if (r < 0 || !linked(s, r)) continue;
      const int a = find(&coarse_parent_, s), b = find(&coarse_parent_, r);
      if (a != b) coarse_parent_[std::max(a, b)] = std::min(a, b);
    }
  }
  for (std::int32_t s = 0; s < ncs; ++s) {
    if (find(&coarse_parent_, s) == s) ++stats_.coarse_blobs;
  }

  // --- Dense level: weighted densities and, per super-cell, the mask of its dense sub-cells.
  dense_occupied_.assign(nds, 0);
  dense_rho_.resize(nds);
  coarse_dense_mask_.assign(ncs, 0);
  const float thr = static_cast<float>(params_.dense_min_weighted_points);
  const float dcell = static_cast<float>(dense_cell_m_);
  for (std::int32_t s = 0; s < nds; ++s) {
    const int ix = dense_xy_[s].x, iy = dense_xy_[s].y;
    const float x = (ix + 0.5f) * dcell + origin, y = (iy + 0.5f) * dcell + origin;
    dense_rho_[s] = static_cast<float>(dense_count_[s]) * weight_(std::sqrt(x * x + y * y));
    if (dense_rho_[s] >= thr) {
      dense_occupied_[s] = 1;
      ++stats_.dense_occupied;
      coarse_dense_mask_[dense_coarse_[s]] |= std::uint64_t{1} << ((iy % xi) * xi + ix % xi);
    }
  }

  coarse_unsplittable_.resize(ncs);
  for (std::int32_t c = 0; c < ncs; ++c) coarse_unsplittable_[c] = computeUnsplittable(c);

  // Super-cell parts: a super-cell whose interior line (column or row) of sub-cells is all
  // near-empty, with dense sub-cells on both sides, is split in two (Fig. 4c).
  coarse_part_mask_.resize(2 * static_cast<std::size_t>(ncs));
  for (std::int32_t c = 0; c < ncs; ++c) {
    const std::uint64_t dense = coarse_dense_mask_[c];
    coarse_part_mask_[2 * c] = full_mask_;
    coarse_part_mask_[2 * c + 1] = 0;
    if (!params_.dense_refinement || unsplittable(c)) continue;
    for (const Separator& sep : separators_) {
      if ((dense & sep.line) == 0 && (dense & sep.side_a) != 0 && (dense & sep.side_b) != 0) {
        coarse_part_mask_[2 * c] = sep.side_a;
        coarse_part_mask_[2 * c + 1] = sep.side_b;
        ++stats_.split_cells;
        break;
      }
    }
  }

  // Bounding box (in sub-cells) of the dense sub-cells of every part.
  part_box_.resize(2 * static_cast<std::size_t>(ncs));
  for (std::int32_t k = 0; k < 2 * ncs; ++k) {
    PartBox& box = part_box_[k];
    box = PartBox{127, -1, 127, -1};
    std::uint64_t m = coarse_dense_mask_[k / 2] & coarse_part_mask_[k];
    while (m) {
      const int b = __builtin_ctzll(m);
      m &= m - 1;
      const int lx = b % xi, ly = b / xi;
      box.min_x = std::min<int>(box.min_x, lx);
      box.max_x = std::max<int>(box.max_x, lx);
      box.min_y = std::min<int>(box.min_y, ly);
      box.max_y = std::max<int>(box.max_y, ly);
    }
  }

  // Links between parts of neighbouring super-cells (Fig. 4a, 4b); the rule is in the header.
  node_parent_.resize(2 * static_cast<std::size_t>(ncs));
  for (std::size_t k = 0; k < node_parent_.size(); ++k) {
    node_parent_[k] = static_cast<std::int32_t>(k);
  }
  if (params_.dense_refinement) {
    for (std::int32_t c = 0; c < ncs; ++c) {
      if (coarse_dense_mask_[c] == 0) continue;
      const int cx = coarse_cell_[c] % nc_, cy = coarse_cell_[c] / nc_;
      for (const auto& o : kForward) {
        const int x = cx + o[0], y = cy + o[1];
        if (x < 0 || x >= nc_ || y >= nc_) continue;
        const std::int32_t r = coarse_slot_[y * nc_ + x];
        if (r < 0 || coarse_dense_mask_[r] == 0 || !linked(c, r)) continue;
        const std::uint64_t facing_c = facing_[(o[1] + 1) * 3 + o[0] + 1];
        const std::uint64_t facing_r = facing_[(1 - o[1]) * 3 + 1 - o[0]];
        const bool coarse_only = unsplittable(c) || unsplittable(r);
        for (int pc = 0; pc < 2; ++pc) {
          const std::uint64_t part_c = coarse_part_mask_[2 * c + pc];
          if ((part_c & facing_c) == 0 || (part_c & coarse_dense_mask_[c]) == 0) continue;
          for (int pr = 0; pr < 2; ++pr) {
            const std::uint64_t part_r = coarse_part_mask_[2 * r + pr];
            if ((part_r & facing_r) == 0 || (part_r & coarse_dense_mask_[r]) == 0) continue;
            if (!spansTouch(part_c, part_r, o[0], o[1])) continue;
            if (!coarse_only && gapBetween(2 * c + pc, 2 * r + pr, o[0], o[1]) >=
                                    params_.min_gap_subcells) {
              continue;  // a near-empty strip at least min_gap_subcells wide separates them
            }
            const int a = find(&node_parent_, 2 * c + pc), b = find(&node_parent_, 2 * r + pr);
            if (a != b) node_parent_[std::max(a, b)] = std::min(a, b);
          }
        }
      }
    }
  }

  // --- Component index per sub-cell (near-empty ones borrow a dense neighbour's). -----------
  // Components are numbered in the order of first appearance of their sub-cells, which is the
  // order of the first point in the input, so ids do not depend on the grid layout.
  dense_object_.assign(nds, -1);
  root_object_.assign(2 * static_cast<std::size_t>(ncs), -1);
  std::int32_t ncomp = 0;
  auto componentOf = [&](std::int32_t s) -> std::int32_t {
    const std::int32_t c = dense_coarse_[s];
    std::int32_t root;
    if (params_.dense_refinement) {
      const int ix = dense_xy_[s].x, iy = dense_xy_[s].y;
      const std::uint64_t bit = std::uint64_t{1} << ((iy % xi) * xi + ix % xi);
      root = find(&node_parent_, 2 * c + ((coarse_part_mask_[2 * c + 1] & bit) ? 1 : 0));
    } else {
      root = find(&coarse_parent_, c);
    }
    if (root_object_[root] < 0) root_object_[root] = ncomp++;
    return root_object_[root];
  };
  for (std::int32_t s = 0; s < nds; ++s) {
    if (!params_.dense_refinement || dense_occupied_[s]) {
      dense_object_[s] = componentOf(s);
      continue;
    }
    const int ix = dense_xy_[s].x, iy = dense_xy_[s].y;
    std::int32_t best = -1;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = ix + dx, y = iy + dy;
        if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= nd_ || y >= nd_) continue;
        const std::int32_t r = dense_slot_[y * nd_ + x];
        if (r < 0 || !dense_occupied_[r] || !linked(dense_coarse_[s], dense_coarse_[r])) continue;
        if (best < 0 || dense_rho_[r] > dense_rho_[best]) best = r;
      }
    }
    if (best >= 0) dense_object_[s] = componentOf(best);
  }
  stats_.components = ncomp;

  // --- Per component: size and extent (on the sub-cells it covers) for the filters. --------
  comp_count_.assign(ncomp, 0);
  comp_box_.resize(4 * static_cast<std::size_t>(ncomp));
  for (std::int32_t c = 0; c < ncomp; ++c) {
    comp_box_[4 * c] = comp_box_[4 * c + 1] = std::numeric_limits<std::int32_t>::max();
    comp_box_[4 * c + 2] = comp_box_[4 * c + 3] = -1;
  }
  for (std::int32_t s = 0; s < nds; ++s) {
    const std::int32_t c = dense_object_[s];
    if (c < 0) {
      stats_.noise_points += dense_count_[s];
      continue;
    }
    comp_count_[c] += dense_count_[s];
    const std::int32_t ix = dense_xy_[s].x, iy = dense_xy_[s].y;
    std::int32_t* box = &comp_box_[4 * static_cast<std::size_t>(c)];
    box[0] = std::min(box[0], ix);
    box[1] = std::min(box[1], iy);
    box[2] = std::max(box[2], ix);
    box[3] = std::max(box[3], iy);
  }
  comp_final_.assign(ncomp, -1);
  std::size_t nobj = 0;
  const double max_extent_cells = params_.max_extent_m / dense_cell_m_;
  for (std::int32_t c = 0; c < ncomp; ++c) {
    const std::int32_t* box = &comp_box_[4 * static_cast<std::size_t>(c)];
    if (comp_count_[c] < static_cast<std::uint32_t>(params_.min_points)) {
      ++stats_.dropped_small;
    } else if (box[2] - box[0] + 1 > max_extent_cells || box[3] - box[1] + 1 > max_extent_cells) {
      ++stats_.dropped_large;
    } else {
      comp_final_[c] = static_cast<std::int32_t>(nobj++);
    }
  }
  stats_.objects = nobj;

  // --- Output. One pass scatters every point to its object (a counting sort into one flat
  // position array); the objects vector is resized, not cleared, so the index vectors keep
  // their capacity between frames. ----------------------------------------------------------
  objects->resize(nobj);
  object_begin_.assign(nobj + 1, 0);
  for (std::int32_t c = 0; c < ncomp; ++c) {
    if (comp_final_[c] >= 0) object_begin_[comp_final_[c] + 1] = comp_count_[c];
  }
  for (std::size_t k = 0; k < nobj; ++k) {
    object_begin_[k + 1] += object_begin_[k];
    (*objects)[k].indices.resize(object_begin_[k + 1] - object_begin_[k]);
  }
  positions_.resize(object_begin_[nobj]);
  cursor_.assign(object_begin_.begin(), object_begin_.end() - 1);
  for (std::int32_t s = 0; s < nds; ++s) {
    dense_object_[s] = dense_object_[s] < 0 ? -1 : comp_final_[dense_object_[s]];
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t s = point_slot_[i];
    if (s < 0) continue;
    const std::int32_t k = dense_object_[s];
    if (k < 0) continue;
    positions_[cursor_[k]++] = static_cast<std::uint32_t>(i);
  }
  for (std::size_t k = 0; k < nobj; ++k) {
    DetectedObject& obj = (*objects)[k];
    obj.id = static_cast<std::uint32_t>(k + 1);
    geometry_.compute(foreground, positions_.data() + object_begin_[k],
                      object_begin_[k + 1] - object_begin_[k], &obj, obj.indices.data());
  }
}

}  // namespace core
}  // namespace urban_detection
