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

void SectorCompletion::startGrowing(std::int32_t seed) {
  component_.clear();
  stack_.clear();
  for (const std::int32_t c : marked_) mark_[c] = 0;
  marked_.clear();
  stack_.push_back(seed);
  mark_[seed] = 1;
  marked_.push_back(seed);
}

bool SectorCompletion::grow(const GridSegmenter& segmenter, std::int32_t seed, int link,
                            bool occupied_only) {
  const SimpleGrid& grid = segmenter.grid();
  const std::vector<SegmentClass>& cls = segmenter.cellClasses();
  const int rows = grid.rows(), cols = grid.cols();
  startGrowing(seed);
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
  const double min_len = hp.min_line_length_m / cell_m;
  const double len = std::hypot(static_cast<double>(rmax_ - rmin_ + 2 * w),
                                static_cast<double>(cmax_ - cmin_ + 2 * w)) +
                     1.0;
  std::uint8_t state = 2;
  if (closed && len < min_len) {
    state = 1;
  } else if (closed &&
             static_cast<double>(supportExtent(segmenter, w)) < minSupportExtent(hp, cell_m, w)) {
    state = 1;
  }
  for (const std::int32_t c : component_) {
    if (group_state_[c] == 0 && hough_state_[c] == 0) touched_.push_back(c);
    hough_state_[c] = state;
  }
  return state;
}

// A run only relabels cells when, over at least min_line_length_m, min_tall_fraction f of its
// occupied pixels are supporting (within the half width of a tall or wall-supporting cell).
// Along its major axis a run of length >= min_line_length_m has n >= (min_len - 1) / sqrt(2) + 1
// pixels, one per row (column); it begins and ends on occupied pixels, consecutive occupied
// pixels are at most gap_cells + 1 apart, and at most floor((1 - f) n) of them are not
// supporting. So its supporting pixels span at least n - floor((1 - f) n) (gap_cells + 1)
// rows (columns), and they all lie in the supporting cells dilated by the half width. The
// mixed-wall stretches begin and end on supporting pixels and are as long: they ask more.
// Returns the least such span over the run lengths the window allows.
double SectorCompletion::minSupportExtent(const HoughWallRefinerParams& hp, double cell_m, int w) {
  const double min_len = hp.min_line_length_m / cell_m;
  const int gap_cells = static_cast<int>(std::floor(hp.max_line_gap_m / cell_m));
  const int n_min = static_cast<int>(std::ceil(std::max(0.0, min_len - 1.0) / std::sqrt(2.0))) + 1;
  const int n_max = 2 * static_cast<int>(std::ceil(hp.max_range_m / cell_m)) + 2 * w + 1;
  const double f = std::min(1.0, std::max(0.0, hp.min_tall_fraction));
  double least = std::numeric_limits<double>::max();
  for (int n = n_min; n <= std::max(n_min, n_max); ++n) {
    const double off = std::floor((1.0 - f) * n + 1e-9);
    least = std::min(least, n - off * (gap_cells + 1));
  }
  return least;
}

std::size_t SectorCompletion::supportExtent(const GridSegmenter& segmenter, int w) const {
  const SimpleGrid& grid = segmenter.grid();
  const std::vector<SegmentClass>& cls = segmenter.cellClasses();
  const std::vector<std::uint8_t>& support = segmenter.wallSupport();
  const int cols = grid.cols();
  int rmin = std::numeric_limits<int>::max(), rmax = std::numeric_limits<int>::min();
  int cmin = rmin, cmax = rmax;
  for (const std::int32_t c : component_) {
    const bool supporting = cls[c] == SegmentClass::kTall ||
                            (static_cast<std::size_t>(c) < support.size() && support[c]) ||
                            flippable(segmenter, c);
    if (!supporting) continue;
    const int r = grid.rowOf(c), col = c - r * cols;
    rmin = std::min(rmin, r), rmax = std::max(rmax, r);
    cmin = std::min(cmin, col), cmax = std::max(cmax, col);
  }
  if (rmax < rmin) return 0;
  return static_cast<std::size_t>(std::max(rmax - rmin, cmax - cmin) + 2 * w + 1);
}

