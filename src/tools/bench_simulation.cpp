// urban_detection_bench_simulation: time to simulate one revolution of the default drive
// (config/demo_drive.yaml, nominal HDL-64E S2): ray casting of every laser of every firing,
// noise, packet encoding and ground truth. One revolution per repetition, so the median and p95
// aggregates are per revolution. Pin it to one core: taskset -c 0 urban_detection_bench_simulation
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <ros/package.h>

#include "urban_detection/core/simulation/simulation_config.h"

#include "tool_common.h"

namespace ud = urban_detection::core;

using urban_detection::tools::percentile;

namespace {

std::string configPath() {
  const std::string pkg = ros::package::getPath("urban_detection");
  return (pkg.empty() ? std::string(".") : pkg) + "/config/demo_drive.yaml";
}

void BM_SimulateRevolution(benchmark::State& state) {
  static const ud::SimulationConfig base = ud::loadSimulationConfig(configPath());
  ud::SimulationConfig c = base;
  c.sensor.rpm = static_cast<double>(state.range(0));
  static std::unique_ptr<ud::LidarSimulator> sim;
  static double rpm = 0.0;
  if (!sim || rpm != c.sensor.rpm) {  // one simulator per rpm, driving on across repetitions
    sim =
        std::make_unique<ud::LidarSimulator>(ud::generateScene(c.scene, c.drive), c.scene, c.drive,
                                             ud::Calibration::nominalHdl64eS2(), c.sensor);
    rpm = c.sensor.rpm;
  }
  ud::SimRevolution rev;
  std::size_t rays = 0, returns = 0;
  for (auto _ : state) {
    if (sim->driveFinished()) {
      state.PauseTiming();
      sim->reset();
      state.ResumeTiming();
    }
    sim->simulateNext(&rev);
    benchmark::DoNotOptimize(rev.packets.data());
    rays += rev.stats.rays;
    returns += rev.stats.returns;
  }
  state.counters["rays"] = benchmark::Counter(static_cast<double>(rays) / state.iterations());
  state.counters["returns"] = benchmark::Counter(static_cast<double>(returns) / state.iterations());
}
BENCHMARK(BM_SimulateRevolution)
    ->Arg(600)
    ->Arg(300)
    ->Arg(1200)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(100)
    ->ComputeStatistics("p95", [](const std::vector<double>& v) { return percentile(v, 0.95); })
    ->ReportAggregatesOnly(true);

void BM_GenerateScene(benchmark::State& state) {
  const ud::SimulationConfig c = ud::loadSimulationConfig(configPath());
  for (auto _ : state) {
    ud::Scene s = ud::generateScene(c.scene, c.drive);
    benchmark::DoNotOptimize(s.primitives.data());
  }
}
BENCHMARK(BM_GenerateScene)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
