// Helpers shared by the detection tools (not a tool itself: only src/tools/*.cpp are built as
// executables): option parsing, sweep listing/reading, statistics and JSON output of the
// benchmarks and the evaluator, and a minimal OpenCV line plot.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace tools {

/// The value after option argv[*i] (advancing *i); exits with status 2 naming the option when
/// it is missing.
inline std::string optionValue(int argc, char** argv, int* i, const char* option) {
  if (*i + 1 >= argc) {
    std::fprintf(stderr, "error: %s needs a value\n", option);
    std::exit(2);
  }
  return argv[++*i];
}

/// A non-negative integer option value; exits with status 2 naming the option otherwise.
inline long optionCount(int argc, char** argv, int* i, const char* option) {
  const std::string v = optionValue(argc, argv, i, option);
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (end == v.c_str() || *end != '\0' || x < 0) {
    std::fprintf(stderr, "error: %s needs a non-negative integer, got '%s'\n", option, v.c_str());
    std::exit(2);
  }
  return x;
}

/// A finite number option value; exits with status 2 naming the option otherwise.
inline double optionNumber(int argc, char** argv, int* i, const char* option) {
  const std::string v = optionValue(argc, argv, i, option);
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || *end != '\0' || !std::isfinite(x)) {
    std::fprintf(stderr, "error: %s needs a number, got '%s'\n", option, v.c_str());
    std::exit(2);
  }
  return x;
}

/// The value readers of a tool's option loop, for the option at argv[*i] (each advances *i):
///   for (int i = 1; i < argc; ++i) {
///     const std::string a = argv[i];
///     const OptionArgs arg{argc, argv, &i};
///     if (a == "--out") out = arg.value("--out"); else if (a == "--n") n = arg.count("--n"); ...
struct OptionArgs {
  int argc;
  char** argv;
  int* i;
  std::string value(const char* option) const { return optionValue(argc, argv, i, option); }
  long count(const char* option) const { return optionCount(argc, argv, i, option); }
  double number(const char* option) const { return optionNumber(argc, argv, i, option); }
};

/// Applies the pipeline config files in order over the values in `params`
/// (core::loadPipelineConfigsYaml). Prints the first error and returns false.
inline bool loadConfigs(const std::vector<std::string>& paths, core::PipelineParams* params) {
  std::string err;
  if (core::loadPipelineConfigsYaml(paths, params, &err)) return true;
  std::fprintf(stderr, "error: %s\n", err.c_str());
  return false;
}

/// Nearest-rank percentile (q in [0, 1]) of `v`; NaN when `v` is empty.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

/// Median of `v` (mean of the two middle values for an even count); NaN when `v` is empty.
inline double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// A JSON number with 6 significant digits, or null when `v` is not finite.
inline std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char b[32];
  std::snprintf(b, sizeof(b), "%.6g", v);
  return b;
}

/// `s` as the inside of a JSON string: quotes and backslashes escaped, control characters
/// dropped.
inline std::string jsonEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o;
}

/// Sorted .bin and .pcd files directly in `dir` (a single file is returned as is).
inline std::vector<std::string> listSweeps(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  if (std::filesystem::is_regular_file(dir, ec)) return {dir};
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && (ext == ".bin" || ext == ".pcd")) files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

/// Reads a KITTI .bin or a PCD sweep.
inline bool readSweep(const std::string& path, CloudXYZIRT* cloud, std::string* error) {
  const std::string ext = std::filesystem::path(path).extension().string();
  return ext == ".bin" ? core::readKittiBin(path, cloud, error)
                       : core::readPcdXyzi(path, cloud, error);
}

struct Series {
  std::vector<double> x, y;
  cv::Scalar colour;
  std::string label;
  bool points = false;  // draw dots instead of a line
};

/// Writes a simple x/y plot (linear axes, grid, legend) to `png`. Returns false on failure.
inline bool plotSeries(const std::string& png, const std::string& title, const std::string& xlabel,
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

}  // namespace tools
}  // namespace urban_detection
