/// \file hierarchical_grid_detector.h
/// Object detection with the hierarchical grid model (paper Sec. 3 "Hierarchical Grid Model"
/// and Sec. 3.2), ROS-free.
///
/// Data structure. A coarse 2-D grid of side W_S (`coarse_cell_m`, the paper's optimum 0.60 m)
/// lies on the sensor's xy plane; each coarse cell ("super-cell") s is subdivided into xi x xi
/// dense sub-cells of side W_S / xi (xi = 3: 0.20 m). Every valid point is stored at both
/// levels: its sub-cell is computed once and its super-cell is the sub-cell index divided by xi,
/// so the two levels always agree. The grid covers at least [-grid_half_extent_m,
/// grid_half_extent_m)^2 around the sensor origin, with cell borders on multiples of W_S (the cloud
/// must be in the sensor frame: the distance weight uses the distance to the origin). Cells are
/// flat arrays; only the cells touched by a frame are visited and reset, so the cost is linear in
/// the number of points and nothing is allocated per frame in steady state.
///
/// Exact rule (the paper describes it in words and with Fig. 4; this is how it is implemented;
/// the radial bridges of step 3 are ours):
///
///  1. Coarse level. Z_max(s) is the largest z of the points in super-cell s. Two super-cells
///     s, r are *linked* when s = r or psi(s, r) = |Z_max(s) - Z_max(r)| <= `psi_max_m`. The
///     connected components of the links between 8-neighbouring non-empty super-cells
///     (union-find) are the coarse blobs: with `dense_refinement` = false they are the objects
///     (the paper's "simple grid" comparison of Fig. 7); with it, the links of step 3 carry
///     the coarse level's psi test and the blobs themselves are not built.
///  2. Dense level. The weighted density of sub-cell c with n points whose centre lies at
///     horizontal distance d from the sensor is rho(c) = n * w(d), w the distance weight of
///     distance_weight.h (far sub-cells are enriched, paper Sec. 4). c is *dense* when rho(c) >=
///     `dense_min_weighted_points`, otherwise *near-empty* (the grey cells of Fig. 4).
///  3. Separation. The coarse level only allows, the dense level separates: two dense
///     sub-cells a, b are connected when their super-cells are linked (step 1) and
///       - they are 8-neighbours, or
///       - b lies on a's *radial bridge*: with o = b - a in sub-cells and u the unit vector
///         from the sensor to a's centre, 2 <= max(|o.x|, |o.y|) <= B + 1, o.u > 0 and
///         |o x u| <= 1, i.e. ahead of a on its line of sight, at most one sub-cell beside it,
///         across at most B near-empty sub-cells; B = `radial_bridge_subcells`, or
///         `far_radial_bridge_subcells` when a's centre is farther than `bridge_range_m` from
///         the sensor. A spinning LiDAR samples an object finely in azimuth but its scan
///         lines land far apart in range on oblique and horizontal surfaces (a roof, a side
///         seen at a grazing angle), so holes along the line of sight are sampling holes, and
///         more so far away;
///       - or a's centre is farther than `gap_bridge_range_m` from the sensor and
///         max(|o.x|, |o.y|) = 2: there the azimuth step (~0.1 m at 35 m) leaves more than a
///         sub-cell between the returns on a face seen obliquely, in any direction.
///     (The bridges are tabulated per 1.4 deg bin of the direction of u.)
///  3b. Roof bridge (ours). Scan rings land r^2 * dtheta / h apart on a horizontal surface h
///     below the sensor at distance r (dtheta = `ring_spacing_deg`): on a car roof 0.3 m below
///     the sensor that is ~0.8 m at 7 m, so the far ring of a roof is cut off from the rest of
///     the car and becomes an object of its own. After step 3, a dense sub-cell b is also
///     connected to a dense sub-cell a nearer than `roof_bridge_range_m` on b's line of sight
///     (as in step 3: nearer the sensor, at most one sub-cell beside it, up to
///     `roof_bridge_subcells` + 1 sub-cells away) when b looks like a lone ring on a roof at the
///     height of a's top:
///       - b's component of step 3 is flat: its z range is at most `roof_max_step_m` (a car,
///         a pedestrian or a wall behind a car is not, whatever its top);
///       - b's top z_b is within `roof_max_step_m` of the Z_max of a's super-cell and of b's
///         super-cell (a pedestrian beside a car is taller than the car's roof);
///       - the distance from a to b is at most r_a^2 * dtheta / (-z_b) plus one sub-cell (z in
///         the sensor frame, the sensor at z = 0), and their super-cells are psi-linked.
///     `roof_bridge_subcells` = 0: off.
///  4. The points of a near-empty sub-cell join the object of the densest dense 8-neighbour
///     sub-cell whose super-cell is linked to its own; near-empty sub-cells with no such
///     neighbour are noise and their points are in no object.
///  5. Objects with fewer than `min_points` points, with a distance-weighted point count
///     sum(rho(c)) over their sub-cells below `min_weighted_points`, or whose sub-cells span
///     more than `max_extent_m` along x or y are dropped. The weighted count is the number of
///     points the object would have at full density (w = 1 up to the fitted density maximum,
///     ~7 m): a fixed point count is too strict far away and too lax near the sensor, where
///     fragments of bushes and leftovers of cars have tens of points. Ids are 1..N in the
///     order of the objects' first point in the input cloud.
///  6. Far pieces of one vehicle (ours, far_object_merger.h): objects at least
///     `far_merge.min_range_m` away whose boxes are at most `far_merge.max_gap_m` apart are
///     joined when the result still fits a vehicle box; `far_merge.max_gap_m` = 0: off.
///  7. Groups of people (ours, group_splitter.h): an object of a group's size and a person's
///     height whose height map shows several heads with a dip between them is split into one
///     object per head; `group_split.min_length_m` = 0: off.
///
/// Non-finite points, points outside the grid and points with |z| > max_abs_z_m are ignored
/// (counted in the stats).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/distance_weight.h"
#include "urban_detection/core/detection/far_object_merger.h"
#include "urban_detection/core/detection/group_splitter.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/detection/object_geometry.h"

