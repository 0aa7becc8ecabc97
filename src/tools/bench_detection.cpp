// urban_detection_bench_detection: detection speed on real foregrounds (paper Sec. 5, Table 1).
//
//   taskset -c 0 urban_detection_bench_detection [--data DIR]... [--passes N]
//                                                [--kdtree-passes N] [--digest [--dump FILE]]
//                                                [--stats] [benchmark flags]
//
// Every sweep of DIR (default: ../shared/data/kitti_raw/drive_0005 and drive_0048, KITTI .bin
// or PCD) goes through the segmentation (GridSegmenter with default parameters,
// extractForeground) once; then the hierarchical grid detector and the kd-tree baseline run on
// the same foregrounds in the same process. Prints Google Benchmark results (mean time per
// revolution over all frames; compare its CPU column) and a per-revolution distribution of
// thread CPU time: median and p95 [ms] for each
// detector over `passes` passes over the frames, and the speed ratio of the medians.
//
// --digest: instead of timing, prints one 64-bit FNV-1a digest per detector of all its outputs
// over the frames (object count, ids, index lists and the bit patterns of every centroid, box
// and oriented-box float), so a speed change can be checked to leave the outputs bit-identical
// by comparing two builds' digests (the kd-tree one is skipped with --kdtree-passes 0).
// --dump FILE (with --digest): also writes every hierarchical object as one text line (frame,
// id, point count, then the 16 box floats with 9 significant digits) to compare two builds
// field by field when the digests differ.
// --stats: instead of timing, prints the hierarchical grid's stats (HierarchicalGridStats)
// averaged per revolution: how many cells, links and objects the timed work handles.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "tool_common.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/evaluation/bench_sources.h"
#include "urban_detection/core/evaluation/output_digest.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

using namespace urban_detection;
using urban_detection::core::threadCpuMs;