bool SectorCompletion::groupDoomed(const GridSegmenter& segmenter, std::int32_t seed) {
  // The cells that are in the seed's vehicle group whatever the rest of the revolution
  // brings: closed cells (their statistics and ground are final) that are short or candidate
  // tall (top and z range within vehicle_max_height_m of the ground), 8-connected to the seed
  // through such cells. The group of the whole revolution holds them all; its length and
  // width only grow with more cells and "touches a higher tall cell" stays true, so when
  // these cells already fail the vehicle test the group is never made short, and its cells
  // keep the classes they have now (the group so far holds them too, and fails as well).
  if (doomed_state_[seed] != 0) return doomed_state_[seed] == 1;
  const GridSegmenterParams& sp = segmenter.params();
  const SimpleGrid& grid = segmenter.grid();
  const std::vector<SegmentClass>& cls = segmenter.cellClasses();
  const int rows = grid.rows(), cols = grid.cols();
  const float vehicle_h = static_cast<float>(sp.vehicle_max_height_m);
  // Surely tall and not a candidate: tall by its statistics whatever the class rules, above
  // the candidates' bound.
  const float higher_h =
      static_cast<float>(std::max(sp.vehicle_max_height_m, sp.tall_min_height_m));
  const float higher_range =
      static_cast<float>(std::max(sp.vehicle_max_height_m, sp.tall_min_range_m));
  auto ground = [&](std::int32_t c) {
    return segmenter.cellHasGround(c) ? segmenter.cellGround(c) : 0.0f;
  };
  auto member = [&](std::int32_t c) {
    if (!cellClosed(grid, c)) return false;
    if (cls[c] == SegmentClass::kShort) return true;
    if (cls[c] != SegmentClass::kTall) return false;
    const GridCell& cell = grid.cell(c);
    return cell.z_max - ground(c) <= vehicle_h && cell.zRange() <= vehicle_h;
  };
  auto higher = [&](std::int32_t c) {
    if (cls[c] != SegmentClass::kTall || !cellClosed(grid, c)) return false;
    const GridCell& cell = grid.cell(c);
    return cell.z_max - ground(c) > higher_h || cell.zRange() > higher_range;
  };
  std::uint8_t state = 2;
  const bool grown = sp.vehicle_max_height_m > 0.0 && member(seed);
  if (grown) {
    startGrowing(seed);
    bool touches_higher = false;
    while (!stack_.empty()) {
      const std::int32_t c = stack_.back();
      stack_.pop_back();
      component_.push_back(c);
      const int r = grid.rowOf(c), col = c - r * cols;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int rr = r + dr, cc = col + dc;
          if ((dr == 0 && dc == 0) || rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
          const std::int32_t n = rr * cols + cc;
          if (mark_[n]) continue;
          if (member(n)) {
            mark_[n] = 1;
            marked_.push_back(n);
            stack_.push_back(n);
          } else if (higher(n)) {
            touches_higher = true;
          }
        }
      }
    }
    float len, wid;  // the segmenter's measure of the group
    cellGroupExtent(grid, component_, &len, &wid);
    const float max_len = static_cast<float>(sp.vehicle_max_length_m / sp.cell_size_m);
    const float max_wid = static_cast<float>(sp.vehicle_max_width_m / sp.cell_size_m);
    if (touches_higher || !(len <= max_len && wid <= max_wid)) state = 1;
    // Every cell of this closed part has the same answer (the same part grows from each).
    for (const std::int32_t c : component_) {
      if (doomed_state_[c] == 0) doomed_touched_.push_back(c);
      doomed_state_[c] = state;
    }
  } else {
    if (doomed_state_[seed] == 0) doomed_touched_.push_back(seed);
    doomed_state_[seed] = state;
  }
  return state == 1;
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
  if (doomed_state_.size() != grid.numCells()) {
    doomed_state_.assign(grid.numCells(), 0);
    doomed_touched_.clear();
  }
  for (const std::int32_t c : doomed_touched_) doomed_state_[c] = 0;
  doomed_touched_.clear();
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
          if (flippable(segmenter, n) && groupState(segmenter, n) != 1 &&
              !groupDoomed(segmenter, n)) {
            ok = false;
          }
        }
      }
    }
    if (!ok) {
      ++last_open_;
      continue;
    }
    // Hough: cells in the window (widened by the half width) must not be on a possible run,
    // neither the object's own nor those within the detector's reach (a neighbour made tall
    // may join or split it).
    if (hp.enabled) {
      for (std::size_t j = 0; ok && j < cells_.size(); ++j) {
        const int r0 = grid.rowOf(cells_[j]), c0 = cells_[j] - r0 * cols;
        for (int dr = -reach; ok && dr <= reach; ++dr) {
          for (int dc = -reach; ok && dc <= reach; ++dc) {
            const int r = r0 + dr, col = c0 + dc;
            if (r < wr0 || r >= wr1 || col < wc0 || col >= wc1) continue;
            if (r < 0 || r >= rows || col < 0 || col >= cols) continue;
            const std::int32_t c = r * cols + col;
            const SegmentClass cls = segmenter.cellClasses()[c];
            if (cls != SegmentClass::kTall && cls != SegmentClass::kShort) continue;
            if (houghState(segmenter, c) != 1) ok = false;
          }
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