namespace urban_detection {
namespace core {

/// Parameters of HierarchicalGridDetector, mirrored in config/hierarchical_grid.yaml
/// (`hierarchical_grid:`).
struct HierarchicalGridDetectorParams {
  double coarse_cell_m = 0.60;             // [m] W_S, side of a coarse super-cell (paper: 0.60)
  int xi = 3;                              // [-] sub-cells per super-cell side, 1..8 (paper: 3)
  double grid_half_extent_m = 80.0;        // [m] grid covers [-e, e)^2 around the sensor
  double max_abs_z_m = 50.0;               // [m] points with |z| above this are ignored
  double psi_max_m = 1.2;                  // [m] link neighbours when |Zmax(s) - Zmax(r)| <= this
  double dense_min_weighted_points = 6.0;  // [-] sub-cell dense when n * w(d) >= this
  int radial_bridge_subcells = 1;          // [sub-cells] near-empty sub-cells bridged along the
                                           //     line of sight (step 3)
  int far_radial_bridge_subcells = 3;      // [sub-cells] the same beyond bridge_range_m
  double bridge_range_m = 20.0;            // [m] sensor distance where the far bridge starts
  double gap_bridge_range_m = 35.0;        // [m] beyond, one near-empty sub-cell is bridged in any
                                           //     direction (step 3)
  int roof_bridge_subcells = 8;            // [sub-cells] 0 = off; a flat component (a lone scan
                                           //     ring on a roof) joins a dense sub-cell nearer on
                                           //     its line of sight across up to this many
                                           //     near-empty sub-cells (step 3b)
  double roof_max_step_m = 0.15;           // [m] that component's z range, and its top's distance
                                           //     to both super-cells' Z_max, at most this
  double roof_bridge_range_m = 25.0;       // [m] step 3b only from sub-cells this close
  double ring_spacing_deg = 0.5;           // [deg] elevation step between the sensor's scan rings:
                                           //     step 3b spans at most the gap two rings leave on
                                           //     a horizontal surface at that height
  bool dense_refinement = true;            // [-] false: objects are the coarse blobs (simple grid)
  int min_points = 10;                     // [-] objects with fewer points are dropped
  double min_weighted_points = 60.0;       // [-] objects whose distance-weighted point count
                                           //     (sum of n * w(d) over their sub-cells) is
                                           //     lower are dropped (step 5); 0 = off
  double max_extent_m = 20.0;              // [m] objects with a longer xy box side are dropped
  DistanceWeightParams weight;             // distance weight of sub-cell densities (paper Sec. 4)
  FarObjectMergerParams far_merge;         // step 6: far pieces of one vehicle joined (ours)
  GroupSplitterParams group_split;         // step 7: groups of people split (ours)
};

/// HierarchicalGridDetectorParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<HierarchicalGridDetectorParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"coarse_cell_m", "m", 0.05, 10.0, "W_S, side of a coarse super-cell"}, p.coarse_cell_m);
    f({"xi", "", 1, 8, "sub-cells per super-cell side"}, p.xi);
    f({"grid_half_extent_m", "m", 1.0, 500.0, "the grid covers [-e, e)^2 around the sensor"},
      p.grid_half_extent_m);
    f({"max_abs_z_m", "m", 0.1, 1000.0, "points with a larger |z| are ignored"}, p.max_abs_z_m);
    f({"psi_max_m", "m", 0.0, 100.0, "neighbours link when their Z_max differ by at most this"},
      p.psi_max_m);
    f({"dense_min_weighted_points", "", 0.0, 1e6, "a sub-cell is dense when n * w(d) >= this"},
      p.dense_min_weighted_points);
    f({"radial_bridge_subcells", "sub-cells", 0, 8,
       "near-empty sub-cells bridged along the line of sight"},
      p.radial_bridge_subcells);
    f({"far_radial_bridge_subcells", "sub-cells", 0, 8, "the same beyond bridge_range_m"},
      p.far_radial_bridge_subcells);
    f({"bridge_range_m", "m", 0.0, 1000.0, "sensor distance where the far bridge starts"},
      p.bridge_range_m);
    f({"gap_bridge_range_m", "m", 0.0, 1000.0,
       "beyond, one near-empty sub-cell is bridged in any direction"},
      p.gap_bridge_range_m);
    f({"roof_bridge_subcells", "sub-cells", 0, 8,
       "a flat component joins a dense sub-cell nearer on its line of sight across this many; 0 = "
       "off"},
      p.roof_bridge_subcells);
    f({"roof_max_step_m", "m", 0.0, 10.0, "that component's z range and step at most this"},
      p.roof_max_step_m);
    f({"roof_bridge_range_m", "m", 0.0, 1000.0, "the roof bridge only from sub-cells this close"},
      p.roof_bridge_range_m);
    f({"ring_spacing_deg", "deg", 0.01, 10.0, "elevation step between the sensor's scan rings"},
      p.ring_spacing_deg);
    f({"dense_refinement", "false: objects are the coarse blobs (simple grid)"},
      p.dense_refinement);
    f({"min_points", "", 1, 1000000, "objects with fewer points are dropped"}, p.min_points);
    f({"min_weighted_points", "", 0.0, 1e6,
       "objects with a lower distance-weighted point count are dropped; 0 = off"},
      p.min_weighted_points);
    f({"max_extent_m", "m", 0.1, 1000.0, "objects with a longer xy box side are dropped"},
      p.max_extent_m);
    forEachField(p.weight, "weight", f);
    forEachField(p.far_merge, "far_merge", f);
    forEachField(p.group_split, "group_split", f);
  }
};

