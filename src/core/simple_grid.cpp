#include "urban_detection/core/simple_grid.h"

#include <algorithm>
#include <cmath>

namespace urban_detection {
namespace core {

SimpleGrid::SimpleGrid(const SimpleGridParams& params) : params_(params) {
  // Guard against nonsense here too: callers validate, but a core class must not allocate
  // a multi-gigabyte grid or divide by zero on a bad value.
  const double cell = std::max(params_.cell_size_m, 0.01);
  const double range = std::clamp(params_.max_range_m, cell, 1000.0);
  params_.cell_size_m = cell;
  params_.max_range_m = range;
  side_ = std::max(1, static_cast<int>(std::ceil(2.0 * range / cell)));
  inv_cell_ = static_cast<float>(1.0 / cell);
  origin_m_ = static_cast<float>(-0.5 * side_ * cell);
  cells_.assign(static_cast<std::size_t>(side_) * side_, GridCell());
}

std::int32_t SimpleGrid::cellAt(float x_m, float y_m) const {
  // Written so that NaN fails the comparisons and lands in kNoCell.
  const float fc = (x_m - origin_m_) * inv_cell_;
  const float fr = (y_m - origin_m_) * inv_cell_;
  if (!(fc >= 0.0f && fc < static_cast<float>(side_) && fr >= 0.0f &&
        fr < static_cast<float>(side_))) {
    return kNoCell;
  }
  return static_cast<std::int32_t>(fr) * side_ + static_cast<std::int32_t>(fc);
}

void SimpleGrid::cellCenter(std::int32_t index, float* x_m, float* y_m) const {
  const float cell = static_cast<float>(params_.cell_size_m);
  *x_m = origin_m_ + (static_cast<float>(colOf(index)) + 0.5f) * cell;
  *y_m = origin_m_ + (static_cast<float>(rowOf(index)) + 0.5f) * cell;
}

void SimpleGrid::build(const CloudXYZIRT& cloud, float z_offset_m, float max_abs_height_m) {
  for (const std::int32_t c : occupied_) cells_[c] = GridCell();
  occupied_.clear();
  const std::size_t n = cloud.size();
  point_cell_.resize(n);
  point_z_.resize(n);
  const float range = static_cast<float>(params_.max_range_m);
  for (std::size_t i = 0; i < n; ++i) {
    const PointXYZIRT& p = cloud[i];
    const float z = p.z + z_offset_m;
    // The range test also rejects NaN/inf (comparisons with NaN are false).
    if (!(std::fabs(p.x) < range && std::fabs(p.y) < range && std::fabs(z) <= max_abs_height_m)) {
      point_cell_[i] = kNoCell;
      point_z_[i] = 0.0f;
      continue;
    }
    const std::int32_t c = cellAt(p.x, p.y);
    point_cell_[i] = c;
    point_z_[i] = z;
    if (c == kNoCell) continue;
    GridCell& cell = cells_[c];
    if (cell.count == 0) occupied_.push_back(c);
    ++cell.count;
    cell.z_min = std::min(cell.z_min, z);
    cell.z_max = std::max(cell.z_max, z);
    cell.z_sum += z;
  }
}

}  // namespace core
}  // namespace urban_detection
