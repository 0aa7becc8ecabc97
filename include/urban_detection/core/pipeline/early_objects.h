/// \file early_objects.h
/// Early objects: which objects of a partly swept revolution are already final. ROS-free.
///
/// While a revolution arrives sector by sector, Pipeline::addSector() runs the chain on the
/// points so far; SectorCompletion decides which of the objects found are finished, i.e. will
/// be the same (same points, hence same class and box) when the whole revolution is in:
///
///  - The sweep: the azimuth of the revolution's first points is the seam, the azimuth of the
///    last points added is the front, and the rotation sense is the one the front moved in.
///    A segmentation cell is *closed* when its whole azimuth span, widened on each side by
///    margin_m (seen at the cell's range) and angle_margin_deg, lies between the seam and the
///    front: no later point of the revolution can fall into it, nor within margin_m of it.
///    margin_m covers the segmentation's local reach (terrain fill, ground growing across gaps)
///    and the detector's links (radial and roof bridges, the far-object merger).
///  - The group an object sits in: its cells' 8-connected component over short cells and
///    the tall cells low enough to be a vehicle candidate (top above the local ground and z
///    range within max(vehicle_max_height_m, tall_min_height_m / tall_min_range_m)). Every
///    neighbour rule of the segmentation's cell classes stays inside it and its ring of
///    neighbours: the vehicle groups (8-connected over candidates and short cells, "touches a
///    higher tall cell"), the curb rule. An object is final when all of it is closed, or
///    when it cannot become a vehicle whatever is added (groupDoomed).
///  - The Hough refinement is global over the revolution (cv::HoughLinesP votes over the whole
///    window, in a random order seeded per call, and extend_lines walks a line across the
///    window), so a line found at the end may cross an early sector. A run only relabels cells
///    when it is at least hough/min_line_length_m long, and its occupied cells are linked
///    within link = floor(max_line_gap_m / cell) + 1 + 2 * line_half_width_cells cells
///    (Chebyshev; consecutive occupied pixels of a run are at most the gap apart, each within
///    the half width of an occupied cell). So for every occupied cell in the window (widened
///    by the half width) within the detector's reach of the object (a neighbour made tall
///    may join or split it): its component over tall and short cells linked within `link`
///    must be closed and either too small to hold such a run (box diagonal plus the half
///    width at both ends) or without the wall support a relabelling run needs (its supporting
///    cells span too few rows and columns, see minSupportExtent); otherwise the object waits
///    for the seam.
///  - The ground growing is seeded near the sensor over the whole revolution; the margin keeps
///    an early cell's terrain away from later points, and Pipeline::finishRevolution() checks
///    every early object against the classic result (PipelineResult::early_mismatches).
///
/// Objects that are not final wait for the seam: finishRevolution() runs the classic chain on
/// the whole revolution and hands on the objects not given early.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace core {

/// Parameters of the early-objects mode (Pipeline::addSector).
struct EarlyObjectsParams {
  double margin_m = 3.0;          // [m] a closed cell is this far from any later point
  double angle_margin_deg = 4.0;  // [deg] further azimuth margin (laser azimuth offsets)
  int front_points = 256;         // [points] the front (and the seam) is the median azimuth of
                                  //     this many last (first) points
};

/// EarlyObjectsParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<EarlyObjectsParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"margin_m", "m", 0.0, 100.0, "an early object's structure is this far from later points"},
      p.margin_m);
    f({"angle_margin_deg", "deg", 0.0, 90.0,
       "further azimuth margin to the sweep's front and seam"},
      p.angle_margin_deg);
    f({"front_points", "points", 1, 100000,
       "the sweep's front (seam) is the median azimuth of this many last (first) points"},
      p.front_points);
  }
};

/// "" when every parameter is in its table range, else why not.
std::string validate(const EarlyObjectsParams& p);

/// Which objects of a partly swept revolution are final (see the file comment).
class SectorCompletion {
 public:
  explicit SectorCompletion(const EarlyObjectsParams& params = EarlyObjectsParams());

