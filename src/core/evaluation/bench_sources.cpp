#include "urban_detection/core/evaluation/bench_sources.h"

#include <time.h>

#include <cstdio>
#include <utility>

#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace core {

using Clock = std::chrono::steady_clock;

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

StageTimer::StageTimer() : wall_(Clock::now()), cpu_(threadCpuMs()) {}

void StageTimer::stop(const std::string& name, std::map<std::string, std::vector<double>>* wall,
                      std::map<std::string, std::vector<double>>* cpu, double* wall_total,
                      double* cpu_total) const {
  const double w = msSince(wall_), c = threadCpuMs() - cpu_;
  (*wall)[name].push_back(w);
  (*cpu)[name].push_back(c);
  if (wall_total) *wall_total += w;
  if (cpu_total) *cpu_total += c;
}

FileRevolutionSource::FileRevolutionSource(const std::string& dir, std::vector<std::string> files,
                                           bool pcd)
    : dir_(dir), files_(std::move(files)), pcd_(pcd) {}

bool FileRevolutionSource::next(CloudXYZIRT* cloud, double* decode_ms, double* decode_cpu_ms) {
  while (pos_ < files_.size()) {
    std::string err;
    const std::string& f = files_[pos_++];
    const bool ok = pcd_ ? readPcdXyzi(f, cloud, &err) : readKittiBin(f, cloud, &err);
    if (ok) {
      *decode_ms = -1.0;
      *decode_cpu_ms = -1.0;
      return true;
    }
    std::fprintf(stderr, "warning: skipping %s: %s\n", f.c_str(), err.c_str());
  }
  return false;
}

std::string FileRevolutionSource::describe() const {
  return dir_ + " (" + std::to_string(files_.size()) +
         (pcd_ ? " PCD sweeps)" : " KITTI .bin scans)");
}

PcapRevolutionSource::PcapRevolutionSource(const std::string& path, const Calibration& calib)
    : path_(path), reader_(path), decoder_(calib, DecoderParams()) {}

bool PcapRevolutionSource::next(CloudXYZIRT* cloud, double* decode_ms, double* decode_cpu_ms) {
  cloud->clear();
  if (reader_.next(&revolution_) != PcapRevolutionReader::Result::kRevolution) return false;
  const double rev_start_s = revolution_[0].stamp_s;
  const auto t0 = Clock::now();
  const double c0 = threadCpuMs();
  for (const PcapPacket& p : revolution_) {
    decoder_.decode(p.data.data(), p.data.size(), p.stamp_s - rev_start_s, cloud, &stats_);
  }
  *decode_cpu_ms = threadCpuMs() - c0;
  *decode_ms = msSince(t0);
  return true;
}

std::vector<std::unique_ptr<RevolutionSource>> openRevolutionSources(
    const std::vector<std::string>& pcd_dirs, const std::vector<std::string>& bin_dirs,
    const std::string& pcap, const std::string& calibration_path) {
  std::vector<std::unique_ptr<RevolutionSource>> sources;
  for (const bool pcd : {true, false}) {
    for (const std::string& d : pcd ? pcd_dirs : bin_dirs) {
      auto files = listFiles(d, pcd ? ".pcd" : ".bin");
      if (files.empty())
        std::fprintf(stderr, "warning: no %s files in %s\n", pcd ? ".pcd" : ".bin", d.c_str());
      else
        sources.emplace_back(new FileRevolutionSource(d, files, pcd));
    }
  }
  if (!pcap.empty())
    sources.emplace_back(new PcapRevolutionSource(pcap, loadCalibration(calibration_path)));
  return sources;
}

}  // namespace core
}  // namespace urban_detection
