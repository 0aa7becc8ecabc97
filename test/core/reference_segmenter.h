// A plain, unoptimised re-statement of GridSegmenter::segment (grid_segmenter.h, paper
// Sec. 3.1), used as the oracle that the optimised segmenter must match label for label.
// Everything is allocated per call, indexed by (row, col), and done one point or one cell at a
// time, in the order that defines the algorithm's floating-point results:
//  - a cell's z_sum is accumulated per maximal run of consecutive points falling in the same
//    cell, points without a cell (invalid) not interrupting a run (run sum first, then added to
//    the cell), which is the summation order the segmenter specifies;
//  - the terrain growing is a breadth-first search seeded in the order cells first receive a
//    point (the ground height a cell gets depends on the neighbour it is reached from).
// The Hough refinement is the library's HoughWallRefiner on the reference's cell classes.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace reference {

using core::SegmentClass;

struct RefCell {
  std::uint32_t count = 0;
  float z_min = std::numeric_limits<float>::max();
  float z_max = std::numeric_limits<float>::lowest();
  float z_sum = 0.0f;
  float mean() const { return z_sum / static_cast<float>(count); }
  float range() const { return z_max - z_min; }
};

struct RefOutput {
  std::vector<SegmentClass> labels;
  core::SegmentationStats stats;
};

