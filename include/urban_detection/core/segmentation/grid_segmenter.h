/// \file grid_segmenter.h
/// Point cloud segmentation with the simple grid model (paper Sec. 3.1): ground, tall
/// structures, short street objects and clutter, with a locally adaptive terrain model and the
/// Hough wall refinement. ROS-free.
///
/// Algorithm (one call, GridSegmenter::segment):
///  1. Grid the points (SimpleGrid); heights are referenced to the ground below the sensor.
///  2. Clutter: cells with fewer than min_points_per_cell points.
///  3. Local terrain: a cell is a ground candidate when its height spread is below
///     ground_max_range_m. Candidates near the sensor whose elevation is close to 0 seed a
///     region growing over neighbouring candidates whose elevation differs by less than
///     ground_max_step_m per cell, so slopes, camber and curbs stay connected to the road while
///     car roofs and walls do not. Cells with both ground and object returns (a car over road)
///     join via their lowest point; the growing crosses empty and sparse cells for up to
///     ground_max_gap_m (the rings of a Velodyne are metres apart at range). Cells the growing
///     did not reach get the mean ground elevation of the nearest ring of reached cells
///     (terrain_fill_iterations cells at most).
///  4. Cell classes against the local ground g: tall when z_max - g > tall_min_height_m or
///     z_max - z_min > tall_min_range_m; ground when all points lie within ground_tolerance_m
///     of g, or (curb_cells_ground) when it holds a curb: its z range and all its points within
///     ground_max_step_m of g and its top the ground of a reached neighbour (a flat cell's g
///     is its mean, between road and sidewalk); short otherwise.
///  4b. Long vehicles (ours): tall cells whose top is at most vehicle_max_height_m above the
///     ground (and z range at most that) and short cells form 8-connected groups; the tall
///     cells of a group that touches no other tall cell, fits an oriented box of
///     vehicle_max_length_m x vehicle_max_width_m (extents measured along 8 directions,
///     22.5 deg apart) and at most half of whose tall cells reach the upper edge of the field
///     of view (fov_top_elevation_deg: their true height is unknown; counted only beyond
///     the Hough window for groups at least 3.5 m long unless vehicle_fov_test_near, as
///     step 5 turns a facade's cells inside it back to tall) become short: a truck, bus
///     or van, not a wall, hedge or facade, which are longer, higher, joined to higher
///     structure or cut by the field of view.
///  5. HoughWallRefiner turns short cells on long straight walls into tall.
///  5b. Overhangs (ours): in a cell that is tall by its top (z_max - g > tall_min_height_m)
///     after step 4b (a cell step 5 turns back to tall is a wall and not one of them),
///     has a terrain estimate and whose centre is within overhang_max_range_m, the heights
///     of its non-ground points above g + ground_tolerance_m are binned (64 bins of 0.125 m,
///     the last one open); going up from the lowest bin, the first run of empty bins at least
///     overhang_min_gap_m deep ends the lower part. When the lower part's top (the upper edge
///     of its highest bin, plus the tolerance) is at least overhang_min_height_m and at most
///     tall_min_height_m above g, its points
///     are short and the points above the run tall: a person, a car or a bin under a tree
///     canopy, a balcony or an awning is not a tall structure. Without such a gap, when the
///     points more than tall_min_height_m above g fit in an xy box at most thin_max_width_m
///     on each side (a pole, a sign post, a trunk), the points up to that height lying more
///     than kThinMargin_m (0.1 m: a wider foot) outside that box are short: a person beside a
///     pole. The cell's class stays tall.
///  6. Per point: in ground-bearing cells a point within ground_tolerance_m of g is ground, the
///     others take the cell class (mixed cells are split per point). Sparse (clutter) cells of
///     far road get the same per-point test against the filled terrain when
///     ground_in_sparse_cells is set.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/common/segment_class.h"
#include "urban_detection/core/segmentation/hough_wall_refiner.h"
#include "urban_detection/core/segmentation/simple_grid.h"

