/// \file hough_wall_refiner.h
/// Hough-transform based refinement of the grid segmentation (paper Sec. 3.1, Fig. 3):
/// near the sensor, facade parts below the vertical field of view look like short objects;
/// long straight lines of occupied cells are facades and walls, so short cells on them become
/// tall. ROS-free.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/segment_class.h"

namespace urban_detection {
namespace core {

/// Parameters of the probabilistic Hough refinement. Lengths are in metres and converted to
/// cells with the grid's cell size.
struct HoughWallRefinerParams {
  bool enabled = true;                   // run the refinement at all
  double max_range_m = 20.0;             // [m] only cells within this square half side are
                                         //     rasterised (the misreading happens near the sensor)
  int votes = 8;                         // [cells] accumulator threshold of cv::HoughLinesP
  double min_line_length_m = 6.0;        // [m] shortest accepted line
  double max_line_gap_m = 1.0;           // [m] largest gap bridged within one line
  double theta_resolution_deg = 2.0;     // [deg] angular resolution of the accumulator
  double min_tall_fraction = 0.9;        // [0..1] a run of occupied cells along a line must lie
                                         //     on at least this fraction of wall-supporting cells
                                         //     (tall, or reaching the top of the field of view):
                                         //     rows of parked cars are not walls
  double min_mixed_wall_length_m = 8.0;  // [m] in a run that fails min_tall_fraction, a
                                         //     stretch of wall-supporting cells at least this long
                                         //     (longer than a vehicle) is still a wall: a facade
                                         //     continuing a row of parked cars; 0 disables
  bool extend_lines = true;              // walk each Hough segment across the whole window, so a
                                         //     facade fragment found by Hough recovers the facade
  int line_half_width_cells = 1;         // [cells] relabel short cells up to this far from a line
};

/// HoughWallRefinerParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<HoughWallRefinerParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"enabled", "run the Hough wall refinement"}, p.enabled);
    f({"max_range_m", "m", 1.0, 250.0, "only cells within this square half side are rasterised"},
      p.max_range_m);
    f({"votes", "cells", 1, 10000, "accumulator threshold of cv::HoughLinesP"}, p.votes);
    f({"min_line_length_m", "m", 0.0, 500.0, "shortest accepted line"}, p.min_line_length_m);
    f({"max_line_gap_m", "m", 0.0, 100.0, "largest gap bridged within one line"}, p.max_line_gap_m);
    f({"theta_resolution_deg", "deg", 0.1, 45.0, "angular resolution of the accumulator"},
      p.theta_resolution_deg);
    f({"min_tall_fraction", "", 0.0, 1.0,
       "a line's occupied cells must be at least this fraction wall-supporting"},
      p.min_tall_fraction);
    f({"min_mixed_wall_length_m", "m", 0.0, 500.0,
       "a wall-supporting stretch this long is a wall anyway; 0 = off"},
      p.min_mixed_wall_length_m);
    f({"extend_lines", "walk each Hough segment across the whole window"}, p.extend_lines);
    f({"line_half_width_cells", "cells", 0, 5, "relabel short cells up to this far from a line"},
      p.line_half_width_cells);
  }
};

/// "" when every parameter is in its table range, else why not (outOfRangeMessage()).
std::string validate(const HoughWallRefinerParams& p);

/// Statistics of the last refine() call.
struct HoughWallStats {
  int lines_found = 0;      // lines returned by cv::HoughLinesP
  int lines_accepted = 0;   // lines with at least one accepted wall run
  int cells_relabeled = 0;  // short cells turned tall
};

/// Relabels short cells lying on long straight structures as tall (paper Sec. 3.1).
class HoughWallRefiner {
 public:
  explicit HoughWallRefiner(const HoughWallRefinerParams& params = HoughWallRefinerParams());

  void setParams(const HoughWallRefinerParams& params) { params_ = params; }
  const HoughWallRefinerParams& params() const { return params_; }

  /// `cell_classes` is a row-major rows x cols grid of cell classes (cell size `cell_size_m`,
  /// sensor at the grid centre). Tall and short cells within max_range_m are rasterised into a
  /// binary image, cv::HoughLinesP finds line segments; each segment is split into runs of
  /// occupied cells (gaps up to max_line_gap_m), and kShort cells of runs at least
  /// min_line_length_m long with at least min_tall_fraction wall support become kTall. In a
  /// run that fails the support test, stretches of wall-supporting cells (same gaps, same
  /// fraction) at least min_mixed_wall_length_m long become kTall too.
  /// Only kShort -> kTall changes are made.
  HoughWallStats refine(int rows, int cols, double cell_size_m,
                        std::vector<SegmentClass>* cell_classes);
  /// As above; `wall_support` (same layout, may be null) marks further cells that count as
  /// wall evidence for min_tall_fraction besides the tall ones (e.g. short cells whose top
  /// reaches the upper edge of the sensor's field of view, so their true height is unknown).
  HoughWallStats refine(int rows, int cols, double cell_size_m,
                        std::vector<SegmentClass>* cell_classes,
                        const std::vector<std::uint8_t>* wall_support);

  /// Line segments accepted by the last refine() call, as (x0, y0, x1, y1) in cell
  /// coordinates of the full grid (col, row).
  const std::vector<cv::Vec4i>& acceptedLines() const { return accepted_; }
  /// Row-major indices of the cells the last refine() call turned from kShort into kTall.
  const std::vector<std::int32_t>& relabeledCells() const { return relabeled_; }

 private:
  HoughWallRefinerParams params_;
  cv::Mat image_;                 // scratch: binary occupancy image of the Hough window
  std::vector<cv::Vec4i> lines_;  // scratch: raw Hough output
  std::vector<cv::Vec4i> accepted_;
  std::vector<std::int32_t> relabeled_;
  struct LinePixel {
    int col, row;   // full-grid cell coordinates
    bool occupied;  // a tall or short cell within the half width
    bool support;   // a tall or wall-supporting cell within the half width
  };
  std::vector<LinePixel> line_px_;  // scratch: pixels of the segment being examined
};

}  // namespace core
}  // namespace urban_detection
