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
  // Hot loop (once per point per revolution): everything inline, one bounds test that also
  // rejects NaN (comparisons with NaN are false) and inf/1e30 (outside the grid). Consecutive
  // returns of a laser mostly fall in the same cell (~1 cm apart at 10 m), so statistics are
  // accumulated in registers over such runs and written once per run instead of a
  // read-modify-write chain through memory per point.
  const float org = origin_m_, inv = inv_cell_, side_f = static_cast<float>(side_);
  const int side = side_;
  GridCell* cells = cells_.data();
  std::int32_t* pc = point_cell_.data();
  float* pz = point_z_.data();
  std::int32_t run_cell = kNoCell;
  std::uint32_t run_count = 0;
  float run_min = 0.0f, run_max = 0.0f, run_sum = 0.0f;
  auto flush = [&]() {
    if (run_cell == kNoCell) return;
    GridCell& cell = cells[run_cell];
    if (cell.count == 0) occupied_.push_back(run_cell);
    cell.count += run_count;
    cell.z_min = std::min(cell.z_min, run_min);
    cell.z_max = std::max(cell.z_max, run_max);
    cell.z_sum += run_sum;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const PointXYZIRT& p = cloud[i];
    const float fc = (p.x - org) * inv;
    const float fr = (p.y - org) * inv;
    const float z = p.z + z_offset_m;
    pz[i] = z;
    if (!(fc >= 0.0f && fc < side_f && fr >= 0.0f && fr < side_f &&
          std::fabs(z) <= max_abs_height_m)) {
      pc[i] = kNoCell;
      continue;
    }
    const std::int32_t c = static_cast<std::int32_t>(fr) * side + static_cast<std::int32_t>(fc);
    pc[i] = c;
    if (c == run_cell) {
      ++run_count;
      run_min = std::min(run_min, z);
      run_max = std::max(run_max, z);
      run_sum += z;
    } else {
      flush();
      run_cell = c;
      run_count = 1;
      run_min = run_max = run_sum = z;
    }
  }
  flush();
}

}  // namespace core
}  // namespace urban_detection
