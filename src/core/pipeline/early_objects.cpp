#include "urban_detection/core/pipeline/early_objects.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace urban_detection {
namespace core {

namespace {

constexpr double kTwoPi = 6.283185307179586;

// a - b wrapped into [-pi, pi).
double wrapPi(double a) {
  a = std::fmod(a + M_PI, kTwoPi);
  if (a < 0.0) a += kTwoPi;
  return a - M_PI;
}

// Median azimuth of the finite points [from, to) of `cloud` (at most `n` of them, taken from
// the `from_end` side), or NaN when none is finite.
double medianAzimuth(const CloudXYZIRT& cloud, std::size_t n, bool from_end,
                     std::vector<float>* az) {
  az->clear();
  const std::size_t size = cloud.size();
  for (std::size_t k = 0; k < size && az->size() < n; ++k) {
    const PointXYZIRT& p = cloud[from_end ? size - 1 - k : k];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || (p.x == 0.0f && p.y == 0.0f)) continue;
    az->push_back(std::atan2(p.y, p.x));
  }
  if (az->empty()) return std::nan("");
  const double ref = (*az)[0];
  for (float& a : *az) a = static_cast<float>(wrapPi(a - ref));
  std::nth_element(az->begin(), az->begin() + az->size() / 2, az->end());
  return ref + (*az)[az->size() / 2];
}

}  // namespace

std::string validate(const EarlyObjectsParams& p) {
  return checkFieldRanges(p);
}

SectorCompletion::SectorCompletion(const EarlyObjectsParams& params) : params_(params) {}

bool SectorCompletion::updateSweep(const CloudXYZIRT& cloud) {
  sweep_valid_ = false;
  swept_rad_ = 0.0;
  const std::size_t n = static_cast<std::size_t>(std::max(1, params_.front_points));
  const double seam = medianAzimuth(cloud, n, false, &scratch_az_);
  const double front = medianAzimuth(cloud, n, true, &scratch_az_);
  if (!std::isfinite(seam) || !std::isfinite(front)) return false;
  // The time field of a decoded revolution grows with the points; the rotation sense is the
  // one the front moved in. Before the front is 10 degrees away, nothing is final.
  const double d = wrapPi(front - seam);
  if (std::abs(d) < 10.0 * M_PI / 180.0 && cloud.size() < 4 * n) return false;
  // The sense is taken from the middle of the points so far (unambiguous past half a turn).
  const PointXYZIRT& mid = cloud[cloud.size() / 2];
  double sense = d >= 0.0 ? 1.0 : -1.0;
  if (std::isfinite(mid.x) && std::isfinite(mid.y)) {
    const double dm = wrapPi(std::atan2(mid.y, mid.x) - seam);
    if (std::abs(dm) > 10.0 * M_PI / 180.0) sense = dm >= 0.0 ? 1.0 : -1.0;
  }
  double swept = sense * (front - seam);
  swept = std::fmod(swept, kTwoPi);
  if (swept < 0.0) swept += kTwoPi;
  seam_rad_ = seam;
  sense_ = sense;
  swept_rad_ = swept;
  sweep_valid_ = swept > 0.0;
  return sweep_valid_;
}

bool SectorCompletion::cellClosed(const SimpleGrid& grid, std::int32_t cell) const {
  if (!sweep_valid_) return false;
  float x = 0.0f, y = 0.0f;
  grid.cellCenter(cell, &x, &y);
  const double r = std::hypot(static_cast<double>(x), static_cast<double>(y));
  const double reach = params_.margin_m + 0.7072 * grid.params().cell_size_m;
  if (r <= reach) return false;
  const double w = std::asin(reach / r) + params_.angle_margin_deg * M_PI / 180.0;
  double u = sense_ * (std::atan2(y, x) - seam_rad_);
  u = std::fmod(u, kTwoPi);
  if (u < 0.0) u += kTwoPi;
  return u - w >= 0.0 && u + w <= swept_rad_;
}

namespace {

// The detector's reach beyond an object's own cells: its radial, gap and roof bridges (at most
// 1.6 m with the shipped parameters) and the far-object merger's gap (1.2 m).
constexpr double kDetectorReach_m = 2.0;

}  // namespace

