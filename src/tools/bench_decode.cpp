// Decode benchmark: one 600 rpm HDL-64E revolution (348 packets, 133,632 returns) of a synthetic
// street scene, encoded with the packet encoder and decoded with the given calibration.
//
//   taskset -c 0 urban_detection_bench_decode [--calibration=FILE] [benchmark flags]
//
// Without --calibration the SZTAKI S2.1 file is taken from $UD_SHARED_DATA/calibration (or
// ../shared/data/calibration), else the nominal geometry. Each iteration decodes the whole
// revolution into a reused cloud; the per-revolution times are kept and reported as median,
// p95 and points per second (counters; wall clock, and cpu_* from the thread CPU clock, which
// is robust to other load on a shared VM), besides Google Benchmark's own mean.
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "tool_common.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/synthetic_scene.h"

namespace uc = urban_detection::core;

using urban_detection::tools::percentile;

namespace {

std::string g_calibration_path;
constexpr int kPacketsPerRevolution = 348;

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + ts.tv_nsec * 1e-9;
}

std::string kittiScanPath() {
  const char* env = std::getenv("UD_SHARED_DATA");
  return std::string(env != nullptr ? env : "../shared/data") + "/kitti_object/velodyne/000000.bin";
}

// state.range(0): 0 = synthetic street (every return valid), 1 = range pattern of a real KITTI
// scan (with its no-return slots).
void BM_DecodeRevolution600Rpm(benchmark::State& state) {
  const uc::Calibration cal = uc::findCalibration(g_calibration_path);
  const uc::PacketEncoder encoder(cal);
  std::vector<uc::RawPacket> packets;
  std::string label = cal.source;
  if (state.range(0) == 0) {
    uc::SyntheticSceneParams scene;
    scene.rpm = 600.0;
    packets = uc::scanScene(encoder, scene, kPacketsPerRevolution);
    label += ", synthetic street";
  } else {
    const std::vector<float> xyz = uc::readKittiBinXyz(kittiScanPath());
    if (xyz.empty()) {
      state.SkipWithError(("KITTI scan not found: " + kittiScanPath()).c_str());
      return;
    }
    packets = uc::packetsFromScan(encoder, xyz, 600.0, kPacketsPerRevolution);
    label += ", range pattern of " + kittiScanPath();
  }
  uc::PacketDecoder decoder(cal, uc::DecoderParams{});
  urban_detection::CloudXYZIRT cloud;
  cloud.reserve(kPacketsPerRevolution * 384);
  std::vector<double> times_s, cpu_s;
  times_s.reserve(1 << 16);
  cpu_s.reserve(1 << 16);
  std::size_t points = 0, no_return = 0;

  for (auto _ : state) {
    const double c0 = threadCpuSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    cloud.clear();
    uc::DecodeStats stats;
    for (int i = 0; i < kPacketsPerRevolution; ++i) {
      decoder.decode(packets[i].data(), packets[i].size(), i * 6 * uc::kFiringPeriodS, &cloud,
                     &stats);
    }
    benchmark::DoNotOptimize(cloud.points.data());
    benchmark::ClobberMemory();
    const auto t1 = std::chrono::steady_clock::now();
    times_s.push_back(std::chrono::duration<double>(t1 - t0).count());
    cpu_s.push_back(threadCpuSeconds() - c0);
    points = stats.points;
    no_return = stats.no_return;
  }
  const double median = percentile(times_s, 0.5), p95 = percentile(times_s, 0.95);
  state.counters["points"] = static_cast<double>(points);
  state.counters["median_ms"] = median * 1e3;
  state.counters["p95_ms"] = p95 * 1e3;
  // Thread CPU time excludes the time the VM or other processes took the core away.
  state.counters["cpu_median_ms"] = percentile(cpu_s, 0.5) * 1e3;
  state.counters["cpu_p95_ms"] = percentile(cpu_s, 0.95) * 1e3;
  // Returns = every distance slot of the revolution (348 x 384 = 133,632), valid or not.
  state.counters["Mreturns_per_s_median"] =
      median > 0 ? kPacketsPerRevolution * 384.0 / median / 1e6 : 0.0;
  state.counters["Mpoints_per_s_median"] = median > 0 ? points / median / 1e6 : 0.0;
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(points));
  state.counters["no_return"] = static_cast<double>(no_return);
  state.SetLabel(label);
}

}  // namespace

BENCHMARK(BM_DecodeRevolution600Rpm)
    ->ArgName("kitti_pattern")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--calibration=", 0) == 0) {
      g_calibration_path = arg.substr(14);
    } else {
      std::fprintf(stderr, "usage: %s [--calibration=FILE] [--benchmark_* flags]\n", argv[0]);
      return 2;
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