namespace urban_detection {
namespace core {

/// Every threshold of the segmentation; config/segmentation.yaml mirrors it field by field.
struct GridSegmenterParams {
  double sensor_height_m = 1.73;       // [m] sensor height above the road (KITTI: 1.73)
  double cell_size_m = 0.5;            // [m] W_S, side of a simple-grid cell
  double max_range_m = 80.0;           // [m] half side of the grid; farther points: kUnknown
  double max_abs_height_m = 50.0;      // [m] points farther than this from the ground plane
                                       //     (|z + sensor_height_m|) are kUnknown
  int min_points_per_cell = 3;         // [points] fewer -> clutter (paper: 4-8; 3 keeps far
                                       //     cyclists on SemanticKITTI)
  bool ground_in_sparse_cells = true;  // points of a clutter cell lying within
                                       //     ground_tolerance_m of the terrain filled in from
                                       //     neighbouring ground cells are ground (far road)
  double ground_max_range_m = 0.25;    // [m] z_max - z_min below this: ground candidate (paper)
  double ground_tolerance_m = 0.08;    // [m] a point this close above the local ground is ground
  double ground_max_step_m = 0.20;     // [m] elevation step allowed between neighbouring ground
                                       //     cells (curbs, slopes)
  bool curb_cells_ground = false;      // a reached cell whose points span less than
                                       //     ground_max_step_m, lie within it of the local
                                       //     ground and whose top is the ground of a reached
                                       //     neighbour is ground (a curb inside the cell). Off:
                                       //     it lowers SemanticKITTI's held-out F (see
                                       //     docs/measurements.md, 2026-12-05)
  double ground_max_gap_m = 2.0;       // [m] the terrain growing crosses empty or sparse cells
                                       //     over at most this distance (gaps between far rings)
  double seed_radius_m = 12.0;         // [m] ground growing starts from candidates this close
  double seed_max_abs_height_m = 0.4;  // [m] ... whose elevation is within this of z = 0
  int terrain_fill_iterations = 6;     // [cells] search radius for the terrain of cells the
                                       //     growing did not reach
  double terrain_max_offset_m = 0.35;  // [m] a flat cell the growing did not reach is ground when
                                       //     its mean is this close to the filled terrain
  double tall_min_height_m = 2.00;     // [m] z_max above local ground beyond this: tall (paper:
                                       //     1.40, which makes standing people (1.7-1.9 m) tall
                                       //     when heights are taken above the local ground)
  double tall_min_range_m = 3.10;      // [m] z_max - z_min beyond this: tall (paper)
  double vehicle_max_height_m = 4.0;   // [m] 0 = off; a tall cell whose top above the local
                                       //     ground and whose z range are at most this is short
                                       //     when the 8-connected group of such cells it is in
                                       //     fits a vehicle box (trucks, buses, vans: 2-4 m)
  double vehicle_max_length_m = 13.0;  // [m] ... that box's longer side at most this (a bus)
  double vehicle_max_width_m = 3.5;    // [m] ... and its shorter side at most this
  bool vehicle_fov_test_near = true;   // the field-of-view test of step 4b also inside the
                                       //     Hough window; false: only beyond it, since inside
                                       //     it the Hough refinement turns a facade's cells
                                       //     back to tall (a van seen to the upper edge of the
                                       //     field of view, within ~20 m, is short)
  double overhang_min_gap_m = 0.0;     // [m] 0 = off (shipped off for its run time, see
                                       //     docs/design.md; 0.6 when on); a tall
                                       //     cell whose heights above the
                                       //     local ground leave an empty band at least this
                                       //     deep, with at most tall_min_height_m below it,
                                       //     holds a short object under an overhang (a person
                                       //     under a canopy): the points below the band are
                                       //     short, those above it tall
  double overhang_min_height_m = 1.2;  // [m] ... and whose lower part reaches at least this
                                       //     high (a person, a cyclist, a car; not the wall
                                       //     under a window band, whose sill is at ~0.9 m)
  double overhang_max_range_m = 40.0;  // [m] ... for cells this close to the sensor (the rings
                                       //     that see above the road beyond ~12 m, 1/3 deg
                                       //     apart, lie <= 0.25 m apart there: an empty 0.6 m
                                       //     band is not a gap between two rings)
  double thin_max_width_m = 0.0;       // [m] 0 = off (shipped off, as step 5b's overhangs;
                                       //     0.3 when on); a tall cell of step 5b without an
                                       //     overhang whose points above tall_min_height_m fit
                                       //     in an xy box this wide holds a thin upright (a
                                       //     pole, a post, a trunk): its points up to that
                                       //     height more than 0.1 m outside the box
                                       //     are short (a person beside a pole)
  double fov_top_elevation_deg = 1.0;  // [deg] a cell whose highest point is seen at this
                                       //     elevation or more may extend above the vertical
                                       //     field of view (HDL-64E: +2 deg); it supports Hough
                                       //     wall lines like a tall cell
  HoughWallRefinerParams hough;        // Hough wall refinement (paper Fig. 3)
};

/// GridSegmenterParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<GridSegmenterParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"sensor_height_m", "m", -10.0, 10.0, "sensor height above the road"}, p.sensor_height_m);
    f({"cell_size_m", "m", 0.05, 5.0, "W_S, side of a simple-grid cell"}, p.cell_size_m);
    f({"max_range_m", "m", 1.0, 250.0, "half side of the grid; farther points are unknown"},
      p.max_range_m);
    f({"max_abs_height_m", "m", 1.0, 1000.0,
       "points farther than this from the ground plane are unknown"},
      p.max_abs_height_m);
    f({"min_points_per_cell", "points", 1, 1000, "fewer points: clutter"}, p.min_points_per_cell);
    f({"ground_in_sparse_cells",
       "points of a clutter cell close to the terrain filled in from ground neighbours are ground"},
      p.ground_in_sparse_cells);
    f({"ground_max_range_m", "m", 0.01, 2.0, "z range below this: ground candidate"},
      p.ground_max_range_m);
    f({"ground_tolerance_m", "m", 0.0, 2.0, "a point this close above the local ground is ground"},
      p.ground_tolerance_m);
    f({"ground_max_step_m", "m", 0.0, 2.0, "elevation step allowed between ground cells"},
      p.ground_max_step_m);
    f({"curb_cells_ground", "a low cell reaching a ground neighbour's top is ground (a curb)"},
      p.curb_cells_ground);
    f({"ground_max_gap_m", "m", 0.0, 20.0, "terrain growing crosses empty cells over this much"},
      p.ground_max_gap_m);
    f({"seed_radius_m", "m", 0.0, 250.0, "ground growing starts from candidates this close"},
      p.seed_radius_m);
    f({"seed_max_abs_height_m", "m", 0.0, 5.0, "... whose elevation is within this of z = 0"},
      p.seed_max_abs_height_m);
    f({"terrain_fill_iterations", "cells", 0, 100,
       "search radius for the terrain of cells the growing did not reach"},
      p.terrain_fill_iterations);
    f({"terrain_max_offset_m", "m", 0.0, 5.0,
       "an unreached flat cell this close to the filled terrain is ground"},
      p.terrain_max_offset_m);
    f({"tall_min_height_m", "m", 0.1, 20.0, "top above the local ground beyond this: tall"},
      p.tall_min_height_m);
    f({"tall_min_range_m", "m", 0.1, 50.0, "z range beyond this: tall"}, p.tall_min_range_m);
    f({"vehicle_max_height_m", "m", 0.0, 20.0,
       "tall cells up to this high forming a vehicle-sized group are short; 0 = off"},
      p.vehicle_max_height_m);
    f({"vehicle_max_length_m", "m", 0.5, 100.0, "... that group's longer side at most this"},
      p.vehicle_max_length_m);
    f({"vehicle_max_width_m", "m", 0.5, 100.0, "... and its shorter side at most this"},
      p.vehicle_max_width_m);
    f({"vehicle_fov_test_near",
       "the vehicle group's field-of-view test also inside the Hough window"},
      p.vehicle_fov_test_near);
    f({"overhang_min_gap_m", "m", 0.0, 8.0,
       "an empty height band this deep over a short object in a tall cell: overhang; 0 = off"},
      p.overhang_min_gap_m);
    f({"overhang_min_height_m", "m", 0.0, 20.0, "... over an object at least this high"},
      p.overhang_min_height_m);
    f({"overhang_max_range_m", "m", 0.0, 250.0, "... in cells this close to the sensor"},
      p.overhang_max_range_m);
    f({"thin_max_width_m", "m", 0.0, 5.0,
       "points beside a thin upright (its top part this wide) in a tall cell are short; 0 = off"},
      p.thin_max_width_m);
    f({"fov_top_elevation_deg", "deg", -30.0, 30.0,
       "a cell seen at this elevation or more may pass the top of the field of view"},
      p.fov_top_elevation_deg);
    forEachField(p.hough, "hough", f);
  }
};