  /// The sweep of `cloud` (the revolution's points so far, in time order). False when it
  /// cannot be told yet (too few finite points, no rotation seen): then nothing is final.
  bool updateSweep(const CloudXYZIRT& cloud);
  /// Radians swept from the seam to the front by the last updateSweep().
  double sweptRad() const { return swept_rad_; }

  /// Marks final[k] = 1 for every object of `objects` (found on `cloud`, segmented by
  /// `segmenter`) that is final, 0 otherwise. updateSweep(cloud) first.
  void finalObjects(const CloudXYZIRT& cloud, const GridSegmenter& segmenter,
                    const std::vector<DetectedObject>& objects, std::vector<std::uint8_t>* final);

  /// Of the objects of the last finalObjects() call: not final because their component
  /// reaches an open cell, or (closed) because it could hold a Hough wall run.
  std::size_t lastOpen() const { return last_open_; }
  std::size_t lastHough() const { return last_hough_; }

  /// Whether a cell is closed in the last sweep.
  bool cellClosed(const SimpleGrid& grid, std::int32_t cell) const;

 private:
  // Empties the component, stack and marks and starts them at `seed`.
  void startGrowing(std::int32_t seed);
  // Depth first from `seed` over the cells within Chebyshev `link`: tall and short cells
  // (occupied_only) or groupable ones; fills component_ and its box (rmin_ ...); true when all
  // of them are closed.
  bool grow(const GridSegmenter& segmenter, std::int32_t seed, int link, bool occupied_only);
  // A short cell, or a tall one low enough to be a vehicle candidate (or a short cell the
  // Hough refinement made tall).
  bool groupable(const GridSegmenter& segmenter, std::int32_t c) const;
  // A cell whose class a vehicle group may change: a groupable tall cell, or a short cell
  // with a tall cell's statistics (a candidate made short).
  bool flippable(const GridSegmenter& segmenter, std::int32_t c) const;
  // Memoised per call: 1 the cell's 8-connected group is closed, 2 not.
  std::uint8_t groupState(const GridSegmenter& segmenter, std::int32_t seed);
  // Memoised per call: 1 the cell's Hough component is closed and holds no run, 2 not.
  std::uint8_t houghState(const GridSegmenter& segmenter, std::int32_t seed);
  // Whether the vehicle group of `seed` surely fails the vehicle test whatever the rest of the
  // revolution adds (its closed part is already too long or wide, or touches a higher tall
  // cell): then none of its cells changes class. Memoised per call.
  bool groupDoomed(const GridSegmenter& segmenter, std::int32_t seed);
  // Rows or columns (the larger extent) spanned by component_'s supporting cells (tall,
  // wall-supporting short, or flippable) dilated by `w`; 0 when none.
  std::size_t supportExtent(const GridSegmenter& segmenter, int w) const;
  // The least extent of supporting pixels a relabelling Hough run has (see the .cpp).
  static double minSupportExtent(const HoughWallRefinerParams& hp, double cell_m, int w);

  EarlyObjectsParams params_;
  bool sweep_valid_ = false;
  double seam_rad_ = 0.0;   // azimuth of the seam
  double sense_ = 1.0;      // +1: azimuth grows with time, -1: it falls
  double swept_rad_ = 0.0;  // [rad] from the seam to the front, in the rotation sense
  std::vector<float> scratch_az_;
  // Per cell: the states of the current call (0 unknown), reset on touched_ only.
  std::vector<std::uint8_t> group_state_, hough_state_;
  std::vector<std::uint8_t> doomed_state_;  // 1 doomed, 2 not (reset on doomed_touched_)
  std::vector<std::int32_t> doomed_touched_;
  std::vector<std::int32_t> cells_;  // scratch: one object's cells
  int rmin_ = 0, rmax_ = 0, cmin_ = 0, cmax_ = 0;
  std::vector<std::int32_t> touched_;
  std::vector<std::uint8_t> mark_;  // per cell: visited by the current search (reset on marked_)
  std::vector<std::int32_t> marked_;
  std::vector<std::int32_t> stack_;
  std::vector<std::int32_t> component_;
  std::size_t last_open_ = 0, last_hough_ = 0;
};

}  // namespace core
}  // namespace urban_detection
