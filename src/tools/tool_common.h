// Helpers shared by the command-line tools (not a tool itself: only src/tools/*.cpp are built
// as executables): option parsing and config loading; the sweep readers, statistics, JSON and
// plot helpers live in the core (core/evaluation/datasets.h, report.h).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/params/params_yaml.h"

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

// The report and sweep helpers of the core, named here as the tools have always called them.
using core::jsonEscape;
using core::jsonNumber;
using core::listSweeps;
using core::median;
using core::percentile;
using core::plotSeries;
using core::readSweep;
using core::Series;

}  // namespace tools
}  // namespace urban_detection