/// Returns "" when `p` is usable, else a message naming the first bad field and its range.
std::string validate(const HierarchicalGridDetectorParams& p);

/// Counters of the last detect() call.
struct HierarchicalGridStats {
  std::size_t input_points = 0;
  std::size_t invalid_points = 0;  // non-finite coordinates
  std::size_t outside_points = 0;  // outside the grid extent or |z| > max_abs_z_m
  std::size_t coarse_cells = 0;    // non-empty super-cells
  std::size_t coarse_blobs = 0;    // coarse blobs (step 1); 0 with dense_refinement (not built)
  std::size_t dense_cells = 0;     // non-empty sub-cells
  std::size_t dense_occupied = 0;  // sub-cells with weighted density >= threshold
  std::size_t bridges = 0;         // bridges (step 3) that joined two components
  std::size_t roof_bridges = 0;    // roof bridges (step 3b) that joined two components
  std::size_t noise_points = 0;    // points of isolated near-empty sub-cells
  std::size_t components = 0;      // objects before the size filters
  std::size_t dropped_small = 0;   // components with < min_points points
  std::size_t dropped_large = 0;   // components longer than max_extent_m
  std::size_t far_joins = 0;       // far pieces joined by step 6
  std::size_t group_splits = 0;    // objects added by step 7
  std::size_t objects = 0;
};

