/// \file hierarchical_grid_detector.h
/// Object detection with the hierarchical grid model (paper Sec. 3 "Hierarchical Grid Model"
/// and Sec. 3.2), ROS-free.
///
/// Data structure. A coarse 2-D grid of side W_S (`coarse_cell_m`, the paper's optimum 0.60 m)
/// lies on the sensor's xy plane; each coarse cell ("super-cell") s is subdivided into xi x xi
/// dense sub-cells of side W_S / xi (xi = 3: 0.20 m). Every valid point is stored at both
/// levels: its sub-cell is computed once and its super-cell is the sub-cell index divided by xi,
/// so the two levels always agree. The grid covers at least [-grid_half_extent_m,
/// grid_half_extent_m)^2 around the sensor origin, with cell borders on multiples of W_S (the cloud must be in the sensor frame: the distance weight uses the
/// distance to the origin). Cells are flat arrays; only the cells touched by a frame are visited
/// and reset, so the cost is linear in the number of points and nothing is allocated per frame
/// in steady state.
///
/// Exact rule (the paper describes it in words and with Fig. 4; this is how it is implemented;
/// step 3's thin-cell exception is ours):
///
///  1. Coarse level. Z_max(s) is the largest z of the points in super-cell s. Two 8-neighbouring
///     non-empty super-cells s, r are *linked* when psi(s, r) = |Z_max(s) - Z_max(r)| <=
///     `psi_max_m`. The connected components of this link graph (union-find) are the coarse
///     blobs (reported in the stats; with `dense_refinement` = false they are the objects: the
///     paper's "simple grid" comparison of Fig. 7).
///  2. Dense level. The weighted density of sub-cell c with n points whose centre lies at
///     horizontal distance d from the sensor is rho(c) = n * w(d), w the distance weight of
///     distance_weight.h (far sub-cells are enriched, paper Sec. 4). c is *dense* when rho(c) >=
///     `dense_min_weighted_points`, otherwise *near-empty* (the grey cells of Fig. 4).
///  3. Separation. A super-cell is split into two parts when one of its interior lines of
///     sub-cells (a column or row other than the border ones; for xi = 3 the centre column,
///     then the centre row) is entirely near-empty while both sides hold dense sub-cells; its
///     sub-cells on either side form the two parts and the line itself belongs to neither.
///     Otherwise the super-cell is one part. Two parts P (of s) and Q (of r) of 8-neighbouring
///     super-cells are connected when all of these hold:
///       - s and r are linked by psi (step 1);
///       - P and Q both hold dense sub-cells and both reach the side of their super-cell that
///         faces the other (its border column or row; for a diagonal neighbour its corner
///         sub-cell): a half of a split super-cell only touches the neighbours on its side;
///       - for an edge neighbour, the columns (rows) P and Q occupy along the shared border
///         are adjacent (the left half of one cell never touches the right half of the cell
///         above it);
///       - the dense sub-cells of P and of Q are not separated by a near-empty strip at least
///         `min_gap_subcells` wide (default 2 sub-cells, 0.4 m): counted between the bounding
///         boxes of their dense sub-cells, across the shared border (along x for a left/right
///         neighbour, y for above/below, the larger of the two for a diagonal one). The strip
///         may lie on the border (both facing lines near-empty) or beside it; a single empty
///         column is not enough, because that is also what an oblique car side or the corner
///         of one car looks like in the data.
///     Objects are the connected components of the parts holding dense sub-cells. This is the
///     paper's Fig. 4:
///       a) two cars whose super-cells touch and pass psi: the near-empty strip along the
///          border of the two super-cells cuts the link;
///       b) a pedestrian beside a car: likewise, between the car's and the pedestrian's cell;
///       c) a super-cell straddling two objects: its near-empty centre line splits it, and each
///          part connects only to the neighbours on its side.
///     Exceptions (ours), where sub-cell gaps are sampling gaps rather than gaps between
///     objects, so a super-cell is never split and its psi links never cut:
///       - a *thin* super-cell, whose points span less than `min_split_height_span_m` in z
///         (Zmax - Zmin): it holds only a slab of scan lines seen from above (a near car's
///         roof or bonnet, where the HDL-64E's lines are up to ~1 m apart), whereas the
///         objects of Fig. 4 are separated where vertical surfaces face each other;
///       - a super-cell whose centre is farther than `max_split_range_m` from the sensor: the
///         0.17 deg azimuth step leaves ~0.1 m between returns at 30 m and 0.2-0.3 m on
///         oblique surfaces beyond, the sub-cell size, so empty sub-cells appear inside
///         objects (the weight scales densities but cannot fill an empty sub-cell).
///     The dense level only divides coarse blobs, never joins them.
///  4. The points of a near-empty sub-cell join the object of the densest dense 8-neighbour
///     sub-cell that it may connect to (same or linked super-cell); near-empty sub-cells with no
///     such neighbour are noise and their points are in no object.
///  5. Objects with fewer than `min_points` points or whose sub-cells span more than
///     `max_extent_m` along x or y are dropped. Ids are 1..N in the order of the objects' first
///     point in the input cloud.
///
/// Non-finite points, points outside the grid and points with |z| > max_abs_z_m are ignored
/// (counted in the stats).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/distance_weight.h"
#include "urban_detection/core/object_detector.h"
#include "urban_detection/core/object_geometry.h"
#include "urban_detection/core/point_types.h"

