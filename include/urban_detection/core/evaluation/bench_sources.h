/// \file bench_sources.h
/// What the benchmarks (urban_detection_bench, _bench_detection, _bench_segmentation) time with
/// and read: the thread-CPU clock, a stage timer keeping wall and CPU time apart, and
/// revolution sources (KITTI .bin / PCD files, or the packets of a pcap decoded in one timed
/// block per revolution). ROS-free.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"

namespace urban_detection {
namespace core {

/// [ms] CPU time of the calling thread.
double threadCpuMs();

/// [ms] wall time since `t0`.
double msSince(std::chrono::steady_clock::time_point t0);

/// Wall and thread-CPU time of one stage. On a machine shared with other jobs the wall time
/// includes time the thread waited for the core; the CPU time does not.
class StageTimer {
 public:
  StageTimer();
  /// Appends the times since construction to (*wall)[name] and (*cpu)[name], and adds them to
  /// the totals when given.
  void stop(const std::string& name, std::map<std::string, std::vector<double>>* wall,
            std::map<std::string, std::vector<double>>* cpu, double* wall_total = nullptr,
            double* cpu_total = nullptr) const;

 private:
  std::chrono::steady_clock::time_point wall_;
  double cpu_;
};

/// A source of revolutions: clouds from files, or packets decoded into clouds.
class RevolutionSource {
 public:
  virtual ~RevolutionSource() = default;
  /// Next revolution into `cloud`; `decode_ms` / `decode_cpu_ms` are the wall / thread-CPU
  /// decode time (negative: no packets). Returns false at the end.
  virtual bool next(CloudXYZIRT* cloud, double* decode_ms, double* decode_cpu_ms) = 0;
  virtual void rewind() = 0;
  virtual std::string describe() const = 0;
};

/// Sweep files of one folder (PCD or KITTI .bin); unreadable ones are skipped with a warning
/// on stderr.
class FileRevolutionSource : public RevolutionSource {
 public:
  FileRevolutionSource(const std::string& dir, std::vector<std::string> files, bool pcd);
  bool next(CloudXYZIRT* cloud, double* decode_ms, double* decode_cpu_ms) override;
  void rewind() override { pos_ = 0; }
  std::string describe() const override;

 private:
  std::string dir_;
  std::vector<std::string> files_;
  bool pcd_;
  std::size_t pos_ = 0;
};

/// The packets of a pcap, cut into revolutions as everywhere else (PcapRevolutionReader); a
/// revolution's packets are read first (not timed) and then decoded in one timed block, since
/// timing every packet would add two clock reads per packet to the figure.
class PcapRevolutionSource : public RevolutionSource {
 public:
  PcapRevolutionSource(const std::string& path, const Calibration& calib);
  bool next(CloudXYZIRT* cloud, double* decode_ms, double* decode_cpu_ms) override;
  void rewind() override { reader_.rewind(); }
  std::string describe() const override { return "packets of " + path_; }

 private:
  std::string path_;
  PcapRevolutionReader reader_;
  PacketDecoder decoder_;
  std::vector<PcapPacket> revolution_;  // the current revolution's packets (reused)
  DecodeStats stats_;
};

/// The sources of a benchmark run in order: one FileRevolutionSource per folder of
/// `pcd_dirs` (.pcd) and `bin_dirs` (.bin) that holds such files (a warning on stderr for one
/// that does not), then the pcap when given (`calibration_path` empty: nominal). Throws
/// std::runtime_error when the calibration cannot be loaded.
std::vector<std::unique_ptr<RevolutionSource>> openRevolutionSources(
    const std::vector<std::string>& pcd_dirs, const std::vector<std::string>& bin_dirs,
    const std::string& pcap, const std::string& calibration_path);

}  // namespace core
}  // namespace urban_detection
