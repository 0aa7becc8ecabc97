// Demo: a generated HDL-64E packet stream of a small street scene (ground, walls, one box) is
// cut into revolutions at the cut angle and decoded; prints packets, points and decode time per
// revolution. Replaced by the full simulated drive later.
//
//   urban_detection_demo [--calibration FILE] [--revolutions N] [--rpm R] [--cut-angle DEG]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "synthetic_scene.h"
#include "urban_detection/core/hdl64e_packet.h"

namespace uc = urban_detection::core;
namespace ut = urban_detection::tools;

namespace {

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s [--calibration FILE(.yaml|.xml)] [--revolutions N (1..1000)] "
               "[--rpm R (300..1200)] [--cut-angle DEG]\n",
               argv0);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string calibration_path;
  int revolutions = 5;
  double rpm = 600.0, cut_deg = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--calibration" && has_value) {
      calibration_path = argv[++i];
    } else if (arg == "--revolutions" && has_value) {
      revolutions = std::atoi(argv[++i]);
    } else if (arg == "--rpm" && has_value) {
      rpm = std::atof(argv[++i]);
    } else if (arg == "--cut-angle" && has_value) {
      cut_deg = std::atof(argv[++i]);
    } else {
      return usage(argv[0]);
    }
  }
  if (revolutions < 1 || revolutions > 1000 || !(rpm >= 300.0 && rpm <= 1200.0)) {
    return usage(argv[0]);
  }

  uc::Calibration cal;
  try {
    cal = ut::findCalibration(calibration_path);
  } catch (const uc::CalibrationError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  std::printf("calibration: %s\n", cal.source.c_str());

  // Enough packets for the requested whole revolutions plus the partial one before the
  // first cut; the scan starts 37 deg past the cut.
  ut::SceneParams scene;
  scene.rpm = rpm;
  const double packets_per_rev = 60.0 / rpm / (6 * uc::kFiringPeriodS);
  const int total = static_cast<int>((revolutions + 1) * packets_per_rev) + 2;
  const std::vector<uc::RawPacket> stream =
      ut::scanScene(uc::PacketEncoder(cal), scene, total, cut_deg + 37.0);
  std::printf("stream: %d packets at %.0f rpm (%.1f packets/revolution), cut at %.1f deg\n", total,
              rpm, packets_per_rev, cut_deg);

  uc::PacketDecoder decoder(cal, uc::DecoderParams{});
  uc::RevolutionCutter cutter(cut_deg);
  urban_detection::CloudXYZIRT cloud;
  cloud.reserve(static_cast<std::size_t>(packets_per_rev + 2) * 384);  // no growth while timing
  std::vector<const uc::RawPacket*> revolution;
  bool whole = false;  // the current revolution started at a cut
  int done = 0;
  double total_ms = 0.0;
  std::size_t total_points = 0;

  auto flush = [&]() {
    if (!whole || revolution.empty()) return;
    const auto t0 = std::chrono::steady_clock::now();
    cloud.clear();
    uc::DecodeStats stats;
    for (std::size_t i = 0; i < revolution.size(); ++i) {
      decoder.decode(revolution[i]->data(), revolution[i]->size(), i * 6 * uc::kFiringPeriodS,
                     &cloud, &stats);
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++done;
    total_ms += ms;
    total_points += stats.points;
    std::printf(
        "revolution %d: %zu packets, %zu points, %zu no return, %zu out of range, "
        "%zu bad packets, decode %.3f ms\n",
        done, stats.packets, stats.points, stats.no_return, stats.out_of_range, stats.bad_packets,
        ms);
  };

  for (const uc::RawPacket& packet : stream) {
    if (done >= revolutions) break;
    if (cutter.startsNewRevolution(uc::blockAzimuth(packet.data(), 0))) {
      flush();
      revolution.clear();
      whole = true;
    }
    revolution.push_back(&packet);
  }
  if (done < revolutions) flush();  // the last one if the stream ends exactly at a cut
  if (done > 0) {
    std::printf("summary: %d revolutions, %.0f points/revolution, mean decode %.3f ms\n", done,
                static_cast<double>(total_points) / done, total_ms / done);
  }
  return done == revolutions ? 0 : 1;
}
