/// \file cell_fitness.h
/// Cell fitness value for choosing the grid resolution (paper Sec. 4, "Parameter
/// sensitivity", Fig. 6a). ROS-free.
///
/// The paper's formula is garbled in print ("f = #d / (#d + #s) - #e"); the intent it states is
/// the relative frequency of dense grid cells among the cells "on the screen", in [0, 1]. This
/// implementation uses
///
///     f(W) = #d / (#d + #s + #e)
///
/// for a grid of cell side W aligned with the sensor origin, where a cell is dense with
/// n >= t_min points (t_min = 20, the paper's value), sparse with 1 <= n < t_min points, and
/// the empty cells counted are those 8-adjacent to a non-empty cell: exactly the cells the
/// detector visits in its 3x3 neighbourhood scan around the populated area. Cells far from any
/// point are therefore not counted (they would only measure the size of the screen). Small
/// cells give many sparse cells, large cells a rim of empty cells around every object. On the
/// KITTI foregrounds of ../shared/data/kitti_raw the sparse and rim counts fall faster than the
/// dense count over 0.2-1.5 m, so f rises monotonically there (0.025 at 0.2 m, 0.065 at
/// 0.6 m, 0.118 at 1.5 m; urban_detection_cell_fitness): this formula does not reproduce the
/// paper's maximum near 0.6 m on these data, and the 0.60 m default is the paper's.
#pragma once

#include <cstddef>
#include <vector>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Cell counts of one grid resolution (possibly summed over several frames).
struct CellCounts {
  double cell_m = 0.0;     // [m] grid cell side
  std::size_t dense = 0;   // cells with >= t_min points
  std::size_t sparse = 0;  // cells with 1..t_min-1 points
  std::size_t empty = 0;   // empty cells 8-adjacent to a non-empty cell
  /// f = dense / (dense + sparse + empty), 0 when no cell is counted.
  double fitness() const {
    const std::size_t all = dense + sparse + empty;
    return all ? static_cast<double>(dense) / static_cast<double>(all) : 0.0;
  }
};

/// Counts the cells of a grid of side `cell_m` [m] over the finite points of `cloud` with
/// |x|, |y| < `half_extent_m` [m] (others are ignored), and adds them to `counts`
/// (counts->cell_m is set). `t_min` [points] is the dense threshold.
void countCells(const LabeledCloud& cloud, double cell_m, double half_extent_m, std::size_t t_min,
                CellCounts* counts);

}  // namespace core
}  // namespace urban_detection
