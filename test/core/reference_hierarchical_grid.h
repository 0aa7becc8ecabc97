// A plain, unoptimised re-statement of HierarchicalGridDetector::detect (the rules in the file
// comment of hierarchical_grid_detector.h, steps 1 to 5; steps 6 and 7 are the library's
// FarObjectMerger and GroupSplitter, applied by the caller), used as the oracle that the
// optimised detector must
// match object for object. Written for obviousness, not speed: everything is allocated per
// call, cells live in std::map keyed by their (column, row), every neighbour is bounds-checked,
// components are breadth-first searches over an explicit edge list, and every rule is tested
// for every candidate pair, not looked up in tables.
//
// What is taken from the detector as part of the rule (the results depend on it):
//  - cells are computed in float, as (x - origin) * (1 / sub-cell side), truncated, and a
//    sub-cell's centre is (i + 0.5) * side + origin in float; distances compare as float squares;
//  - the psi test compares |Z_max(s) - Z_max(r)|, a float difference, with psi_max_m;
//  - the weighted density is count * w(d) with w the library's DistanceWeight (its table), and
//    an object's weighted count is the float sum over its sub-cells in the order they first
//    receive a point;
//  - the radial bridges use the direction of the centre of a's 1.4 deg bin (256 bins of a
//    pseudo-angle, the header's "tabulated per 1.4 deg bin"); the roof bridge uses b's bin for
//    the offsets and b's own direction for the distance along its line of sight;
//  - ids follow the first point of each object in the input cloud.
//
// Two places where the detector does not do what the header says (kept selectable, see
// RefOptions). (1) The gap bridge of step 3 ("a's centre farther than
// gap_bridge_range_m and max(|o.x|, |o.y|) = 2") is probed by the detector only towards the
// forward half of the ring (o.y > 0, or o.y = 0 and o.x > 0), on the assumption that the other
// half is "the same pairs seen from their other end". That holds only when both ends are beyond
// gap_bridge_range_m: for a pair straddling that circle, the detector links it only when the
// far end is the one with the smaller (row, column), so a scene and its mirror image
// (y -> -y) can give different objects. The reference follows the detector by default (so the
// equivalence tests compare everything else exactly) and states the header's rule with the
// option off; test_hierarchical_reference.cpp shows the difference on a constructed scene.
// (2) Beyond gap_bridge_range_m the detector takes the radial reach from its farthest table,
// built with far_radial_bridge_subcells, also where the centre is nearer than bridge_range_m;
// the header gives radial_bridge_subcells there. This only matters when gap_bridge_range_m <
// bridge_range_m (never with the shipped 35 m > 20 m, but validate() accepts it).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/distance_weight.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"