bool SectorCompletion::grow(const GridSegmenter& segmenter, std::int32_t seed, int link,
                            bool occupied_only) {
  const SimpleGrid& grid = segmenter.grid();
  const std::vector<SegmentClass>& cls = segmenter.cellClasses();
  const int rows = grid.rows(), cols = grid.cols();
  component_.clear();
  stack_.clear();
  for (const std::int32_t c : marked_) mark_[c] = 0;
  marked_.clear();
  stack_.push_back(seed);
  mark_[seed] = 1;
  marked_.push_back(seed);
  rmin_ = cmin_ = std::numeric_limits<int>::max();
  rmax_ = cmax_ = -1;
  bool closed = true;
  while (!stack_.empty()) {
    const std::int32_t c = stack_.back();
    stack_.pop_back();
    component_.push_back(c);
    if (!cellClosed(grid, c)) closed = false;
    const int r = grid.rowOf(c), col = c - r * cols;
    rmin_ = std::min(rmin_, r), rmax_ = std::max(rmax_, r);
    cmin_ = std::min(cmin_, col), cmax_ = std::max(cmax_, col);
    for (int dr = -link; dr <= link; ++dr) {
      const int rr = r + dr;
      if (rr < 0 || rr >= rows) continue;
      for (int dc = -link; dc <= link; ++dc) {
        const int cc = col + dc;
        if (cc < 0 || cc >= cols) continue;
        const std::int32_t n = rr * cols + cc;
        if (mark_[n]) continue;
        const bool member = occupied_only
                                ? (cls[n] == SegmentClass::kTall || cls[n] == SegmentClass::kShort)
                                : groupable(segmenter, n);
        if (!member) continue;
        mark_[n] = 1;
        marked_.push_back(n);
        stack_.push_back(n);
      }
    }
  }
  return closed;
}

bool SectorCompletion::groupable(const GridSegmenter& segmenter, std::int32_t c) const {
  const SegmentClass cls = segmenter.cellClasses()[c];
  if (cls == SegmentClass::kShort) return true;
  if (cls != SegmentClass::kTall) return false;
  const GridSegmenterParams& sp = segmenter.params();
  const GridCell& cell = segmenter.grid().cell(c);
  const float g = segmenter.cellHasGround(c) ? segmenter.cellGround(c) : 0.0f;
  return cell.z_max - g <=
             static_cast<float>(std::max(sp.vehicle_max_height_m, sp.tall_min_height_m)) &&
         cell.zRange() <=
             static_cast<float>(std::max(sp.vehicle_max_height_m, sp.tall_min_range_m));
}

bool SectorCompletion::flippable(const GridSegmenter& segmenter, std::int32_t c) const {
  const SegmentClass cls = segmenter.cellClasses()[c];
  if (cls == SegmentClass::kTall) return groupable(segmenter, c);
  if (cls != SegmentClass::kShort) return false;
  // A short cell with the statistics of a tall one: a vehicle candidate made short.
  const GridSegmenterParams& sp = segmenter.params();
  const GridCell& cell = segmenter.grid().cell(c);
  const float g = segmenter.cellHasGround(c) ? segmenter.cellGround(c) : 0.0f;
  return cell.z_max - g > static_cast<float>(sp.tall_min_height_m) ||
         cell.zRange() > static_cast<float>(sp.tall_min_range_m);
}

std::uint8_t SectorCompletion::groupState(const GridSegmenter& segmenter, std::int32_t seed) {
  if (group_state_[seed] != 0) return group_state_[seed];
  const std::uint8_t state = grow(segmenter, seed, 1, false) ? 1 : 2;
  for (const std::int32_t c : component_) {
    if (group_state_[c] == 0 && hough_state_[c] == 0) touched_.push_back(c);
    group_state_[c] = state;
  }
  return state;
}

