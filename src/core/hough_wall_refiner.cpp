#include "urban_detection/core/hough_wall_refiner.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace urban_detection {
namespace core {

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

  const int win_rows = r1 - r0, win_cols = c1 - c0;
  mask_.resize(static_cast<std::size_t>(win_rows) * win_cols);
  std::vector<SegmentClass>& cls = *cell_classes;
  for (int r = r0; r < r1; ++r) {
    std::uint8_t* row = mask_.data() + static_cast<std::size_t>(r - r0) * win_cols;
    const SegmentClass* src = &cls[static_cast<std::size_t>(r) * cols + c0];
    for (int c = 0; c < win_cols; ++c) {
      row[c] = (src[c] == SegmentClass::kTall || src[c] == SegmentClass::kShort) ? 255 : 0;
    }
  }

  const double theta = std::max(0.1, params_.theta_resolution_deg) * CV_PI / 180.0;
  const double min_len = params_.min_line_length_m / cell_size_m;
  const double max_gap = params_.max_line_gap_m / cell_size_m;
  const int votes = std::max(1, params_.votes);
  lines_.clear();
  // A header on the window's mask: cv::HoughLinesP's input, and the geometry (not the pixels)
  // of the line walks below.
  image_ = cv::Mat(win_rows, win_cols, CV_8UC1, mask_.data());
  if (use_opencv_) {
    cv::HoughLinesP(image_, lines_, 1.0, theta, votes, min_len, max_gap);
  } else {
    houghLinesP(mask_.data(), win_rows, win_cols, theta, votes, min_len, max_gap, &lines_);
  }
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
    // short cells below the sensor, without tall or field-of-view-truncated cells.
    bool line_used = false;
    const std::size_t n = line_px_.size();
    std::size_t i = 0;
    while (i < n) {
      while (i < n && !line_px_[i].occupied) ++i;
      if (i >= n) break;
      const std::size_t start = i;
      std::size_t last = i;
      int occupied = 0, support = 0;
      for (std::size_t j = i; j < n && static_cast<int>(j - last) <= gap_cells + 1; ++j) {
        if (!line_px_[j].occupied) continue;
        last = j;
        ++occupied;
        support += line_px_[j].support ? 1 : 0;
      }
      i = last + 1;
      const double len = std::hypot(line_px_[last].col - line_px_[start].col,
                                    line_px_[last].row - line_px_[start].row) + 1.0;
      if (len < min_len || support < params_.min_tall_fraction * occupied) continue;
      line_used = true;
      for (std::size_t k = start; k <= last; ++k) {
        for (int dr = -w; dr <= w; ++dr) {
          for (int dc = -w; dc <= w; ++dc) {
            const int r = line_px_[k].row + dr, c = line_px_[k].col + dc;
            if (r < r0 || r >= r1 || c < c0 || c >= c1) continue;
            const std::size_t idx = static_cast<std::size_t>(r) * cols + c;
            if (isShort(idx)) {
              cls[idx] = SegmentClass::kTall;
              ++stats.cells_relabeled;
            }
          }
        }
      }
    }
    if (line_used) {
      ++stats.lines_accepted;
      accepted_.emplace_back(l[0] + c0, l[1] + r0, l[2] + c0, l[3] + r0);
    }
  }
  return stats;
}