namespace urban_detection {
namespace reference {

struct RefOptions {
  // true: the gap bridge only towards the forward half of the ring, as the detector probes it
  // (see the file comment); false: the header's rule, any direction from a far sub-cell.
  bool gap_bridge_forward_half_only = true;
  // true: beyond gap_bridge_range_m the radial bridges reach far_radial_bridge_subcells even
  // where the centre is nearer than bridge_range_m, as the detector's farthest table does
  // (only differs when gap_bridge_range_m < bridge_range_m, not the shipped configuration);
  // false: the header's rule, the far reach only beyond bridge_range_m.
  bool far_reach_beyond_gap_range = true;
};

struct RefHierarchicalOutput {
  // Objects after step 5 in id order; each one the positions of its points in the input cloud,
  // ascending.
  std::vector<std::vector<std::uint32_t>> objects;
  // The counters the rules define (not the order-dependent bridge counts, nor far_joins).
  core::HierarchicalGridStats stats;
};

namespace hg_detail {

using Cell = std::pair<int, int>;  // (column, row)

struct SubCell {
  std::vector<std::uint32_t> points;  // positions in the cloud, ascending
  float zmin = std::numeric_limits<float>::infinity();
  float zmax = -std::numeric_limits<float>::infinity();
  float rho = 0.0f;
  bool dense = false;
};

// The pseudo-angle bin of the direction (x, y): 256 bins over [0, 4), monotonic in the angle.
inline int directionBin(float x, float y) {
  const float t = x / (std::fabs(x) + std::fabs(y));
  const float a = y >= 0.0f ? 1.0f - t : 3.0f + t;
  return std::min(255, static_cast<int>(a * 64));
}

// The unit vector of the centre of bin `bin` (the inverse of directionBin, in double).
inline void binDirection(int bin, double* ux, double* uy) {
  const double a = (bin + 0.5) * 4.0 / 256;
  const double t = a < 2.0 ? 1.0 - a : a - 3.0;
  double x = t, y = (a < 2.0 ? 1.0 : -1.0) * (1.0 - std::fabs(t));
  const double n = std::hypot(x, y);
  *ux = x / n;
  *uy = y / n;
}

// Offset o (sub-cells) lies on the line of sight u, ahead, at most one sub-cell beside it,
// beyond the 8-neighbourhood and at most `reach` sub-cells away (Chebyshev).
inline bool onRadialBridge(int ox, int oy, double ux, double uy, int reach) {
  const int cheb = std::max(std::abs(ox), std::abs(oy));
  if (cheb < 2 || cheb > reach) return false;
  const double along = ox * ux + oy * uy, across = ox * uy - oy * ux;
  return along > 1e-9 && std::fabs(across) <= 1.0 + 1e-9;
}

// Breadth-first components of `nodes` over the undirected `edges`: node -> component number.
inline std::map<Cell, int> components(const std::vector<Cell>& nodes,
                                      const std::map<Cell, std::set<Cell>>& edges) {
  std::map<Cell, int> comp;
  int next = 0;
  for (const Cell& start : nodes) {
    if (comp.count(start)) continue;
    std::deque<Cell> queue{start};
    comp[start] = next;
    while (!queue.empty()) {
      const Cell c = queue.front();
      queue.pop_front();
      const auto it = edges.find(c);
      if (it == edges.end()) continue;
      for (const Cell& n : it->second) {
        if (comp.count(n)) continue;
        comp[n] = next;
        queue.push_back(n);
      }
    }
    ++next;
  }
  return comp;
}

}  // namespace hg_detail

inline RefHierarchicalOutput detectHierarchical(const LabeledCloud& cloud,
                                                const core::HierarchicalGridDetectorParams& p,
                                                const RefOptions& options = RefOptions()) {
  using hg_detail::Cell;
  using hg_detail::SubCell;
  RefHierarchicalOutput out;
  core::HierarchicalGridStats& stats = out.stats;
  stats.input_points = cloud.size();

  // Grid: an even number of super-cells per side, the sensor on a cell corner.
  const int half = static_cast<int>(std::ceil(p.grid_half_extent_m / p.coarse_cell_m));
  const int nd = 2 * half * p.xi;  // sub-cells per side
  const double dcell = p.coarse_cell_m / p.xi;
  const float origin_f = static_cast<float>(-half * p.coarse_cell_m);
  const float dcell_f = static_cast<float>(dcell);
  const float inv_f = static_cast<float>(1.0 / dcell);
  const float max_z = static_cast<float>(p.max_abs_z_m);
  auto inGrid = [nd](const Cell& c) {
    return c.first >= 0 && c.second >= 0 && c.first < nd && c.second < nd;
  };
  auto superOf = [&p](const Cell& c) { return Cell(c.first / p.xi, c.second / p.xi); };
  auto centre = [&](const Cell& c, float* x, float* y) {
    *x = (c.first + 0.5f) * dcell_f + origin_f;
    *y = (c.second + 0.5f) * dcell_f + origin_f;
  };
  auto dist2 = [&](const Cell& c) {
    float x, y;
    centre(c, &x, &y);
    return x * x + y * y;
  };

  // Binning: every valid point into its sub-cell.
  std::map<Cell, SubCell> sub;
  std::vector<Cell> first_touch;  // sub-cells in the order they receive their first point
  for (std::uint32_t i = 0; i < cloud.size(); ++i) {
    const LabeledPoint& pt = cloud.points[i];
    if (!isFinitePoint(pt)) {
      ++stats.invalid_points;
      continue;
    }
    const float fx = (pt.x - origin_f) * inv_f, fy = (pt.y - origin_f) * inv_f;
    const float side = static_cast<float>(nd);
    if (!(fx >= 0.0f && fx < side && fy >= 0.0f && fy < side) || std::fabs(pt.z) > max_z) {
      ++stats.outside_points;
      continue;
    }
    const Cell c(static_cast<int>(fx), static_cast<int>(fy));
    if (!sub.count(c)) first_touch.push_back(c);
    SubCell& s = sub[c];
    s.points.push_back(i);
    s.zmin = std::min(s.zmin, pt.z);
    s.zmax = std::max(s.zmax, pt.z);
  }
  stats.dense_cells = sub.size();

  // Step 1: Z_max per super-cell and the psi link.
  std::map<Cell, float> zmax_of;
  for (const auto& kv : sub) {
    const Cell s = superOf(kv.first);
    const auto it = zmax_of.find(s);
    zmax_of[s] = it == zmax_of.end() ? kv.second.zmax : std::max(it->second, kv.second.zmax);
  }
  stats.coarse_cells = zmax_of.size();
  auto linked = [&](const Cell& a, const Cell& b) {  // super-cells
    const float d = std::fabs(zmax_of.at(a) - zmax_of.at(b));
    return a == b || static_cast<double>(d) <= p.psi_max_m;
  };

  // Step 2: weighted densities.
  const core::DistanceWeight weight(p.weight,
                                    (p.grid_half_extent_m + p.coarse_cell_m) * M_SQRT2 + 1.0);
  for (auto& kv : sub) {
    kv.second.rho =
        static_cast<float>(kv.second.points.size()) * weight(std::sqrt(dist2(kv.first)));
    kv.second.dense = kv.second.rho >= static_cast<float>(p.dense_min_weighted_points);
    stats.dense_occupied += kv.second.dense;
  }
  auto isDense = [&](const Cell& c) {
    const auto it = sub.find(c);
    return it != sub.end() && it->second.dense;
  };

  // The component (object candidate) of each sub-cell, -1 for noise.
  std::map<Cell, int> comp_of;
  if (!p.dense_refinement) {
    // Step 1's coarse blobs: 8-neighbouring non-empty super-cells with linked Z_max.
    std::vector<Cell> supers;
    std::map<Cell, std::set<Cell>> edges;
    for (const auto& kv : zmax_of) {
      supers.push_back(kv.first);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const Cell n(kv.first.first + dx, kv.first.second + dy);
          if (n == kv.first || !zmax_of.count(n) || !linked(kv.first, n)) continue;
          edges[kv.first].insert(n);
          edges[n].insert(kv.first);
        }
      }
    }
    const std::map<Cell, int> blob = hg_detail::components(supers, edges);
    std::set<int> blobs;
    for (const auto& kv : blob) blobs.insert(kv.second);
    stats.coarse_blobs = blobs.size();
    for (const auto& kv : sub) comp_of[kv.first] = blob.at(superOf(kv.first));
  } else {
    std::vector<Cell> dense_cells;
    for (const auto& kv : sub) {
      if (kv.second.dense) dense_cells.push_back(kv.first);
    }
    std::map<Cell, std::set<Cell>> edges;
    auto connect = [&](const Cell& a, const Cell& b) {
      edges[a].insert(b);
      edges[b].insert(a);
    };
    // Step 3: 8-neighbours and bridges between dense sub-cells of linked super-cells.
    const int reach_near = p.radial_bridge_subcells + 1,
              reach_far = p.far_radial_bridge_subcells + 1;
    const float bridge2 = static_cast<float>(p.bridge_range_m * p.bridge_range_m);
    const float gap2 = static_cast<float>(p.gap_bridge_range_m * p.gap_bridge_range_m);
    for (const Cell& a : dense_cells) {
      for (int oy = -1; oy <= 1; ++oy) {
        for (int ox = -1; ox <= 1; ++ox) {
          const Cell b(a.first + ox, a.second + oy);
          if (b != a && isDense(b) && linked(superOf(a), superOf(b))) connect(a, b);
        }
      }
      const float d2 = dist2(a);
      if (d2 < dcell_f * dcell_f) continue;  // the sensor's own sub-cells have no direction
      float ax, ay;
      centre(a, &ax, &ay);
      double ux, uy;
      hg_detail::binDirection(hg_detail::directionBin(ax, ay), &ux, &uy);
      const bool far = d2 > bridge2 || (options.far_reach_beyond_gap_range && d2 > gap2);
      const int reach = far ? reach_far : reach_near;
      const bool gap = d2 > gap2;
      const int r = std::max(reach, gap ? 2 : 0);  // no bridge is longer
      for (int oy = -r; oy <= r; ++oy) {
        for (int ox = -r; ox <= r; ++ox) {
          bool bridged = hg_detail::onRadialBridge(ox, oy, ux, uy, reach);
          if (gap && std::max(std::abs(ox), std::abs(oy)) == 2) {
            const bool forward = oy > 0 || (oy == 0 && ox > 0);
            bridged = bridged || forward || !options.gap_bridge_forward_half_only;
          }
          const Cell b(a.first + ox, a.second + oy);
          if (bridged && inGrid(b) && isDense(b) && linked(superOf(a), superOf(b))) connect(a, b);
        }
      }
    }
    // Step 3b: roof bridges, from each flat component of step 3 (z range of its dense
    // sub-cells at most roof_max_step_m) back along the line of sight of its sub-cells.
    if (p.roof_bridge_subcells > 0) {
      const std::map<Cell, int> comp3 = hg_detail::components(dense_cells, edges);
      std::map<int, std::pair<float, float>> range;  // component -> (zmin, zmax)
      for (const Cell& c : dense_cells) {
        const SubCell& s = sub.at(c);
        const auto it = range.find(comp3.at(c));
        if (it == range.end()) {
          range[comp3.at(c)] = {s.zmin, s.zmax};
        } else {
          it->second.first = std::min(it->second.first, s.zmin);
          it->second.second = std::max(it->second.second, s.zmax);
        }
      }
      const float step = static_cast<float>(p.roof_max_step_m);
      const float range2 = static_cast<float>(p.roof_bridge_range_m * p.roof_bridge_range_m);
      const float dtheta = static_cast<float>(p.ring_spacing_deg * M_PI / 180.0);
      std::vector<std::pair<Cell, Cell>> roof;
      for (const Cell& b : dense_cells) {
        const SubCell& sb = sub.at(b);
        const std::pair<float, float> zr = range.at(comp3.at(b));
        if (zr.second - zr.first > step || sb.zmax - sb.zmin > step) continue;  // not flat
        const float db2 = dist2(b);
        if (db2 < dcell_f * dcell_f) continue;
        const float zb = sb.zmax;
        if (std::fabs(zmax_of.at(superOf(b)) - zb) > step) continue;
        float bx, by;
        centre(b, &bx, &by);
        double ux, uy;
        hg_detail::binDirection(hg_detail::directionBin(bx, by), &ux, &uy);
        const int r = p.roof_bridge_subcells + 1;
        for (int oy = -r; oy <= r; ++oy) {
          for (int ox = -r; ox <= r; ++ox) {
            // a = b - o with o ahead of a on b's line of sight: a is nearer the sensor.
            if (!hg_detail::onRadialBridge(ox, oy, ux, uy, p.roof_bridge_subcells + 1)) continue;
            const Cell a(b.first - ox, b.second - oy);
            if (!inGrid(a) || !isDense(a)) continue;
            if (std::fabs(zb - zmax_of.at(superOf(a))) > step) continue;
            if (!linked(superOf(a), superOf(b))) continue;
            const float da2 = dist2(a);
            if (da2 > range2) continue;
            // Distance from a to b along b's line of sight, at most the gap two rings leave on
            // a horizontal surface at b's height (only below the sensor), plus one sub-cell.
            const float along = (ox * bx + oy * by) / std::sqrt(db2) * dcell_f;
            const float h = -zb;
            if (h > 0.0f && along > dtheta * da2 / h + dcell_f) continue;
            roof.emplace_back(a, b);
          }
        }
      }
      for (const auto& ab : roof) connect(ab.first, ab.second);
    }
    const std::map<Cell, int> comp = hg_detail::components(dense_cells, edges);
    for (const auto& kv : comp) comp_of[kv.first] = kv.second;
    // Step 4: a near-empty sub-cell joins the densest dense 8-neighbour of a linked super-cell
    // (the first in row-major order of the neighbourhood among equals), else it is noise.
    for (const auto& kv : sub) {
      if (kv.second.dense) continue;
      const Cell s = kv.first;
      Cell best;
      float best_rho = -std::numeric_limits<float>::infinity();
      bool found = false;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const Cell n(s.first + dx, s.second + dy);
          if (n == s || !isDense(n) || !linked(superOf(s), superOf(n))) continue;
          if (sub.at(n).rho > best_rho) {
            best = n;
            best_rho = sub.at(n).rho;
            found = true;
          }
        }
      }
      comp_of[s] = found ? comp.at(best) : -1;
    }
  }

  // Step 5: per component its sub-cells in first-touch order; the filters; ids by first point.
  std::map<int, std::vector<Cell>> members;
  for (const Cell& c : first_touch) {
    const int k = comp_of.at(c);
    if (k < 0) {
      stats.noise_points += sub.at(c).points.size();
    } else {
      members[k].push_back(c);
    }
  }
  stats.components = members.size();
  std::vector<std::vector<std::uint32_t>> kept;
  for (const auto& kv : members) {
    std::size_t count = 0;
    float rho = 0.0f;
    int min_x = nd, min_y = nd, max_x = -1, max_y = -1;
    std::vector<std::uint32_t> points;
    for (const Cell& c : kv.second) {
      const SubCell& s = sub.at(c);
      count += s.points.size();
      rho += s.rho;
      min_x = std::min(min_x, c.first);
      min_y = std::min(min_y, c.second);
      max_x = std::max(max_x, c.first);
      max_y = std::max(max_y, c.second);
      points.insert(points.end(), s.points.begin(), s.points.end());
    }
    const double max_cells = p.max_extent_m / dcell;
    if (count < static_cast<std::size_t>(p.min_points) ||
        rho < static_cast<float>(p.min_weighted_points)) {
      ++stats.dropped_small;
    } else if (max_x - min_x + 1 > max_cells || max_y - min_y + 1 > max_cells) {
      ++stats.dropped_large;
    } else {
      std::sort(points.begin(), points.end());
      kept.push_back(std::move(points));
    }
  }
  std::sort(kept.begin(), kept.end(),
            [](const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
              return a.front() < b.front();
            });
  out.objects = std::move(kept);
  stats.objects = out.objects.size();
  return out;
}

}  // namespace reference
}  // namespace urban_detection