inline RefOutput segment(const CloudXYZIRT& cloud, const core::GridSegmenterParams& p) {
  enum State { kNone, kReached, kFilled, kBridged };
  RefOutput out;
  // Grid geometry (SimpleGrid's guards).
  const double cell_m = std::max(p.cell_size_m, 0.01);
  const double range_m = std::clamp(p.max_range_m, cell_m, 1000.0);
  const int side = std::max(1, static_cast<int>(std::ceil(2.0 * range_m / cell_m)));
  const float inv = static_cast<float>(1.0 / cell_m);
  const float origin = static_cast<float>(-0.5 * side * cell_m);
  const float cell_f = static_cast<float>(cell_m);
  auto centre = [&](int r, int c, float* x, float* y) {
    *x = origin + (static_cast<float>(c) + 0.5f) * cell_f;
    *y = origin + (static_cast<float>(r) + 0.5f) * cell_f;
  };
  const std::size_t cells = static_cast<std::size_t>(side) * side;
  std::vector<RefCell> grid(cells);
  std::vector<int> point_cell(cloud.size(), -1);
  std::vector<float> point_z(cloud.size(), 0.0f);
  std::vector<int> first_touch;  // cells in the order they first receive a point
  const float offset = static_cast<float>(p.sensor_height_m);
  const float max_abs = static_cast<float>(p.max_abs_height_m);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float fc = (cloud[i].x - origin) * inv, fr = (cloud[i].y - origin) * inv;
    const float z = cloud[i].z + offset;
    point_z[i] = z;
    const bool inside = fc >= 0.0f && fc < static_cast<float>(side) && fr >= 0.0f &&
                        fr < static_cast<float>(side) && std::fabs(z) <= max_abs;
    if (!inside) continue;
    point_cell[i] = static_cast<int>(fr) * side + static_cast<int>(fc);
  }
  // Per-cell statistics, run by run.
  for (std::size_t i = 0; i < cloud.size();) {
    const int c = point_cell[i];
    if (c < 0) {
      ++i;
      continue;
    }
    std::size_t j = i;
    std::uint32_t n = 0;
    float lo = point_z[i], hi = point_z[i], sum = 0.0f;
    // A run: consecutive points in cell c; points without a cell do not interrupt it.
    while (j < cloud.size() && (point_cell[j] == c || point_cell[j] < 0)) {
      if (point_cell[j] == c) {
        lo = std::min(lo, point_z[j]);
        hi = std::max(hi, point_z[j]);
        sum = n == 0 ? point_z[j] : sum + point_z[j];
        ++n;
      }
      ++j;
    }
    RefCell& g = grid[c];
    if (g.count == 0) first_touch.push_back(c);
    g.count += n;
    g.z_min = std::min(g.z_min, lo);
    g.z_max = std::max(g.z_max, hi);
    g.z_sum += sum;
    i = j;
  }
  out.stats.cells_occupied = static_cast<std::uint32_t>(first_touch.size());

  std::vector<SegmentClass> cls(cells, SegmentClass::kUnknown);
  const std::uint32_t min_pts = static_cast<std::uint32_t>(std::max(1, p.min_points_per_cell));
  for (int c : first_touch) {
    if (grid[c].count < min_pts) cls[c] = SegmentClass::kClutter;
  }

  // Terrain growing.
  const float flat = static_cast<float>(p.ground_max_range_m);
  const float step = static_cast<float>(p.ground_max_step_m);
  const float tol = static_cast<float>(p.ground_tolerance_m);
  std::vector<int> state(cells, kNone), hops(cells, 0);
  std::vector<float> ground(cells, 0.0f);
  std::vector<int> queue;
  const float seed_r2 = static_cast<float>(p.seed_radius_m * p.seed_radius_m);
  for (int c : first_touch) {
    const RefCell& g = grid[c];
    if (cls[c] == SegmentClass::kClutter) continue;
    if (!(g.range() < flat) || std::fabs(g.mean()) > static_cast<float>(p.seed_max_abs_height_m)) {
      continue;
    }
    float x, y;
    centre(c / side, c % side, &x, &y);
    if (x * x + y * y > seed_r2) continue;
    state[c] = kReached;
    ground[c] = g.mean();
    queue.push_back(c);
  }
  std::uint32_t reached = static_cast<std::uint32_t>(queue.size());
  const int max_hops = std::min(250, static_cast<int>(p.ground_max_gap_m / cell_m));
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int c = queue[head];
    const int r = c / side, k = c % side;
    const int hop = state[c] == kBridged ? hops[c] : 0;
    for (int dr = -1; dr <= 1; ++dr) {
      for (int dk = -1; dk <= 1; ++dk) {
        if (dr == 0 && dk == 0) continue;
        const int nr = r + dr, nk = k + dk;
        if (nr < 0 || nr >= side || nk < 0 || nk >= side) continue;
        const int nc = nr * side + nk;
        if (state[nc] != kNone) continue;
        if (grid[nc].count == 0 || cls[nc] == SegmentClass::kClutter) {
          if (hop >= max_hops) continue;
          state[nc] = kBridged;
          ground[nc] = ground[c];
          hops[nc] = hop + 1;
          queue.push_back(nc);
          continue;
        }
        const bool is_flat = grid[nc].range() < flat;
        const float e = is_flat ? grid[nc].mean() : grid[nc].z_min;
        if (!(std::fabs(e - ground[c]) < step)) continue;
        state[nc] = kReached;
        ground[nc] = !is_flat && e - ground[c] > tol ? ground[c] : e;
        ++reached;
        if (is_flat) queue.push_back(nc);
      }
    }
  }
  out.stats.cells_ground_reached = reached;

  // Terrain fill: mean of the nearest square ring (Chebyshev distance) of reached or bridged
  // cells, rows top to bottom, columns left to right; applied after the search.
  std::vector<std::pair<int, float>> fills;
  for (int c : first_touch) {
    if (state[c] != kNone || (cls[c] == SegmentClass::kClutter && !p.ground_in_sparse_cells)) {
      continue;
    }
    const int r = c / side, k = c % side;
    for (int ring = 1; ring <= p.terrain_fill_iterations; ++ring) {
      float sum = 0.0f;
      int cnt = 0;
      for (int rr = r - ring; rr <= r + ring; ++rr) {
        for (int kk = k - ring; kk <= k + ring; ++kk) {
          if (rr < 0 || rr >= side || kk < 0 || kk >= side) continue;
          if (std::max(std::abs(rr - r), std::abs(kk - k)) != ring) continue;
          const int s = state[rr * side + kk];
          if (s == kReached || s == kBridged) {
            sum += ground[rr * side + kk];
            ++cnt;
          }
        }
      }
      if (cnt > 0) {
        fills.emplace_back(c, sum / static_cast<float>(cnt));
        break;
      }
    }
  }
  for (const auto& f : fills) {
    ground[f.first] = f.second;
    state[f.first] = kFilled;
  }

  // Cell classes.
  std::vector<std::uint8_t> support(cells, 0);
  const float tan_top = static_cast<float>(std::tan(p.fov_top_elevation_deg * M_PI / 180.0));
  const float half_diag = static_cast<float>(p.cell_size_m * M_SQRT1_2);
  for (int c : first_touch) {
    if (cls[c] == SegmentClass::kClutter) continue;
    const RefCell& g = grid[c];
    const float gz = state[c] != kNone ? ground[c] : 0.0f;
    if (g.z_max - gz > static_cast<float>(p.tall_min_height_m) ||
        g.range() > static_cast<float>(p.tall_min_range_m)) {
      cls[c] = SegmentClass::kTall;
    } else if (g.z_max - gz < tol) {
      cls[c] = SegmentClass::kGround;
    } else if (state[c] != kReached && g.range() < flat &&
               std::fabs(g.mean() - gz) < static_cast<float>(p.terrain_max_offset_m)) {
      cls[c] = SegmentClass::kGround;
      state[c] = kFilled;
      ground[c] = g.mean();
    } else if (p.curb_cells_ground && state[c] == kReached && g.range() < step &&
               std::fabs(g.z_min - gz) < step && g.z_max - gz < step && [&] {
                 // A kerb inside the cell: its top is the ground of a reached neighbour.
                 const int r = c / side, k = c % side;
                 for (int dr = -1; dr <= 1; ++dr) {
                   for (int dk = -1; dk <= 1; ++dk) {
                     const int nr = r + dr, nk = k + dk;
                     if ((dr == 0 && dk == 0) || nr < 0 || nr >= side || nk < 0 || nk >= side) {
                       continue;
                     }
                     const int n = nr * side + nk;
                     if (state[n] == kReached && std::fabs(ground[n] - g.z_max) < tol) return true;
                   }
                 }
                 return false;
               }()) {
      cls[c] = SegmentClass::kGround;
    } else {
      cls[c] = SegmentClass::kShort;
      float x, y;
      centre(c / side, c % side, &x, &y);
      const float d = std::max(0.0f, std::sqrt(x * x + y * y) - half_diag);
      support[c] = g.z_max - static_cast<float>(p.sensor_height_m) >= d * tan_top ? 1 : 0;
    }
  }
  // Long vehicles: groups of 8-connected cells that are tall and at most vehicle_max_height_m
  // high (top above the ground and z range) or short; a group touching no other tall cell, whose
  // cell centres (in cell units) span at most vehicle_max_length_m along every one of 8
  // directions 22.5 deg apart and vehicle_max_width_m along at least one (plus one cell each),
  // and at most half of whose tall cells have their top at the upper edge of the field of view
  // (the wall-support test), has its tall cells turned short (with the wall support of a short
  // cell).
  if (p.vehicle_max_height_m > 0.0) {
    const float vmax = static_cast<float>(p.vehicle_max_height_m);
    auto groundOf = [&](int c) { return state[c] != kNone ? ground[c] : 0.0f; };
    auto lowTall = [&](int c) {
      return cls[c] == SegmentClass::kTall && grid[c].z_max - groundOf(c) <= vmax &&
             grid[c].range() <= vmax;
    };
    std::vector<int> group_of(cells, -1);
    int groups = 0;
    for (int seed : first_touch) {
      if (!lowTall(seed) || group_of[seed] >= 0) continue;
      const int id = groups++;
      std::vector<int> members{seed};
      group_of[seed] = id;
      bool touches_higher = false;
      for (std::size_t h = 0; h < members.size(); ++h) {
        const int r = members[h] / side, k = members[h] % side;
        for (int dr = -1; dr <= 1; ++dr) {
          for (int dk = -1; dk <= 1; ++dk) {
            const int nr = r + dr, nk = k + dk;
            if ((dr == 0 && dk == 0) || nr < 0 || nr >= side || nk < 0 || nk >= side) continue;
            const int nc = nr * side + nk;
            if (group_of[nc] >= 0) continue;
            if (lowTall(nc) || cls[nc] == SegmentClass::kShort) {
              group_of[nc] = id;
              members.push_back(nc);
            } else if (cls[nc] == SegmentClass::kTall) {
              touches_higher = true;
            }
          }
        }
      }
      if (touches_higher) continue;
      float len = 0.0f, wid = std::numeric_limits<float>::max();
      for (int d = 0; d < 8; ++d) {
        const float dc = static_cast<float>(std::cos(d * M_PI / 8.0));
        const float ds = static_cast<float>(std::sin(d * M_PI / 8.0));
        float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
        for (int c : members) {
          const float v = static_cast<float>(c % side) * dc + static_cast<float>(c / side) * ds;
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
        len = std::max(len, hi - lo + 1.0f);
        wid = std::min(wid, hi - lo + 1.0f);
      }
      if (!(len <= static_cast<float>(p.vehicle_max_length_m / p.cell_size_m) &&
            wid <= static_cast<float>(p.vehicle_max_width_m / p.cell_size_m))) {
        continue;
      }
      std::size_t tall = 0, cut = 0;
      // Inside the Hough window (unless vehicle_fov_test_near) the test is left to the Hough
      // refinement.
      // ... for groups at least 3.5 m long (a van less a cell at each end).
      const float window = p.hough.enabled && !p.vehicle_fov_test_near &&
                                   len >= static_cast<float>(3.5 / p.cell_size_m)
                               ? static_cast<float>(p.hough.max_range_m)
                               : 0.0f;
      for (int c : members) {
        if (cls[c] != SegmentClass::kTall) continue;
        ++tall;
        float x, y;
        centre(c / side, c % side, &x, &y);
        if (window > 0.0f && std::fabs(x) <= window && std::fabs(y) <= window) continue;
        const float d = std::max(0.0f, std::sqrt(x * x + y * y) - half_diag);
        if (grid[c].z_max - static_cast<float>(p.sensor_height_m) >= d * tan_top) ++cut;
      }
      if (2 * cut > tall) continue;
      for (int c : members) {
        if (cls[c] != SegmentClass::kTall) continue;
        cls[c] = SegmentClass::kShort;
        float x, y;
        centre(c / side, c % side, &x, &y);
        const float d = std::max(0.0f, std::sqrt(x * x + y * y) - half_diag);
        support[c] = grid[c].z_max - static_cast<float>(p.sensor_height_m) >= d * tan_top ? 1 : 0;
      }
    }
  }
  // Overhang candidates (below): tall before the Hough refinement (a cell it turns back to
  // tall after the long-vehicle rule made it short is a wall), with a terrain estimate, a top
  // more than tall_min_height_m above it and the centre within overhang_max_range_m.
  std::vector<std::uint8_t> candidate(cells, 0);
  for (int c : first_touch) {
    if (cls[c] != SegmentClass::kTall || state[c] == kNone ||
        !(grid[c].z_max - ground[c] > static_cast<float>(p.tall_min_height_m))) {
      continue;
    }
    float x, y;
    centre(c / side, c % side, &x, &y);
    candidate[c] =
        x * x + y * y <= static_cast<float>(p.overhang_max_range_m * p.overhang_max_range_m);
  }
  if (p.hough.enabled) {
    core::HoughWallRefiner hough(p.hough);
    out.stats.hough = hough.refine(side, side, cell_m, &cls, &support);
  }

  // Overhangs: a tall cell with a terrain estimate whose top is more than tall_min_height_m
  // above it and whose centre is within overhang_max_range_m; the heights of its points above
  // ground + tol in 0.125 m bins (bin 63 open); the lowest run of overhang_min_gap_m or more of
  // empty bins above the lowest point ends the lower part, whose points are short when its top
  // (upper edge of its highest bin, plus tol) is between overhang_min_height_m and
  // tall_min_height_m; the cut is that edge.
  std::vector<float> cut(cells, -std::numeric_limits<float>::infinity());  // none
  // A thin upright's widened box, per cell where there is one.
  std::vector<std::array<float, 4>> upright(cells);
  std::vector<std::uint8_t> is_upright(cells, 0);
  if (p.overhang_min_gap_m > 0.0 || p.thin_max_width_m > 0.0) {
    const int gap_bins = static_cast<int>(std::ceil(p.overhang_min_gap_m * 8.0f - 1e-6));
    std::vector<std::vector<bool>> bins(cells);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const int c = point_cell[i];
      if (c < 0 || !candidate[c] || point_z[i] < ground[c] + tol) continue;
      if (bins[c].empty()) bins[c].assign(64, false);
      const float d = point_z[i] - (ground[c] + tol);
      bins[c][std::min(63, static_cast<int>(d * 8.0f))] = true;
    }
    // Thin uprights: the xy box of the points more than tall_min_height_m above the ground.
    const float upper = static_cast<float>(p.tall_min_height_m) - tol;
    std::vector<std::array<float, 4>> top_box(
        cells, {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                -std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()});
    std::vector<std::vector<bool>> top_bins(cells);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const int c = point_cell[i];
      if (c < 0 || !candidate[c] || !(point_z[i] - (ground[c] + tol) > upper)) continue;
      if (top_bins[c].empty()) top_bins[c].assign(64, false);
      top_bins[c][std::min(63, static_cast<int>((point_z[i] - (ground[c] + tol)) * 8.0f))] = true;
      auto& b = top_box[c];
      b[0] = std::min(b[0], cloud[i].x);
      b[1] = std::min(b[1], cloud[i].y);
      b[2] = std::max(b[2], cloud[i].x);
      b[3] = std::max(b[3], cloud[i].y);
    }
    for (int c : first_touch) {
      if (bins[c].empty()) continue;
      const std::vector<bool>& b = bins[c];
      int top = 0;
      while (!b[top]) ++top;
      // Walk up through the occupied bins until the next one lies above a deep enough run.
      while (gap_bins > 0) {
        int next = top + 1;
        while (next < 64 && !b[next]) ++next;
        if (next == 64) break;  // nothing above: no overhang
        if (next - top - 1 >= gap_bins) {
          const float edge = static_cast<float>(top + 1) / 8.0f;
          int above = 0;  // occupied bins above the band: two scan rings at least
          for (int k = next; k < 64; ++k) above += b[k];
          if (tol + edge <= static_cast<float>(p.tall_min_height_m) &&
              tol + edge >= static_cast<float>(p.overhang_min_height_m) && above >= 2) {
            cut[c] = edge;
          }
          break;
        }
        top = next;
      }
      const auto& bx = top_box[c];
      const float w = static_cast<float>(p.thin_max_width_m);
      const int top_count =
          static_cast<int>(std::count(top_bins[c].begin(), top_bins[c].end(), true));
      if (p.thin_max_width_m > 0.0 && std::isinf(cut[c]) && top_count >= 2 && bx[2] - bx[0] <= w &&
          bx[3] - bx[1] <= w) {
        upright[c] = {bx[0] - 0.1f, bx[1] - 0.1f, bx[2] + 0.1f, bx[3] + 0.1f};
        is_upright[c] = 1;
      }
    }
  }

  // Points: in a short, tall or (with ground_in_sparse_cells) clutter cell that has a terrain
  // estimate, points within ground_tolerance_m above it are ground; otherwise the cell class
  // (in an overhang cell: short below the cut, tall above).
  out.labels.assign(cloud.size(), SegmentClass::kUnknown);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int c = point_cell[i];
    if (c < 0) {
      ++out.stats.points_unknown;
      out.stats.points_non_finite += !isFinitePoint(cloud.points[i]);
      continue;
    }
    SegmentClass label = cls[c];
    const bool split = (label == SegmentClass::kShort || label == SegmentClass::kTall ||
                        (label == SegmentClass::kClutter && p.ground_in_sparse_cells)) &&
                       state[c] != kNone;
    if (split && point_z[i] < ground[c] + tol) {
      label = SegmentClass::kGround;
    } else if (label == SegmentClass::kTall && point_z[i] - (ground[c] + tol) < cut[c]) {
      label = SegmentClass::kShort;
    } else if (label == SegmentClass::kTall && is_upright[c] &&
               point_z[i] - (ground[c] + tol) <= static_cast<float>(p.tall_min_height_m) - tol &&
               !(cloud[i].x >= upright[c][0] && cloud[i].x <= upright[c][2] &&
                 cloud[i].y >= upright[c][1] && cloud[i].y <= upright[c][3])) {
      label = SegmentClass::kShort;
    }
    out.labels[i] = label;
    switch (label) {
      case SegmentClass::kClutter:
        ++out.stats.points_clutter;
        break;
      case SegmentClass::kGround:
        ++out.stats.points_ground;
        break;
      case SegmentClass::kTall:
        ++out.stats.points_tall;
        break;
      case SegmentClass::kShort:
        ++out.stats.points_short;
        break;
      default:
        ++out.stats.points_unknown;
        break;
    }
  }
  return out;
}

}  // namespace reference
}  // namespace urban_detection
