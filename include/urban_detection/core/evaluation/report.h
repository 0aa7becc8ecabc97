/// \file report.h
/// What the evaluation and benchmark reports are made of: order statistics (percentile,
/// median), JSON numbers (strings: common/json.h), and a minimal x/y line plot written as a PNG.
/// ROS-free.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "urban_detection/core/common/json.h"  // jsonEscape, with the reports

namespace urban_detection {
namespace core {

/// Nearest-rank percentile (q in [0, 1]) of `v`; NaN when `v` is empty.
double percentile(std::vector<double> v, double q);

/// Median of `v` (mean of the two middle values for an even count); NaN when `v` is empty.
double median(std::vector<double> v);

/// A JSON number with 6 significant digits, or null when `v` is not finite.
std::string jsonNumber(double v);

/// printf into a string: appends the formatted text to `*out` (the reports' text tables).
template <class... A>
void appendf(std::string* out, const char* format, A... args) {
  const int n = std::snprintf(nullptr, 0, format, args...);
  if (n <= 0) return;
  std::string text(static_cast<std::size_t>(n) + 1, '\0');
  std::snprintf(text.data(), text.size(), format, args...);
  text.resize(static_cast<std::size_t>(n));
  *out += text;
}

/// One line (or dot set) of a plot.
struct Series {
  std::vector<double> x, y;
  cv::Scalar colour;
  std::string label;
  bool points = false;  // draw dots instead of a line
};

/// Writes a simple x/y plot (linear axes, grid, legend) to `png`. Returns false on failure
/// (an empty x range, ymax <= ymin, or the file cannot be written).
bool plotSeries(const std::string& png, const std::string& title, const std::string& xlabel,
                const std::vector<Series>& series, double ymin, double ymax);

}  // namespace core
}  // namespace urban_detection