/// "" when every parameter is in its table range, else why not (outOfRangeMessage()).
std::string validate(const GridSegmenterParams& p);

/// The vehicle-group test's size of a group of grid cells, in cells: its largest (`length`) and
/// smallest (`width`) extent plus one along 8 directions 22.5 deg apart.
void cellGroupExtent(const SimpleGrid& grid, const std::vector<std::int32_t>& cells, float* length,
                     float* width);

/// Statistics of the last segment() call (points and cells per class).
struct SegmentationStats {
  std::uint32_t points_unknown = 0, points_clutter = 0, points_ground = 0, points_tall = 0,
                points_short = 0;
  /// Of the unknown points, those with a NaN or infinite coordinate.
  std::uint32_t points_non_finite = 0;
  std::uint32_t cells_occupied = 0, cells_ground_reached = 0;
  HoughWallStats hough;
};

/// The simple-grid segmenter. Holds its grid and scratch buffers between frames.
class GridSegmenter {
 public:
  explicit GridSegmenter(const GridSegmenterParams& params = GridSegmenterParams());

  /// Replaces the parameters (rebuilds the grid if its geometry changed).
  void setParams(const GridSegmenterParams& params);
  const GridSegmenterParams& params() const { return params_; }

  /// Labels every point of `cloud`: labels->size() == cloud.size() afterwards. Non-finite,
  /// out-of-range and absurd points get kUnknown. Accepts clouds whose ring/time are zero.
  void segment(const CloudXYZIRT& cloud, std::vector<SegmentClass>* labels);