namespace {

std::vector<LabeledCloud> g_frames;

void runAll(core::ObjectDetector* det, benchmark::State& state) {
  std::vector<core::DetectedObject> objects;
  std::size_t i = 0, n_obj = 0;
  for (auto _ : state) {
    det->detect(g_frames[i], &objects);
    benchmark::DoNotOptimize(objects.data());
    n_obj += objects.size();
    i = (i + 1) % g_frames.size();
  }
  state.counters["objects_per_frame"] =
      benchmark::Counter(static_cast<double>(n_obj) / state.iterations());
}

void BM_HierarchicalGrid(benchmark::State& state) {
  core::HierarchicalGridDetector det;
  runAll(&det, state);
}

void BM_KdTree(benchmark::State& state) {
  core::KdTreeDetector det;
  runAll(&det, state);
}

struct Distribution {
  double median_ms = 0, p95_ms = 0, mean_ms = 0, objects = 0;
};

Distribution measure(core::ObjectDetector* det, int passes) {
  std::vector<double> ms;
  std::vector<core::DetectedObject> objects;
  double n_obj = 0;
  for (int p = 0; p < passes; ++p) {
    for (const LabeledCloud& f : g_frames) {
      const double t0 = threadCpuMs();
      det->detect(f, &objects);
      ms.push_back(threadCpuMs() - t0);
      n_obj += objects.size();
    }
  }
  Distribution d;
  std::sort(ms.begin(), ms.end());
  d.median_ms = ms[ms.size() / 2];
  d.p95_ms = ms[std::min(ms.size() - 1, static_cast<std::size_t>(0.95 * ms.size()))];
  for (const double v : ms) d.mean_ms += v / ms.size();
  d.objects = n_obj / ms.size();
  return d;
}

void printStats() {
  core::HierarchicalGridDetector det;
  std::vector<core::DetectedObject> objects;
  double sum[15] = {};
  const char* names[15] = {"input_points",  "invalid_points", "outside_points", "coarse_cells",
                           "coarse_blobs",  "dense_cells",    "dense_occupied", "bridges",
                           "roof_bridges",  "noise_points",   "components",     "dropped_small",
                           "dropped_large", "far_joins",      "objects"};
  for (const LabeledCloud& f : g_frames) {
    det.detect(f, &objects);
    const core::HierarchicalGridStats& s = det.stats();
    const std::size_t v[15] = {s.input_points,  s.invalid_points, s.outside_points, s.coarse_cells,
                               s.coarse_blobs,  s.dense_cells,    s.dense_occupied, s.bridges,
                               s.roof_bridges,  s.noise_points,   s.components,     s.dropped_small,
                               s.dropped_large, s.far_joins,      s.objects};
    for (int k = 0; k < 15; ++k) sum[k] += static_cast<double>(v[k]);
  }
  std::printf("hierarchical_grid stats, mean per revolution:\n");
  for (int k = 0; k < 15; ++k) std::printf("  %-15s %10.1f\n", names[k], sum[k] / g_frames.size());
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> dirs;
  int passes = 20, kd_passes = 1;
  bool digest = false, stats = false;
  std::string dump_path;
  std::vector<char*> bench_args = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--data") && i + 1 < argc) {
      dirs.push_back(argv[++i]);
    } else if (!std::strcmp(argv[i], "--passes") && i + 1 < argc) {
      passes = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--kdtree-passes") && i + 1 < argc) {
      kd_passes = std::max(0, std::atoi(argv[++i]));  // 0: skip
    } else if (!std::strcmp(argv[i], "--digest")) {
      digest = true;
    } else if (!std::strcmp(argv[i], "--stats")) {
      stats = true;
    } else if (!std::strcmp(argv[i], "--dump") && i + 1 < argc) {
      dump_path = argv[++i];
    } else {
      bench_args.push_back(argv[i]);
    }
  }
  if (dirs.empty()) {
    const char* env = std::getenv("UD_SHARED_DATA");
    const std::string root = env ? env : "../shared/data";
    dirs = {root + "/kitti_raw/drive_0005", root + "/kitti_raw/drive_0048"};
  }
  core::GridSegmenter segmenter;
  CloudXYZIRT cloud;
  std::vector<core::SegmentClass> labels;
  std::size_t points = 0, fg_points = 0;
  for (const std::string& dir : dirs) {
    for (const std::string& f : tools::listSweeps(dir)) {
      std::string err;
      if (!tools::readSweep(f, &cloud, &err)) {
        std::fprintf(stderr, "skipping %s: %s\n", f.c_str(), err.c_str());
        continue;
      }
      g_frames.emplace_back();
      core::segmentForeground(segmenter, cloud, &labels, &g_frames.back());
      points += cloud.size();
      fg_points += g_frames.back().size();
    }
  }
  if (g_frames.empty()) {
    std::fprintf(stderr, "no sweep found in the data directories (--data DIR); nothing to do\n");
    return 1;
  }
  std::printf("%zu revolutions, %.0f points and %.0f foreground points per revolution\n",
              g_frames.size(), static_cast<double>(points) / g_frames.size(),
              static_cast<double>(fg_points) / g_frames.size());

  if (stats) {
    printStats();
    return 0;
  }
  if (digest) {
    core::HierarchicalGridDetector grid;
    std::FILE* dump = dump_path.empty() ? nullptr : std::fopen(dump_path.c_str(), "w");
    if (!dump_path.empty() && !dump) {
      std::fprintf(stderr, "cannot write %s\n", dump_path.c_str());
      return 1;
    }
    std::printf("digest hierarchical_grid %016" PRIx64 "\n",
                core::detectionsDigest(&grid, g_frames, dump));
    if (dump) std::fclose(dump);
    if (kd_passes > 0) {
      core::KdTreeDetector kd;
      std::printf("digest kdtree %016" PRIx64 "\n", core::detectionsDigest(&kd, g_frames));
    }
    return 0;
  }

  benchmark::RegisterBenchmark("HierarchicalGrid/revolution", BM_HierarchicalGrid)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("KdTree/revolution", BM_KdTree)
      ->Unit(benchmark::kMillisecond)
      ->Iterations(static_cast<benchmark::IterationCount>(g_frames.size()));
  int bargc = static_cast<int>(bench_args.size());
  benchmark::Initialize(&bargc, bench_args.data());
  benchmark::RunSpecifiedBenchmarks();

  core::HierarchicalGridDetector grid;
  core::KdTreeDetector kd;
  const Distribution g = measure(&grid, passes);
  const Distribution k = kd_passes > 0 ? measure(&kd, kd_passes) : Distribution();
  std::printf("\nper revolution (thread CPU time, %zu frames):\n", g_frames.size());
  std::printf("  %-18s median %8.3f ms  p95 %8.3f ms  mean %8.3f ms  %.1f objects  (%d passes)\n",
              "hierarchical_grid", g.median_ms, g.p95_ms, g.mean_ms, g.objects, passes);
  std::printf("  %-18s median %8.3f ms  p95 %8.3f ms  mean %8.3f ms  %.1f objects  (%d passes)\n",
              "kdtree", k.median_ms, k.p95_ms, k.mean_ms, k.objects, kd_passes);
  std::printf("  speed ratio (kdtree / hierarchical_grid, medians): %.0fx\n",
              k.median_ms / g.median_ms);
  return 0;
}