namespace urban_detection {
namespace core {

/// Parameters of HierarchicalGridDetector, mirrored in config/detection.yaml
/// (`hierarchical_grid:`).
struct HierarchicalGridDetectorParams {
  double coarse_cell_m = 0.60;        // [m] W_S, side of a coarse super-cell (paper: 0.60)
  int xi = 3;                         // [-] sub-cells per super-cell side, 1..8 (paper: 3)
  double grid_half_extent_m = 80.0;   // [m] grid covers [-e, e)^2 around the sensor
  double max_abs_z_m = 50.0;          // [m] points with |z| above this are ignored
  double psi_max_m = 0.8;             // [m] link neighbours when |Zmax(s) - Zmax(r)| <= this
  double dense_min_weighted_points = 6.0;  // [-] sub-cell dense when n * w(d) >= this
  double min_split_height_span_m = 0.3;  // [m] super-cells with Zmax - Zmin below this are
                                         //     "thin" and never split or cut (see step 3)
  double max_split_range_m = 30.0;    // [m] super-cells farther are never split or cut
  int min_gap_subcells = 2;           // [sub-cells] width of a near-empty strip that cuts a
                                      //     link between super-cells (2: 0.4 m)
  bool dense_refinement = true;       // [-] false: objects are the coarse blobs (simple grid)
  int min_points = 5;                 // [-] objects with fewer points are dropped
  double max_extent_m = 20.0;         // [m] objects with a longer xy box side are dropped
  DistanceWeightParams weight;        // distance weight of sub-cell densities (paper Sec. 4)
};

/// Returns "" when `p` is usable, else a message naming the first bad field and its range.
std::string validate(const HierarchicalGridDetectorParams& p);

/// Counters of the last detect() call.
struct HierarchicalGridStats {
  std::size_t input_points = 0;
  std::size_t invalid_points = 0;     // non-finite coordinates
  std::size_t outside_points = 0;     // outside the grid extent or |z| > max_abs_z_m
  std::size_t coarse_cells = 0;       // non-empty super-cells
  std::size_t coarse_blobs = 0;       // connected components at the coarse level
  std::size_t dense_cells = 0;        // non-empty sub-cells
  std::size_t dense_occupied = 0;     // sub-cells with weighted density >= threshold
  std::size_t split_cells = 0;        // super-cells split by an interior near-empty line
  std::size_t noise_points = 0;       // points of isolated near-empty sub-cells
  std::size_t components = 0;         // objects before the size filters
  std::size_t dropped_small = 0;      // components with < min_points points
  std::size_t dropped_large = 0;      // components longer than max_extent_m
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
  int find(std::vector<std::int32_t>* parent, std::int32_t i) const;
  bool linked(std::int32_t coarse_a, std::int32_t coarse_b) const;
  bool computeUnsplittable(std::int32_t coarse) const;  // thin or beyond max_split_range_m
  bool unsplittable(std::int32_t coarse) const { return coarse_unsplittable_[coarse] != 0; }
  int gapBetween(std::int32_t node_a, std::int32_t node_b, int dx, int dy) const;
  bool spansTouch(std::uint64_t part_a, std::uint64_t part_b, int dx, int dy) const;
  void resetGrid();
  void buildMasks();