  /// Streaming: bins the next `count` points of the revolution whose cloud will carry
  /// header.seq == `revolution` into the grid while the revolution arrives (the first call
  /// with a new `revolution` starts it over), so that segment() of that cloud only bins the
  /// points not added yet. segment() checks that the points added are the cloud's first ones
  /// (same count bound, the first point of every batch and the last one bit for bit) and
  /// bins the whole cloud afresh when they are not (a lost batch); its labels are those of
  /// segment() without streaming in every case. A batch whose first point's `time` is below
  /// the previous batch's first point's (batches begin at packets, in order) also starts over:
  /// the decoder gives a dropped partial revolution's seq again to the next one.
  void addPoints(std::uint32_t revolution, const PointXYZIRT* points, std::size_t count);
  /// segment() of the points added by addPoints() so far (`cloud`: exactly those points),
  /// leaving the stream open: later addPoints() of the same revolution go on binning, so a
  /// revolution segmented after each of its sectors is binned once. Same labels as
  /// segment(cloud); when `cloud` is not the stream so far, it is segment(cloud).
  void segmentSoFar(const CloudXYZIRT& cloud, std::vector<SegmentClass>* labels);
  /// Ends the stream: the next addPoints() starts a revolution over.
  void restartStream() { streaming_ = false; }
  /// Whether the last segment() used the points added by addPoints() (false: it binned the
  /// whole cloud, none were added or they did not match).
  bool lastUsedStream() const { return last_used_stream_; }

  const SegmentationStats& stats() const { return stats_; }
  /// The grid of the last frame, and its per-cell classes (row-major, after Hough).
  const SimpleGrid& grid() const { return grid_; }
  const std::vector<SegmentClass>& cellClasses() const { return cell_class_; }
  /// Per cell of the last segment() call: 1 where the Hough refiner counts the cell as wall
  /// evidence besides tall cells (its top at the upper edge of the field of view).
  const std::vector<std::uint8_t>& wallSupport() const { return wall_support_; }
  /// Local ground elevation [m] of each cell of the last frame (valid where cellHasGround()).
  float cellGround(std::int32_t cell) const { return ground_z_[cell]; }
  bool cellHasGround(std::int32_t cell) const { return ground_state_[cell] != kNoGround; }
  const HoughWallRefiner& houghRefiner() const { return hough_; }

 private:
  enum GroundState : std::uint8_t { kNoGround = 0, kReached = 1, kFilled = 2, kBridged = 3 };
  enum DenseState : std::uint8_t { kEmptyOrSparse = 0, kDense = 1, kDenseFlat = 2 };
  // An entry of the terrain growing's queue: the cell, its row, the ground height it carries
  // and the empty cells crossed to reach it (0 for an occupied cell).
  struct QueueEntry {
    std::int32_t cell;
    float ground_z;  // [m]
    std::int32_t row;
    std::int32_t hops;
  };
  // Clears the per-cell scratch the previous frame set (idempotent).
  void resetScratch();
  // Everything after the binning (the grid is complete for `cloud`).
  void segmentBinned(const CloudXYZIRT& cloud, std::vector<SegmentClass>* labels);
  // Whether the points added by addPoints() are the first points of `cloud`.
  bool streamMatches(const CloudXYZIRT& cloud) const;
  void growGround();
  void fillTerrain();
  void classifyCells();
  void shortenVehicles();
  // Step 5b on the per-point labels (pending points of candidate slots); returns the points
  // made short and adds them to counts[kShort], the others to counts[kTall].
  void resolveOverhangs(const CloudXYZIRT& cloud, std::uint8_t* labels, std::uint32_t* counts);