/// Hierarchical grid detector (paper Sec. 3.2); see the file comment for the exact rule.
class HierarchicalGridDetector : public ObjectDetector {
 public:
  /// Throws std::invalid_argument when validate(params) is not empty.
  explicit HierarchicalGridDetector(
      const HierarchicalGridDetectorParams& params = HierarchicalGridDetectorParams());
  std::string name() const override { return "hierarchical_grid"; }
  void detect(const LabeledCloud& foreground, std::vector<DetectedObject>* objects) override;

  const HierarchicalGridDetectorParams& params() const { return params_; }
  const HierarchicalGridStats& stats() const { return stats_; }
  /// Sub-cell side W_S / xi [m].
  double denseCellSize() const { return dense_cell_m_; }

 private:
  // detect()'s stages, in order (the header's steps; each reads the members the previous ones
  // filled).
  // Every point to its sub-cell slot (point_slot_, dense_acc_); returns the number of sub-cells.
  std::int32_t binPoints(const LabeledCloud& foreground);
  // Per sub-cell arrays (dense_*) and the super-cells with their Z_max (coarse_*).
  void buildCells(std::int32_t nds);
  // Step 1's coarse blobs into coarse_parent_ (only without the dense refinement, see detect()).
  void linkCoarse();
  // Step 2: weighted densities, dense sub-cells (dense_bits_), psi keys, probe rows.
  void weighDensities();
  // Step 3: union-find of the dense sub-cells over the 8-neighbourhood and the radial bridges.
  void linkDense();
  // Step 3b: the roof bridges, into the same union-find.
  void roofBridges();
  // Step 4: component number per sub-cell (dense_object_); returns the number of components.
  std::int32_t numberComponents();
  // The size and extent filters: comp_final_; returns the number of objects.
  std::size_t filterComponents(std::int32_t ncomp);
  // The objects: point indices, boxes (object_geometry.h).
  void emitObjects(const LabeledCloud& foreground, std::int32_t ncomp, std::size_t nobj,
                   std::vector<DetectedObject>* objects);

  bool linked(std::int32_t coarse_a, std::int32_t coarse_b) const;
  void resetGrid();
  void buildBridgeTables();
  // Bridge table of step 3b (after the near, far and farthest tables of step 3).
  static constexpr int kRoofTable = 3;
  static constexpr int kDirectionBins = 256;  // line-of-sight directions of the bridge tables
  static int directionBin(float x, float y);

  HierarchicalGridDetectorParams params_;
  DistanceWeight weight_;
  ObjectGeometry geometry_;
  FarObjectMerger far_merger_;
  GroupSplitter group_splitter_;
  HierarchicalGridStats stats_;
  double dense_cell_m_;
  float psi_max_f_;  // [m] the largest float <= psi_max_m (the psi tests compare floats)
  int nd_;           // sub-cells per grid side
  int nc_;           // super-cells per grid side
  double origin_m_;  // [m] x and y of the grid's lower corner (a multiple of W_S)

  // Grid -> slot maps (-1 = untouched), reset through the touched slot lists. The sub-cell
  // maps are padded by probe_margin_ empty sub-cells on every side: sub-cell (ix, iy) is at
  // flat index (iy + probe_margin_) * stride_ + ix + probe_margin_, and every probe of steps
  // 3, 3b and 4 is a flat offset from it, with no bounds check.
  int probe_margin_ = 1;  // [sub-cells] largest probe offset (the padding)
  int stride_ = 0;        // nd_ + 2 * probe_margin_: padded sub-cells per side
  // Bridge tables (built once).
  struct CellXY {
    std::int32_t x, y;
  };
  std::vector<CellXY> bridge_offsets_;      // radial bridge offsets, see buildBridgeTables()
  std::vector<std::int32_t> bridge_begin_;  // [near, far][direction bin] -> offsets begin
  std::vector<std::int32_t> bridge_flat_;   // bridge_offsets_ as flat padded-map offsets
  // Step 3's probes per table (near, far, farthest) and direction bin, see buildBridgeTables().
  std::vector<std::int32_t> probe_flat_;   // rows of flat offsets: 4 forward, bridges, padding
  std::vector<std::uint64_t> probe_mask_;  // [table][bin]: the row's real entries
  std::int32_t probe_row_begin_[3] = {0, 0, 0};
  int probe_row_len_[3] = {0, 0, 0};  // per table: the length of all its rows (<= 64)

