// urban_detection_cell_fitness: the cell fitness curve of paper Sec. 4 (Fig. 6a), for choosing
// the coarse grid resolution.
//
//   urban_detection_cell_fitness [--png OUT.png] [--tmin 20] [--range 40] [--whole-cloud]
//                                DIR_OR_FILE...
//
// Every sweep goes through the segmentation (GridSegmenter, default parameters) and the
// foreground (short street objects: what the detector grids) is gridded at cell sizes
// 0.20, 0.25, ..., 1.50 m within `range` m of the sensor; dense, sparse and empty cells are
// counted over all sweeps and f = dense / (dense + sparse + empty) (cell_fitness.h: empty cells
// are those 8-adjacent to a non-empty cell). Prints the curve and its maximum; optional PNG.
// --whole-cloud grids every point instead of the foreground.
#include "urban_detection/core/common/point_types.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tool_common.h"
#include "urban_detection/core/detection/cell_fitness.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

using namespace urban_detection;

int main(int argc, char** argv) {
  std::string png;
  std::size_t tmin = 20;
  double range = 40.0;
  bool whole = false;
  std::vector<std::string> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--png" && i + 1 < argc) {
      png = argv[++i];
    } else if (a == "--tmin" && i + 1 < argc) {
      tmin = static_cast<std::size_t>(std::max(1, std::atoi(argv[++i])));
    } else if (a == "--range" && i + 1 < argc) {
      range = std::atof(argv[++i]);
    } else if (a == "--whole-cloud") {
      whole = true;
    } else if (a.rfind("--", 0) == 0 || a == "-h") {
      std::fprintf(stderr,
                   "usage: %s [--png OUT.png] [--tmin N] [--range M] [--whole-cloud] "
                   "DIR_OR_FILE...\n",
                   argv[0]);
      return a == "-h" || a == "--help" ? 0 : 2;
    } else {
      inputs.push_back(a);
    }
  }
  if (inputs.empty() || !(range > 0.0 && range <= 200.0)) {
    std::fprintf(stderr, "need at least one input and a range in (0, 200] m\n");
    return 2;
  }
  std::vector<double> sizes;
  for (int k = 0; k <= 26; ++k) sizes.push_back(0.20 + 0.05 * k);
  std::vector<core::CellCounts> counts(sizes.size());

  core::GridSegmenter segmenter;
  CloudXYZIRT cloud;
  std::vector<core::SegmentClass> labels;
  LabeledCloud grid_input;
  std::size_t frames = 0;
  for (const std::string& in : inputs) {
    for (const std::string& f : tools::listSweeps(in)) {
      std::string err;
      if (!tools::readSweep(f, &cloud, &err)) {
        std::fprintf(stderr, "warning: skipping %s: %s\n", f.c_str(), err.c_str());
        continue;
      }
      if (whole) {
        labels.assign(cloud.size(), core::SegmentClass::kShort);
        core::extractForeground(cloud, labels, &grid_input);
      } else {
        core::segmentForeground(segmenter, cloud, &labels, &grid_input);
      }
      for (std::size_t k = 0; k < sizes.size(); ++k) {
        core::countCells(grid_input, sizes[k], range, tmin, &counts[k]);
      }
      ++frames;
    }
  }
  if (frames == 0) {
    std::fprintf(stderr, "no sweep could be read\n");
    return 1;
  }
  std::printf("# %zu sweeps, %s within %.0f m, t_min = %zu\n", frames,
              whole ? "whole cloud" : "foreground", range, tmin);
  std::printf("# cell [m]   dense   sparse    empty   fitness\n");
  std::size_t best = 0;
  std::vector<double> f(sizes.size());
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    f[k] = counts[k].fitness();
    if (f[k] > f[best]) best = k;
    std::printf("%9.2f %8zu %8zu %8zu  %.4f\n", sizes[k], counts[k].dense, counts[k].sparse,
                counts[k].empty, f[k]);
  }
  std::printf("maximum fitness %.4f at %.2f m\n", f[best], sizes[best]);
  if (!png.empty()) {
    const bool ok =
        tools::plotSeries(png, "Cell fitness f = #d / (#d + #s + #e)", "grid cell size [m]",
                          {{sizes, f, cv::Scalar(200, 80, 0), "fitness", false},
                           {sizes, f, cv::Scalar(200, 80, 0), "", true}},
                          0.0, std::max(0.05, f[best] * 1.15));
    std::printf(ok ? "wrote %s\n" : "could not write %s\n", png.c_str());
  }
  return 0;
}