  struct PartBox {
    std::int8_t min_x, max_x, min_y, max_y;  // dense sub-cells of a part, local coordinates
  };
  struct Separator {
    std::uint64_t line, side_a, side_b;  // interior line of sub-cells and the two sides
  };
  HierarchicalGridDetectorParams params_;
  DistanceWeight weight_;
  ObjectGeometry geometry_;
  HierarchicalGridStats stats_;
  double dense_cell_m_;
  int nd_;  // sub-cells per grid side
  std::uint64_t full_mask_;                // all xi * xi sub-cells
  std::uint64_t facing_[9];                // sub-cells facing neighbour (dx, dy)
  std::uint64_t column_mask_[8], row_mask_[8];
  std::vector<Separator> separators_;      // interior lines, centre first
  int nc_;  // super-cells per grid side
  double origin_m_;  // [m] x and y of the grid's lower corner (a multiple of W_S)

  // Grid -> slot maps (-1 = untouched), reset through the touched slot lists.
  std::vector<std::int32_t> dense_slot_;   // nd_ * nd_
  std::vector<std::int32_t> coarse_slot_;  // nc_ * nc_
  // Per touched sub-cell (slot).
  struct CellXY {
    std::int32_t x, y;
  };
  std::vector<std::int32_t> dense_cell_;    // flat grid index
  std::vector<CellXY> dense_xy_;            // grid column and row
  std::vector<std::uint32_t> dense_count_;  // points
  std::vector<std::int32_t> dense_coarse_;  // slot of its super-cell
  std::vector<std::uint8_t> dense_occupied_;
  std::vector<float> dense_rho_;            // weighted density
  std::vector<float> dense_zmin_, dense_zmax_;  // [m] height range of its points
  std::vector<std::int32_t> dense_object_;  // object index or -1
  // Per touched super-cell (slot).
  std::vector<std::int32_t> coarse_cell_;
  std::vector<float> coarse_zmax_;
  std::vector<float> coarse_zmin_;
  std::vector<std::uint8_t> coarse_unsplittable_;
  std::vector<std::int32_t> coarse_parent_;        // union-find of the coarse level
  std::vector<std::uint64_t> coarse_dense_mask_;   // dense sub-cells (bit ly * xi + lx)
  std::vector<std::uint64_t> coarse_part_mask_;    // 2 per super-cell: sub-cells of part 0, 1
  std::vector<std::int32_t> node_parent_;          // union-find over super-cell parts
  std::vector<PartBox> part_box_;                  // 2 per super-cell
  // Per input point: its sub-cell slot, or -1.
  std::vector<std::int32_t> point_slot_;
  // Per component.
  std::vector<std::int32_t> root_object_;  // per dense slot root -> component index
  std::vector<std::uint32_t> comp_count_;
  std::vector<std::int32_t> comp_box_;     // sub-cell min x, min y, max x, max y per component
  std::vector<std::int32_t> comp_final_;   // component -> output object index or -1
  std::vector<std::uint32_t> positions_;     // cloud positions, grouped by output object
  std::vector<std::uint32_t> object_begin_;  // object k: positions_[begin[k], begin[k + 1])
  std::vector<std::uint32_t> cursor_;
};

}  // namespace core
}  // namespace urban_detection