// The progressive probabilistic Hough transform (Matas et al. 2000) as OpenCV 4 implements it
// in HoughLinesProbabilistic (imgproc/src/hough.cpp), step for step: the non-zero pixels in
// row-major order, picked in the order of cv::RNG(~0) (uniform over the remaining ones, the
// picked one replaced by the last), each unprocessed pick votes for numangle rho bins and the
// first angle with the most votes (at least `threshold`) is followed both ways in 16.16 fixed
// point, gaps up to max_line_gap; the pixels walked over are cleared and, for a segment at
// least min_line_length long along x or y, un-vote. Float expressions are OpenCV's (rho bin:
// round-half-even of j * cos + i * sin in float, trig tables rounded from double), so the
// segments are identical. Differences only in bookkeeping: the accumulator and tables live
// between calls and hold only the rho bins the window can reach (OpenCV allocates and zeroes
// all 2 * (rows + cols) + 1 bins per angle every call: 115 kB for the default 80 x 80 window,
// here 37 kB), and a pixel's rho bins are computed four angles at a time.
void HoughWallRefiner::houghLinesP(std::uint8_t* mask, int rows, int cols, double theta_rad,
                                   int threshold, double min_line_length, double max_line_gap,
                                   std::vector<cv::Vec4i>* lines) {
  lines->clear();
  if (rows <= 0 || cols <= 0) return;
  const float theta = static_cast<float>(theta_rad);
  const float irho = 1.0f;
  // cv::HoughLinesP: line length and gap rounded to integers, rho resolution 1.
  const int line_length = cvRound(min_line_length);
  const int line_gap = cvRound(max_line_gap);
  // computeNumangle(0, CV_PI, theta) of hough.cpp.
  int numangle = cvFloor(CV_PI / theta) + 1;
  if (numangle > 1 && std::fabs(CV_PI - (numangle - 1) * static_cast<double>(theta)) < theta / 2) {
    --numangle;
  }
  const int numrho = cvRound(((cols + rows) * 2 + 1) / irho);
  if (numangle <= 0 || numrho <= 0) return;
  const int padded = (numangle + 3) & ~3;
  if (static_cast<double>(theta) != trig_theta_ || rows != trig_rows_ || cols != trig_cols_) {
    cos_.assign(padded, 0.0f);
    sin_.assign(padded, 0.0f);
    row_base_.assign(padded, 0);
    // Only the rho bins the window's pixels can reach are stored, angle after angle: rho is
    // linear in (j, i), so its extremes over the window are at the corners (the float
    // expression and the rounding are monotonic); one bin of margin. About 2/5 of OpenCV's
    // 2 * (rows + cols) + 1 bins per angle, so the accumulator stays in cache between frames.
    std::size_t size = 0;
    for (int n = 0; n < numangle; ++n) {
      cos_[n] = static_cast<float>(std::cos(static_cast<double>(n) * theta) * irho);
      sin_[n] = static_cast<float>(std::sin(static_cast<double>(n) * theta) * irho);
      float lo = 0.0f, hi = 0.0f;
      for (const float x : {0.0f, static_cast<float>(cols - 1)}) {
        for (const float y : {0.0f, static_cast<float>(rows - 1)}) {
          const float v = x * cos_[n] + y * sin_[n];
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
      }
      const int b0 = std::max(0, cvFloor(lo) - 1 + (numrho - 1) / 2);
      const int b1 = std::min(numrho - 1, cvCeil(hi) + 1 + (numrho - 1) / 2);
      // Flat index of bin r of angle n: row_base_[n] + cvRound(rho) for r = cvRound(rho) +
      // (numrho - 1) / 2 in [b0, b1].
      row_base_[n] = static_cast<std::int32_t>(size) - b0 + (numrho - 1) / 2;
      size += static_cast<std::size_t>(b1 - b0 + 1);
    }
    accum_.resize(size);
    vote_idx_.assign(padded, 0);
    trig_theta_ = theta;
    trig_rows_ = rows;
    trig_cols_ = cols;
  }
  std::fill(accum_.begin(), accum_.end(), 0);
  std::int32_t* accum = accum_.data();
  std::int32_t* idx = vote_idx_.data();
  // Rho bins (flat accumulator indices) of pixel (j, i) for every angle.
  auto bins = [&](int j, int i) {
#if defined(__SSE2__)
    const __m128 jf = _mm_set1_ps(static_cast<float>(j)), if4 = _mm_set1_ps(static_cast<float>(i));
    for (int n = 0; n < padded; n += 4) {
      const __m128 v = _mm_add_ps(_mm_mul_ps(jf, _mm_loadu_ps(&cos_[n])),
                                  _mm_mul_ps(if4, _mm_loadu_ps(&sin_[n])));
      const __m128i b = _mm_add_epi32(
          _mm_cvtps_epi32(v), _mm_loadu_si128(reinterpret_cast<const __m128i*>(&row_base_[n])));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(idx + n), b);
    }
#else
    for (int n = 0; n < numangle; ++n) {
      idx[n] =
          cvRound(static_cast<float>(j) * cos_[n] + static_cast<float>(i) * sin_[n]) + row_base_[n];
    }
#endif
  };

  nz_.clear();
  for (int i = 0; i < rows; ++i) {
    std::uint8_t* m = mask + static_cast<std::size_t>(i) * cols;
    for (int j = 0; j < cols; ++j) {
      if (m[j]) {
        m[j] = 1;
        nz_.emplace_back(j, i);
      }
    }
  }
  cv::RNG rng(static_cast<std::uint64_t>(-1));
  constexpr int kShift = 16;
  for (int count = static_cast<int>(nz_.size()); count > 0; --count) {
    const int pick = rng.uniform(0, count);
    const cv::Point point = nz_[pick];
    nz_[pick] = nz_[count - 1];
    const int i = point.y, j = point.x;
    if (!mask[static_cast<std::size_t>(i) * cols + j]) continue;  // on an earlier segment
    bins(j, i);
    int max_val = threshold - 1, max_n = 0;
    for (int n = 0; n < numangle; ++n) {
      const int val = ++accum[idx[n]];
      if (max_val < val) {
        max_val = val;
        max_n = n;
      }
    }
    if (max_val < threshold) continue;

    // Walk from the point along the line in both directions (16.16 fixed point).
    const float a = -sin_[max_n], b = cos_[max_n];
    int x0 = j, y0 = i, dx0, dy0;
    const bool xflag = std::fabs(a) > std::fabs(b);
    if (xflag) {
      dx0 = a > 0 ? 1 : -1;
      dy0 = cvRound(b * (1 << kShift) / std::fabs(a));
      y0 = (y0 << kShift) + (1 << (kShift - 1));
    } else {
      dy0 = b > 0 ? 1 : -1;
      dx0 = cvRound(a * (1 << kShift) / std::fabs(b));
      x0 = (x0 << kShift) + (1 << (kShift - 1));
    }
    cv::Point line_end[2];
    for (int k = 0; k < 2; ++k) {
      int gap = 0, x = x0, y = y0;
      const int dx = k > 0 ? -dx0 : dx0, dy = k > 0 ? -dy0 : dy0;
      for (;; x += dx, y += dy) {
        const int j1 = xflag ? x : x >> kShift;
        const int i1 = xflag ? y >> kShift : y;
        if (j1 < 0 || j1 >= cols || i1 < 0 || i1 >= rows) break;
        if (mask[static_cast<std::size_t>(i1) * cols + j1]) {
          gap = 0;
          line_end[k] = cv::Point(j1, i1);
        } else if (++gap > line_gap) {
          break;
        }
      }
    }
    const bool good_line = std::abs(line_end[1].x - line_end[0].x) >= line_length ||
                           std::abs(line_end[1].y - line_end[0].y) >= line_length;
    for (int k = 0; k < 2; ++k) {
      int x = x0, y = y0;
      const int dx = k > 0 ? -dx0 : dx0, dy = k > 0 ? -dy0 : dy0;
      for (;; x += dx, y += dy) {
        const int j1 = xflag ? x : x >> kShift;
        const int i1 = xflag ? y >> kShift : y;
        std::uint8_t* m = mask + static_cast<std::size_t>(i1) * cols + j1;
        if (*m) {
          if (good_line) {
            bins(j1, i1);
            for (int n = 0; n < numangle; ++n) --accum[idx[n]];
          }
          *m = 0;
        }
        if (i1 == line_end[k].y && j1 == line_end[k].x) break;
      }
    }
    if (good_line) {
      lines->emplace_back(line_end[0].x, line_end[0].y, line_end[1].x, line_end[1].y);
    }
  }
}

}  // namespace core
}  // namespace urban_detection
