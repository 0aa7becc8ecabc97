#include "urban_detection/core/detection/cell_fitness.h"

#include <cmath>
#include <cstdint>

namespace urban_detection {
namespace core {

void countCells(const LabeledCloud& cloud, double cell_m, double half_extent_m, std::size_t t_min,
                CellCounts* counts) {
  counts->cell_m = cell_m;
  if (!(cell_m > 0.0) || !(half_extent_m > 0.0)) return;
  // One cell of margin on each side so the empty rim of border cells is always inside.
  const long side = static_cast<long>(std::ceil(2.0 * half_extent_m / cell_m)) + 2;
  if (side > 20000) return;  // an offline tool; refuse absurd grids rather than exhaust memory
  std::vector<std::uint32_t> n(static_cast<std::size_t>(side * side), 0);
  std::vector<std::size_t> touched;
  for (const LabeledPoint& p : cloud.points) {
    if (!(std::fabs(p.x) < half_extent_m) || !(std::fabs(p.y) < half_extent_m) ||
        !std::isfinite(p.z)) {
      continue;  // NaN fails the comparisons
    }
    const long ix = static_cast<long>(std::floor(p.x / cell_m)) +
                    static_cast<long>(std::ceil(half_extent_m / cell_m)) + 1;
    const long iy = static_cast<long>(std::floor(p.y / cell_m)) +
                    static_cast<long>(std::ceil(half_extent_m / cell_m)) + 1;
    if (ix < 1 || iy < 1 || ix >= side - 1 || iy >= side - 1) continue;
    const std::size_t c = static_cast<std::size_t>(iy * side + ix);
    if (n[c]++ == 0) touched.push_back(c);
  }
  std::vector<std::uint8_t> rim(n.size(), 0);
  for (const std::size_t c : touched) {
    (n[c] >= t_min ? counts->dense : counts->sparse) += 1;
    for (long dy = -1; dy <= 1; ++dy) {
      for (long dx = -1; dx <= 1; ++dx) {
        const std::size_t r = static_cast<std::size_t>(static_cast<long>(c) + dy * side + dx);
        if (n[r] == 0 && !rim[r]) {
          rim[r] = 1;
          ++counts->empty;
        }
      }
    }
  }
}

}  // namespace core
}  // namespace urban_detection