  // Binning's per-slot accumulator (see detect()).
  struct DenseAcc {
    float zmax, zmin;     // [m] highest and lowest point
    std::uint32_t count;  // points
    std::int32_t cell;    // flat padded-map index
  };
  // Step 3's probe row of a sub-cell: its flat offsets probe_flat_[begin, begin + len) and the
  // mask of the row's real entries (only the forward four for the sensor's own sub-cells).
  struct ProbeRow {
    std::int32_t begin, len;
    std::uint64_t mask;
  };
  // Scratch kept between revolutions (capacity reused), one struct per level.
  // Dense level: the padded grid maps, then per touched sub-cell (slot), in the order of their
  // first points.
  struct DenseLevel {
    std::vector<std::int32_t> slot;   // grid -> slot (-1 untouched), stride_ * stride_
    std::vector<std::uint64_t> bits;  // stride_ * stride_ bits: dense sub-cell
    // Grown to the largest cloud seen plus one, never shrunk, so the entry a point may open
    // always exists.
    std::vector<DenseAcc> acc;
    std::vector<ProbeRow> probe_of;
    std::vector<std::int32_t> cell;    // flat padded-map index
    std::vector<CellXY> xy;            // grid column and row
    std::vector<std::uint32_t> count;  // points
    std::vector<std::int32_t> coarse;  // slot of its super-cell
    std::vector<std::uint8_t> occupied;
    std::vector<float> rho;            // weighted density
    std::vector<float> key;            // [m] super-cell Z_max if dense, else NaN
    std::vector<float> zmax;           // [m] highest point
    std::vector<float> zmin;           // [m] lowest point
    std::vector<std::int32_t> parent;  // union-find of the dense level
    std::vector<std::int32_t> object;  // object index or -1
    // Step 3b: z range [m] per component root, and the sub-cells whose component is flat.
    std::vector<float> root_zmin;
    std::vector<float> root_zmax;
    std::vector<std::int32_t> flat;
  };
  // Coarse level: its grid map (not padded), then per touched super-cell (slot).
  struct CoarseLevel {
    std::vector<std::int32_t> slot;  // nc_ * nc_, -1 untouched
    std::vector<std::int32_t> of;    // sub-cell column or row -> super-cell's (i / xi)
    std::vector<std::int32_t> cell;
    std::vector<float> key;  // [m] Z_max at slot + 1, NaN at 0 (slot -1: empty)
    std::vector<float> zmax;
    std::vector<std::int32_t> parent;  // union-find of the coarse level
  };
  // Per component.
  struct Components {
    std::vector<std::int32_t> root_object;  // union-find root -> component index
    std::vector<std::uint32_t> count;
    std::vector<float> rho;                 // distance-weighted point count
    std::vector<std::int32_t> box;          // sub-cell min x, min y, max x, max y
    std::vector<std::int32_t> output;       // component -> output object index or -1
    std::vector<std::int32_t> slot_object;  // sub-cell slot + 1 -> output object index or -1
  };
  // Per output object.
  struct ObjectScratch {
    std::vector<std::uint32_t> begin;       // object k: xy[begin[k], begin[k + 1])
    std::vector<Eigen::Vector2f> xy;        // [m] xy of the points, grouped by object
    std::vector<ObjectMoments> moments;     // pass 1 of the object geometry
    std::vector<std::uint32_t*> index_out;  // scatter cursors into the objects' indices
    std::vector<Eigen::Vector2f*> xy_out;   // scatter cursors into xy
  };
  DenseLevel dense_;
  CoarseLevel coarse_;
  Components comps_;
  ObjectScratch objects_;
  // Per input point: its sub-cell slot, or -1.
  std::vector<std::int32_t> point_slot_;
};

}  // namespace core
}  // namespace urban_detection