std::uint8_t SectorCompletion::houghState(const GridSegmenter& segmenter, std::int32_t seed) {
  if (hough_state_[seed] != 0) return hough_state_[seed];
  const HoughWallRefinerParams& hp = segmenter.params().hough;
  const double cell_m = segmenter.grid().params().cell_size_m;
  const int w = hp.line_half_width_cells;
  const int gap_cells = static_cast<int>(std::floor(hp.max_line_gap_m / cell_m));
  const int link = std::max(1, gap_cells + 1 + 2 * w);
  const bool closed = grow(segmenter, seed, link, true);
  const double len = std::hypot(static_cast<double>(rmax_ - rmin_ + 2 * w),
                                static_cast<double>(cmax_ - cmin_ + 2 * w)) +
                     1.0;
  const std::uint8_t state = closed && len < hp.min_line_length_m / cell_m ? 1 : 2;
  for (const std::int32_t c : component_) {
    if (group_state_[c] == 0 && hough_state_[c] == 0) touched_.push_back(c);
    hough_state_[c] = state;
  }
  return state;
}

void SectorCompletion::finalObjects(const CloudXYZIRT& cloud, const GridSegmenter& segmenter,
                                    const std::vector<DetectedObject>& objects,
                                    std::vector<std::uint8_t>* final) {
  final->assign(objects.size(), 0);
  last_open_ = last_hough_ = 0;
  if (!sweep_valid_) {
    last_open_ = objects.size();
    return;
  }
  const SimpleGrid& grid = segmenter.grid();
  if (group_state_.size() != grid.numCells()) {
    group_state_.assign(grid.numCells(), 0);
    hough_state_.assign(grid.numCells(), 0);
    mark_.assign(grid.numCells(), 0);
    touched_.clear();
    marked_.clear();
  }
  for (const std::int32_t c : touched_) group_state_[c] = hough_state_[c] = 0;
  touched_.clear();
  const HoughWallRefinerParams& hp = segmenter.params().hough;
  const double cell_m = grid.params().cell_size_m;
  const int rows = grid.rows(), cols = grid.cols();
  const int w = hp.line_half_width_cells;
  const int half = static_cast<int>(std::ceil(hp.max_range_m / cell_m));
  const int wr0 = rows / 2 - half - w, wr1 = rows / 2 + half + w;
  const int wc0 = cols / 2 - half - w, wc1 = cols / 2 + half + w;
  const int reach = static_cast<int>(std::ceil(kDetectorReach_m / cell_m));
  for (std::size_t k = 0; k < objects.size(); ++k) {
    // The object's cells, all closed.
    cells_.clear();
    bool ok = true;
    for (const std::uint32_t i : objects[k].indices) {
      std::int32_t c = i < cloud.size() ? grid.pointCell(i) : SimpleGrid::kNoCell;
      if (c == SimpleGrid::kNoCell && i < cloud.size()) c = grid.cellAt(cloud[i].x, cloud[i].y);
      if (c == SimpleGrid::kNoCell || !cellClosed(grid, c)) {
        ok = false;
        break;
      }
      cells_.push_back(c);
    }
    std::sort(cells_.begin(), cells_.end());
    cells_.erase(std::unique(cells_.begin(), cells_.end()), cells_.end());
    // Cells within the detector's reach that may change class with their vehicle group: the
    // group must be closed.
    for (std::size_t j = 0; ok && j < cells_.size(); ++j) {
      const int r = grid.rowOf(cells_[j]), col = cells_[j] - r * cols;
      for (int dr = -reach; ok && dr <= reach; ++dr) {
        for (int dc = -reach; ok && dc <= reach; ++dc) {
          const int rr = r + dr, cc = col + dc;
          if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
          const std::int32_t n = rr * cols + cc;
          if (flippable(segmenter, n) && groupState(segmenter, n) != 1) ok = false;
        }
      }
    }
    if (!ok) {
      ++last_open_;
      continue;
    }
    // Hough: cells in the window (widened by the half width) must not be on a possible run.
    if (hp.enabled) {
      for (const std::int32_t c : cells_) {
        const int r = grid.rowOf(c), col = c - r * cols;
        if (r < wr0 || r >= wr1 || col < wc0 || col >= wc1) continue;
        const SegmentClass cls = segmenter.cellClasses()[c];
        if (cls != SegmentClass::kTall && cls != SegmentClass::kShort) continue;
        if (houghState(segmenter, c) != 1) {
          ok = false;
          break;
        }
      }
      if (!ok) {
        ++last_hough_;
        continue;
      }
    }
    (*final)[k] = 1;
  }
}

}  // namespace core
}  // namespace urban_detection
