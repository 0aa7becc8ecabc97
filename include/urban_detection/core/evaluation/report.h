/// \file report.h
/// What the evaluation and benchmark reports are made of: order statistics (percentile,
/// median), JSON numbers and strings, and a minimal x/y line plot written as a PNG. ROS-free.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace urban_detection {
namespace core {

/// Nearest-rank percentile (q in [0, 1]) of `v`; NaN when `v` is empty.
double percentile(std::vector<double> v, double q);

/// Median of `v` (mean of the two middle values for an even count); NaN when `v` is empty.
double median(std::vector<double> v);

/// A JSON number with 6 significant digits, or null when `v` is not finite.
std::string jsonNumber(double v);

/// `s` as the inside of a JSON string: quotes and backslashes escaped, control characters
/// dropped (the evaluation's reports; core/spark's jsonEscape writes them as \u00XX).
std::string jsonStringContent(const std::string& s);

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
