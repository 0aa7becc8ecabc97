// urban_detection_bench_segmentation: time of the grid segmentation (paper Sec. 3.1) per
// revolution on real KITTI HDL-64E sweeps, with and without the Hough wall refinement.
//
//   taskset -c 0 urban_detection_bench_segmentation [--data=DIR] [benchmark flags]
//   DIR defaults to $UD_SHARED_DATA/kitti_raw/drive_0048 (binary PCD x y z intensity).
// --data may be repeated (e.g. both kitti_raw drives, as the full urban_detection_bench uses).
// Besides Google Benchmark's mean, the counters median_ms / p95_ms (wall) and cpu_median_ms /
// cpu_p95_ms (thread CPU time) are over single frames. The *ColdCache variant writes 16 MB of
// other memory before each (timed) frame, as the other stages of the full pipeline do between
// two segmentations, so the segmenter's scratch buffers are out of L1/L2 as in
// urban_detection_bench.
#include "urban_detection/core/common/point_types.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "urban_detection/core/evaluation/bench_sources.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/kitti_io.h"

namespace {

namespace core = urban_detection::core;
using core::threadCpuMs;
std::vector<urban_detection::CloudXYZIRT> g_frames;
std::vector<char> g_pollution(std::size_t{16} << 20);

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5));
  return v[i];
}

void runSegmentation(benchmark::State& state, bool hough, bool cold_cache = false) {
  if (g_frames.empty()) {
    state.SkipWithError("no KITTI frames loaded (data absent?)");
    return;
  }
  core::GridSegmenterParams p;
  p.hough.enabled = hough;
  core::GridSegmenter seg(p);
  std::vector<core::SegmentClass> labels;
  for (const auto& f : g_frames) seg.segment(f, &labels);  // warm the scratch buffers
  std::vector<double> ms, cpu_ms;
  std::size_t k = 0, points = 0;
  for (auto _ : state) {
    const auto& frame = g_frames[k++ % g_frames.size()];
    if (cold_cache) {
      state.PauseTiming();
      std::memset(g_pollution.data(), static_cast<int>(k & 0x7f), g_pollution.size());
      benchmark::ClobberMemory();
      state.ResumeTiming();
    }
    const double c0 = threadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    seg.segment(frame, &labels);
    const auto t1 = std::chrono::steady_clock::now();
    cpu_ms.push_back(threadCpuMs() - c0);
    benchmark::DoNotOptimize(labels.data());
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    points += frame.size();
  }
  state.counters["median_ms"] = percentile(ms, 0.5);
  state.counters["p95_ms"] = percentile(ms, 0.95);
  state.counters["cpu_median_ms"] = percentile(cpu_ms, 0.5);
  state.counters["cpu_p95_ms"] = percentile(cpu_ms, 0.95);
  state.counters["points"] = static_cast<double>(points) / static_cast<double>(ms.size());
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
}

void BM_SegmentWithHough(benchmark::State& state) {
  runSegmentation(state, true);
}
void BM_SegmentWithoutHough(benchmark::State& state) {
  runSegmentation(state, false);
}
void BM_SegmentWithHoughColdCache(benchmark::State& state) {
  runSegmentation(state, true, true);
}
BENCHMARK(BM_SegmentWithHough)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_SegmentWithoutHough)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK(BM_SegmentWithHoughColdCache)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_ExtractForeground(benchmark::State& state) {
  if (g_frames.empty()) {
    state.SkipWithError("no KITTI frames loaded (data absent?)");
    return;
  }
  core::GridSegmenter seg;
  std::vector<core::SegmentClass> labels;
  urban_detection::LabeledCloud fg;
  core::segmentForeground(seg, g_frames[0], &labels, &fg);
  for (auto _ : state) {
    core::extractForeground(g_frames[0], labels, &fg);
    benchmark::DoNotOptimize(fg.points.data());
  }
}
BENCHMARK(BM_ExtractForeground)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  const char* env = std::getenv("UD_SHARED_DATA");
  std::vector<std::string> dirs;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--data=", 7) == 0) {
      dirs.push_back(argv[i] + 7);
    } else {
      args.push_back(argv[i]);
    }
  }
  if (dirs.empty()) {
    dirs.push_back(std::string(env ? env : "../shared/data") + "/kitti_raw/drive_0048");
  }
  for (const std::string& dir : dirs) {
    std::vector<std::string> files;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
      if (e.path().extension() == ".pcd") files.push_back(e.path().string());
    }
    std::sort(files.begin(), files.end());
    std::size_t loaded = 0;
    for (const std::string& f : files) {
      urban_detection::CloudXYZIRT cloud;
      std::string err;
      if (core::readPcdXyzi(f, &cloud, &err)) {
        g_frames.push_back(std::move(cloud));
        ++loaded;
      } else {
        std::fprintf(stderr, "skipping %s: %s\n", f.c_str(), err.c_str());
      }
    }
    std::fprintf(stderr, "%zu KITTI sweeps from %s\n", loaded, dir.c_str());
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
