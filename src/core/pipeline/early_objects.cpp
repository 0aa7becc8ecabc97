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

std::uint8_t SectorCompletion::componentState(const GridSegmenter& segmenter, std::int32_t seed) {
  if (state_[seed] != 0) return state_[seed];
  const SimpleGrid& grid = segmenter.grid();
  const std::vector<SegmentClass>& cls = segmenter.cellClasses();
  const GridSegmenterParams& sp = segmenter.params();
  const HoughWallRefinerParams& hp = sp.hough;
  const double cell_m = grid.params().cell_size_m;
  const int rows = grid.rows(), cols = grid.cols();
  // A tall cell low enough to be a vehicle candidate of the segmentation's step 4b, or a short
  // cell the Hough refinement made tall (lower than tall_min_height_m): both may change class
  // with their 8-connected group.
  const float low_h = static_cast<float>(std::max(sp.vehicle_max_height_m, sp.tall_min_height_m));
  const float low_range =
      static_cast<float>(std::max(sp.vehicle_max_height_m, sp.tall_min_range_m));
  auto groupable = [&](std::int32_t c) {
    if (cls[c] == SegmentClass::kShort) return true;
    if (cls[c] != SegmentClass::kTall) return false;
    const GridCell& cell = grid.cell(c);
    const float g = segmenter.cellHasGround(c) ? segmenter.cellGround(c) : 0.0f;
    return cell.z_max - g <= low_h && cell.zRange() <= low_range;
  };
  auto occupied = [&](std::int32_t c) {
    return cls[c] == SegmentClass::kTall || cls[c] == SegmentClass::kShort;
  };
  // Breadth first from `seed` over the cells `member` accepts within Chebyshev `link`; fills
  // component_ and its box; true when every cell of it is closed (stops at the first open one).
  int rmin = 0, rmax = 0, cmin = 0, cmax = 0;
  auto grow = [&](int link, auto&& member, std::uint8_t mark) {
    component_.clear();
    stack_.clear();
    stack_.push_back(seed);
    mark_[seed] = mark;
    marked_.push_back(seed);
    rmin = cmin = std::numeric_limits<int>::max();
    rmax = cmax = -1;
    while (!stack_.empty()) {
      const std::int32_t c = stack_.back();
      stack_.pop_back();
      component_.push_back(c);
      if (!cellClosed(grid, c)) return false;
      const int r = grid.rowOf(c), col = c - r * cols;
      rmin = std::min(rmin, r), rmax = std::max(rmax, r);
      cmin = std::min(cmin, col), cmax = std::max(cmax, col);
      for (int dr = -link; dr <= link; ++dr) {
        const int rr = r + dr;
        if (rr < 0 || rr >= rows) continue;
        for (int dc = -link; dc <= link; ++dc) {
          const int cc = col + dc;
          if (cc < 0 || cc >= cols) continue;
          const std::int32_t n = rr * cols + cc;
          if (mark_[n] == mark || !member(n)) continue;
          mark_[n] = mark;
          marked_.push_back(n);
          stack_.push_back(n);
        }
      }
    }
    return true;
  };
  auto settle = [&](std::uint8_t state) {
    for (const std::int32_t c : component_) {
      if (state_[c] == 0) touched_.push_back(c);
      state_[c] = state;
    }
    for (const std::int32_t c : marked_) mark_[c] = 0;
    marked_.clear();
    return state;
  };
  // The vehicle groups and every neighbour rule of the segmentation: 8-connected.
  if (!grow(1, groupable, 1)) return settle(2);
  const std::vector<std::int32_t> local = component_;
  // Hough: within the window (and the line's half width), a run needs the component linked
  // within the run's gap and half widths to be min_line_length_m long.
  if (hp.enabled) {
    const int w = hp.line_half_width_cells;
    const int half = static_cast<int>(std::ceil(hp.max_range_m / cell_m));
    const int r0 = rows / 2 - half - w, r1 = rows / 2 + half + w;
    const int c0 = cols / 2 - half - w, c1 = cols / 2 + half + w;
    if (rmax >= r0 && rmin < r1 && cmax >= c0 && cmin < c1) {
      for (const std::int32_t c : marked_) mark_[c] = 0;
      marked_.clear();
      const int gap_cells = static_cast<int>(std::floor(hp.max_line_gap_m / cell_m));
      const int link = std::max(1, gap_cells + 1 + 2 * w);
      const bool closed = grow(link, occupied, 2);
      const double len = std::hypot(static_cast<double>(rmax - rmin + 2 * w),
                                    static_cast<double>(cmax - cmin + 2 * w)) +
                         1.0;
      if (!closed || len >= hp.min_line_length_m / cell_m) {
        component_ = local;
        return settle(4);
      }
      component_ = local;
    }
  }
  return settle(1);
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
  if (state_.size() != grid.numCells()) {
    state_.assign(grid.numCells(), 0);
    mark_.assign(grid.numCells(), 0);
    touched_.clear();
    marked_.clear();
  }
  for (const std::int32_t c : touched_) state_[c] = 0;
  touched_.clear();
  for (std::size_t k = 0; k < objects.size(); ++k) {
    bool ok = true, hough = false;
    for (const std::uint32_t i : objects[k].indices) {
      if (i >= cloud.size()) {
        ok = false;
        break;
      }
      const std::int32_t c = grid.pointCell(i);
      if (c == SimpleGrid::kNoCell) {  // a point the grid does not hold: judge by its own cell
        const std::int32_t pc = grid.cellAt(cloud[i].x, cloud[i].y);
        if (pc == SimpleGrid::kNoCell || !cellClosed(grid, pc)) {
          ok = false;
          break;
        }
        continue;
      }
      if (state_[c] == 0 && !(segmenter.cellClasses()[c] == SegmentClass::kTall ||
                              segmenter.cellClasses()[c] == SegmentClass::kShort)) {
        // A foreground point in a cell of another class (cannot happen with the grid
        // segmenter): closed cell required.
        if (!cellClosed(grid, c)) {
          ok = false;
          break;
        }
        continue;
      }
      const std::uint8_t state = componentState(segmenter, c);
      if (state != 1) {
        ok = false;
        hough = state == 4;
        break;
      }
    }
    (*final)[k] = ok ? 1 : 0;
    if (!ok) ++(hough ? last_hough_ : last_open_);
  }
}

}  // namespace core
}  // namespace urban_detection
