#include "urban_detection/core/hough_wall_refiner.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace urban_detection {
namespace core {

HoughWallRefiner::HoughWallRefiner(const HoughWallRefinerParams& params) : params_(params) {}

HoughWallStats HoughWallRefiner::refine(int rows, int cols, double cell_size_m,
                                        std::vector<SegmentClass>* cell_classes) {
  HoughWallStats stats;
  accepted_.clear();
  if (rows <= 0 || cols <= 0 || cell_size_m <= 0.0 ||
      cell_classes->size() != static_cast<std::size_t>(rows) * cols) {
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
  for (const cv::Vec4i& l : lines_) {
    const cv::Point a(l[0], l[1]), b(l[2], l[3]);
    // A wall line must be supported by tall cells (the part of the facade seen above the
    // height threshold); a row of parked cars is a line of short cells only.
    int occupied = 0, tall = 0;
    cv::LineIterator it(image_, a, b, 8);
    for (int i = 0; i < it.count; ++i, ++it) {
      const cv::Point p = it.pos();
      const SegmentClass s = cls[static_cast<std::size_t>(p.y + r0) * cols + (p.x + c0)];
      if (s == SegmentClass::kTall) ++tall, ++occupied;
      else if (s == SegmentClass::kShort) ++occupied;
    }
    if (occupied == 0 || tall < params_.min_tall_fraction * occupied) continue;
    ++stats.lines_accepted;
    accepted_.emplace_back(l[0] + c0, l[1] + r0, l[2] + c0, l[3] + r0);
    cv::LineIterator it2(image_, a, b, 8);
    for (int i = 0; i < it2.count; ++i, ++it2) {
      const cv::Point p = it2.pos();
      for (int dr = -w; dr <= w; ++dr) {
        for (int dc = -w; dc <= w; ++dc) {
          const int r = p.y + r0 + dr, c = p.x + c0 + dc;
          if (r < r0 || r >= r1 || c < c0 || c >= c1) continue;
          SegmentClass& s = cls[static_cast<std::size_t>(r) * cols + c];
          if (s == SegmentClass::kShort) {
            s = SegmentClass::kTall;
            ++stats.cells_relabeled;
          }
        }
      }
    }
  }
  return stats;
}

}  // namespace core
}  // namespace urban_detection
