#include "urban_detection/core/evaluation/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace urban_detection {
namespace core {

/// Nearest-rank percentile (q in [0, 1]) of `v`; NaN when `v` is empty.
double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

/// Median of `v` (mean of the two middle values for an even count); NaN when `v` is empty.
double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// A JSON number with 6 significant digits, or null when `v` is not finite.
std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char b[32];
  std::snprintf(b, sizeof(b), "%.6g", v);
  return b;
}

/// Writes a simple x/y plot (linear axes, grid, legend) to `png`. Returns false on failure.
bool plotSeries(const std::string& png, const std::string& title, const std::string& xlabel,
                const std::vector<Series>& series, double ymin, double ymax) {
  const int w = 900, h = 560, l = 70, r = 20, t = 40, b = 60;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  double xmin = 1e300, xmax = -1e300;
  for (const Series& s : series) {
    for (const double v : s.x) {
      xmin = std::min(xmin, v);
      xmax = std::max(xmax, v);
    }
  }
  if (!(xmax > xmin) || !(ymax > ymin)) return false;
  auto px = [&](double x) { return l + (x - xmin) / (xmax - xmin) * (w - l - r); };
  auto py = [&](double y) {
    y = std::clamp(y, ymin, ymax);
    return h - b - (y - ymin) / (ymax - ymin) * (h - t - b);
  };
  for (int i = 0; i <= 10; ++i) {
    const double gx = xmin + (xmax - xmin) * i / 10.0, gy = ymin + (ymax - ymin) * i / 10.0;
    cv::line(img, cv::Point(px(gx), t), cv::Point(px(gx), h - b), cv::Scalar(225, 225, 225));
    cv::line(img, cv::Point(l, py(gy)), cv::Point(w - r, py(gy)), cv::Scalar(225, 225, 225));
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.3g", gx);
    cv::putText(img, buf, cv::Point(px(gx) - 12, h - b + 18), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0));
    std::snprintf(buf, sizeof(buf), "%.3g", gy);
    cv::putText(img, buf, cv::Point(8, py(gy) + 4), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0));
  }
  cv::rectangle(img, cv::Point(l, t), cv::Point(w - r, h - b), cv::Scalar(0, 0, 0));
  cv::putText(img, title, cv::Point(l, 25), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0));
  cv::putText(img, xlabel, cv::Point(w / 2 - 40, h - 15), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0));
  int ly = t + 20;
  for (const Series& s : series) {
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      const cv::Point p(px(s.x[i]), py(s.y[i]));
      if (s.points) {
        cv::circle(img, p, 3, s.colour, cv::FILLED);
      } else if (i > 0) {
        cv::line(img, cv::Point(px(s.x[i - 1]), py(s.y[i - 1])), p, s.colour, 2, cv::LINE_AA);
      }
    }
    cv::line(img, cv::Point(w - r - 250, ly - 4), cv::Point(w - r - 220, ly - 4), s.colour, 3);
    cv::putText(img, s.label, cv::Point(w - r - 210, ly), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(0, 0, 0));
    ly += 20;
  }
  return cv::imwrite(png, img);
}

}  // namespace core
}  // namespace urban_detection
