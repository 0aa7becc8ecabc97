#include "urban_detection/core/segmentation/hough_wall_refiner.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace urban_detection {
namespace core {

std::string validate(const HoughWallRefinerParams& p) {
  return checkFieldRanges(p);
}

HoughWallRefiner::HoughWallRefiner(const HoughWallRefinerParams& params) : params_(params) {}

HoughWallStats HoughWallRefiner::refine(int rows, int cols, double cell_size_m,
                                        std::vector<SegmentClass>* cell_classes) {
  return refine(rows, cols, cell_size_m, cell_classes, nullptr);
}

HoughWallStats HoughWallRefiner::refine(int rows, int cols, double cell_size_m,
                                        std::vector<SegmentClass>* cell_classes,
                                        const std::vector<std::uint8_t>* wall_support) {
  HoughWallStats stats;
  accepted_.clear();
  relabeled_.clear();
  if (rows <= 0 || cols <= 0 || cell_size_m <= 0.0 ||
      cell_classes->size() != static_cast<std::size_t>(rows) * cols ||
      (wall_support && wall_support->size() != cell_classes->size())) {
    return stats;
  }
  // Window of the grid around the sensor (grid centre) that is rasterised.
  const int half = static_cast<int>(std::ceil(params_.max_range_m / cell_size_m));
  const int r0 = std::max(0, rows / 2 - half), r1 = std::min(rows, rows / 2 + half);
  const int c0 = std::max(0, cols / 2 - half), c1 = std::min(cols, cols / 2 + half);
  if (r1 <= r0 || c1 <= c0) return stats;

  image_.create(r1 - r0, c1 - c0, CV_8UC1);
  image_.setTo(0);
  std::vector<SegmentClass>& cls = *cell_classes;
  for (int r = r0; r < r1; ++r) {
    std::uint8_t* row = image_.ptr<std::uint8_t>(r - r0);
    const SegmentClass* src = &cls[static_cast<std::size_t>(r) * cols];
    for (int c = c0; c < c1; ++c) {
      if (src[c] == SegmentClass::kTall || src[c] == SegmentClass::kShort) row[c - c0] = 255;
    }
  }

  const double theta = std::max(0.1, params_.theta_resolution_deg) * CV_PI / 180.0;
  const double min_len = params_.min_line_length_m / cell_size_m;
  const double max_gap = params_.max_line_gap_m / cell_size_m;
  lines_.clear();
  cv::HoughLinesP(image_, lines_, 1.0, theta, std::max(1, params_.votes), min_len, max_gap);
  stats.lines_found = static_cast<int>(lines_.size());

  const int w = params_.line_half_width_cells;
  const int gap_cells = static_cast<int>(std::floor(max_gap));
  auto isShort = [&](std::size_t idx) { return cls[idx] == SegmentClass::kShort; };
  for (const cv::Vec4i& l : lines_) {
    // Walk the segment; a pixel is occupied / supporting when a cell within the half width is.
    // The segment is extended across the whole window and the runs along it decide what is
    // wall: HoughLinesP often returns only a fragment of a facade (it removes the pixels of a
    // found segment and samples randomly), the extension recovers the rest of it.
    cv::Point pa(l[0], l[1]), pb(l[2], l[3]);
    if (params_.extend_lines) {
      const double dx = pb.x - pa.x, dy = pb.y - pa.y, norm = std::hypot(dx, dy);
      if (norm > 0.0) {
        const double ext = image_.cols + image_.rows;
        pa = cv::Point(cvRound(pa.x - dx / norm * ext), cvRound(pa.y - dy / norm * ext));
        pb = cv::Point(cvRound(pb.x + dx / norm * ext), cvRound(pb.y + dy / norm * ext));
        if (!cv::clipLine(image_.size(), pa, pb)) continue;
      }
    }
    line_px_.clear();
    cv::LineIterator it(image_, pa, pb, 8);
    for (int i = 0; i < it.count; ++i, ++it) {
      const cv::Point p = it.pos();
      LinePixel px{p.x + c0, p.y + r0, false, false};
      for (int dr = -w; dr <= w; ++dr) {
        for (int dc = -w; dc <= w; ++dc) {
          const int r = px.row + dr, c = px.col + dc;
          if (r < r0 || r >= r1 || c < c0 || c >= c1) continue;
          const std::size_t idx = static_cast<std::size_t>(r) * cols + c;
          if (cls[idx] == SegmentClass::kTall) {
            px.occupied = px.support = true;
          } else if (isShort(idx)) {
            px.occupied = true;
            if (wall_support && (*wall_support)[idx]) px.support = true;
          }
        }
      }
      line_px_.push_back(px);
    }
    // Split the segment into runs of occupied pixels (gaps up to max_line_gap). Hough joins
    // collinear but separate things (a car, then 3 m of road, then a wall); only a run that is
    // itself long and supported by wall evidence is a wall: a row of parked cars is a line of
    // short cells below the sensor, without tall or field-of-view-truncated cells, and a van
    // among them (tall, or truncated by the field of view) does not make the row a wall.
    // A run that fails the support test can still hold a wall: a facade that continues a row
    // of parked cars. Its stretches of wall-supporting pixels at least min_mixed_wall_length_m
    // long (longer than any vehicle) are walls; there only the facade's own short cells (those
    // truncated by the field of view) become tall, not an object standing against the wall.
    bool line_used = false;
    const std::size_t n = line_px_.size();
    const double min_mixed_len = params_.min_mixed_wall_length_m / cell_size_m;
    auto length = [&](std::size_t a, std::size_t b) {
      return std::hypot(line_px_[b].col - line_px_[a].col, line_px_[b].row - line_px_[a].row) + 1.0;
    };
    // Runs of pixels in [from, to] with `member` set, bridging gaps up to gap_cells; calls
    // `take(start, last, occupied, support)` for each.
    auto runs = [&](std::size_t from, std::size_t to, bool LinePixel::*member, auto&& take) {
      std::size_t i = from;
      while (i <= to) {
        while (i <= to && !(line_px_[i].*member)) ++i;
        if (i > to) break;
        const std::size_t start = i;
        std::size_t last = i;
        int occupied = 0, support = 0;
        for (std::size_t j = i; j <= to && static_cast<int>(j - last) <= gap_cells + 1; ++j) {
          if (line_px_[j].*member) last = j;
        }
        for (std::size_t j = start; j <= last; ++j) {
          occupied += line_px_[j].occupied ? 1 : 0;
          support += line_px_[j].support ? 1 : 0;
        }
        i = last + 1;
        take(start, last, occupied, support);
      }
    };
    // `supported_only`: only short cells that are wall evidence themselves (truncated by the
    // field of view) change, not the short objects standing beside the wall.
    auto relabel = [&](std::size_t start, std::size_t last, bool supported_only) {
      line_used = true;
      for (std::size_t k = start; k <= last; ++k) {
        for (int dr = -w; dr <= w; ++dr) {
          for (int dc = -w; dc <= w; ++dc) {
            const int r = line_px_[k].row + dr, c = line_px_[k].col + dc;
            if (r < r0 || r >= r1 || c < c0 || c >= c1) continue;
            const std::size_t idx = static_cast<std::size_t>(r) * cols + c;
            if (isShort(idx) && (!supported_only || !wall_support || (*wall_support)[idx])) {
              cls[idx] = SegmentClass::kTall;
              relabeled_.push_back(static_cast<std::int32_t>(idx));
              ++stats.cells_relabeled;
            }
          }
        }
      }
    };
    if (n > 0) {
      runs(0, n - 1, &LinePixel::occupied,
           [&](std::size_t start, std::size_t last, int occupied, int support) {
             if (length(start, last) < min_len) return;
             if (support >= params_.min_tall_fraction * occupied) {
               relabel(start, last, false);
               return;
             }
             if (min_mixed_len <= 0.0) return;
             runs(start, last, &LinePixel::support,
                  [&](std::size_t s0, std::size_t s1, int occ, int sup) {
                    if (length(s0, s1) >= std::max(min_len, min_mixed_len) &&
                        sup >= params_.min_tall_fraction * occ) {
                      relabel(s0, s1, true);
                    }
                  });
           });
    }
    if (line_used) {
      ++stats.lines_accepted;
      accepted_.emplace_back(l[0] + c0, l[1] + r0, l[2] + c0, l[3] + r0);
    }
  }
  return stats;
}

}  // namespace core
}  // namespace urban_detection