  GridSegmenterParams params_;
  SimpleGrid grid_;
  // Streaming (addPoints): the revolution being binned, and per batch its first point's
  // position and the point itself (checked against the cloud in segment()).
  bool streaming_ = false;
  std::uint32_t stream_revolution_ = 0;
  std::vector<std::pair<std::size_t, PointXYZIRT>> stream_checks_;
  float stream_batch_time_ = 0.0f;  // [s] time of the last batch's first point
  bool last_used_stream_ = false;
  bool stream_segmented_ = false;  // a segmentSoFar() of the stream set the scratch
  HoughWallRefiner hough_;
  SegmentationStats stats_;
  // Scratch, sized to the grid, reset only on the cells touched by the previous frame.
  std::vector<SegmentClass> cell_class_;
  std::vector<std::uint8_t> wall_support_;  // cell top at the upper edge of the field of view
  std::vector<float> ground_z_;             // [m] local ground elevation per cell
  std::vector<std::uint8_t> ground_state_;
  // shortenVehicles: per cell, a tall cell low enough for a vehicle (candidate), grouped, or a
  // short cell of a group.
  enum VehicleState : std::uint8_t {
    kVehicleNone = 0,
    kVehicleCandidate = 1,
    kVehicleGrouped = 2,
    kVehicleShort = 3
  };
  std::vector<std::uint8_t> vehicle_state_;  // VehicleState per cell
  std::vector<std::int32_t> vehicle_cells_;  // the vehicle-high tall cells, in slot order
  std::vector<std::int32_t> vehicle_group_;  // scratch: one group's cells (breadth first)
  std::vector<std::uint8_t> dense_;          // DenseState: min_points_per_cell points or more, flat
  std::vector<float> slot_elev_;             // [m] per slot: mean (flat cell) or lowest point
  std::vector<QueueEntry> grow_queue_;       // numCells() entries: each cell is queued at most once
  std::vector<std::int32_t> touched_;        // numCells() entries; the first touched_count_ are the
  std::size_t touched_count_ = 0;            //     cells whose ground state was set this frame
  std::vector<std::int32_t> fill_cells_;     // cells given a filled terrain this frame
  std::vector<float> fill_z_;                // [m] their terrain, applied after the search
  static constexpr int kMaxBitRing = 28;     // fillTerrain's bit windows: 2 * 28 + 1 bits
  std::vector<std::uint64_t> terrain_bits_;  // per row: bit k+64 = cell k has terrain (cleared)
  std::size_t bit_words_ = 0;                // 64-bit words per row of terrain_bits_
  std::vector<std::uint64_t> terrain_near_;  // terrain_bits_ ORed over the rows within
                                             //     terrain_fill_iterations (overwritten)
  std::vector<std::uint64_t> near_fwd_, near_bwd_;  // scratch of terrain_near_: block-wise ORs
  std::vector<std::uint64_t> zero_row_;             // one row of zero words (outside the grid)
  // Per slot + 1 (entry 0: points without a cell) for the per-point pass: points below
  // split_z [m] are ground, the others get `label` (a SegmentClass). Filled by
  // classifyCells, then the cells the Hough refiner turned tall are patched.
  struct SlotLabel {
    float split_z;
    std::uint32_t label;
  };
  std::vector<SlotLabel> slot_label_;
  // Step 5b: the slots of the candidate cells, and per slot + 1 their height-bin mask and the
  // height above split_z [m] below which a point is short (-inf: none).
  std::vector<std::int32_t> overhang_slots_;
  std::vector<std::uint64_t> overhang_mask_;
  std::vector<std::uint64_t> overhang_upper_mask_;  // the bins above tall_min_height_m
  std::vector<float> overhang_cut_;
  // ... and the xy box [m] of their points above tall_min_height_m (min x, min y, max x, max y),
  // then widened by the margin.
  std::vector<float> overhang_box_;
  std::vector<std::uint8_t> overhang_upright_;  // per slot + 1: the cell holds a thin upright
};

/// Builds the foreground cloud of the detectors: only the finite kShort points, label =
/// kShort, index = position of the point in `cloud`. `foreground` is cleared and filled; its
/// header is copied from `cloud`.
void extractForeground(const CloudXYZIRT& cloud, const std::vector<SegmentClass>& labels,
                       LabeledCloud* foreground);

/// Builds the labelled cloud: every point of `cloud` (non-finite ones included, label
/// kUnknown), label = SegmentClass value, index = position in `cloud`.
void buildLabeledCloud(const CloudXYZIRT& cloud, const std::vector<SegmentClass>& labels,
                       LabeledCloud* labeled);

}  // namespace core
}  // namespace urban_detection
