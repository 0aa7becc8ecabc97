// urban_detection_seg_eval: accuracy of the grid segmentation (paper Sec. 3.1) with and without
// the Hough wall refinement, on SemanticKITTI scans, KITTI object frames or a simulated drive.
//
//   urban_detection_seg_eval [DIR] [-v] [--json FILE] [--config FILE] [--set name=value ...]
//   urban_detection_seg_eval --sim GTFILE --pcap PCAP [--calibration FILE] [--max-frames N] ...
//   urban_detection_seg_eval --kitti-object [DIR] ...
//   DIR defaults to $UD_SHARED_DATA/semantic_kitti/sequences/00 (or ../shared/data/...); it holds
//   velodyne/*.bin and labels/*.label. Points labelled unlabeled (0) or outlier (1) are ignored.
//   --sim scores against the simulator's exact per-point classes (urban_detection_simulate --gt,
//   with the pcap it wrote): ground as ground, walls (facades) out of the foreground, cars,
//   pedestrians and cyclists in the foreground.
#include "urban_detection/core/common/point_types.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/evaluation/segmentation_eval.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/ground_truth.h"

#include "tool_common.h"

namespace fs = std::filesystem;
namespace core = urban_detection::core;
using core::SegCounts;
using core::SegGroup;
using core::SegmentClass;
using core::SegShare;

namespace {

void print(const char* name, const SegCounts& c) {
  const SegShare& wall = c.of(SegGroup::kWall);
  const SegShare& car = c.of(SegGroup::kCar);
  const SegShare& person = c.of(SegGroup::kPerson);
  const SegShare& cyclist = c.of(SegGroup::kCyclist);
  const SegShare& vehicle = c.of(SegGroup::kOtherVehicle);
  std::printf(
      "| %-9s | %6.4f | %6.4f | %6.4f | %6.4f (%ld) | %6.4f (%ld) | %6.4f (%ld) | %6.4f (%ld) "
      "| %6.4f (%ld) | %6.4f | %6.2f |\n",
      name, core::groundPrecision(c), core::groundRecall(c), core::groundF1(c),
      core::notForeground(wall), wall.total, core::foreground(car), car.total,
      core::foreground(person), person.total, core::foreground(cyclist), cyclist.total,
      core::foreground(vehicle), vehicle.total, core::foreground(c.of(SegGroup::kVegPole)),
      c.frames > 0 ? c.ms_total / c.frames : 0.0);
}

void printTable(const SegCounts& on, const SegCounts& off) {
  std::printf(
      "| hough     | gnd P  | gnd R  | gnd F1 | wall not-fg (n)  | car fg (n)       | "
      "person fg (n)    | cyclist fg (n)   | other veh fg (n) | veg/pole fg | ms/scan |\n");
  print("on", on);
  print("off", off);
}

void printConfusion(const char* name, const SegCounts& c) {
  static const char* groups[5] = {"ground", "building+fence", "car", "person+cyclist", "other"};
  std::printf("confusion (hough %s): rows = SemanticKITTI group, columns = predicted share\n",
              name);
  std::printf("  %-15s %8s %8s %8s %8s %8s\n", "", "unknown", "clutter", "ground", "tall", "short");
  for (int g = 0; g < 5; ++g) {
    long n = 0;
    for (int k = 0; k < 5; ++k) n += c.confusion[g][k];
    std::printf("  %-15s", groups[g]);
    for (int k = 0; k < 5; ++k) std::printf(" %8.4f", core::segRatio(c.confusion[g][k], n));
    std::printf("  (%ld)\n", n);
  }
}

// Cell classes around the sensor (core::cellClassesAscii).
void printAscii(const core::GridSegmenter& seg, double half_m) {
  std::fputs(core::cellClassesAscii(seg, half_m).c_str(), stdout);
}

// --set name=value: a number or switch (non-zero: on) of GridSegmenterParams' field table,
// nested fields with a dot ("hough.votes").
bool setParam(core::GridSegmenterParams* p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) return false;
  std::string k = kv.substr(0, eq);
  std::replace(k.begin(), k.end(), '.', '/');
  const double v = std::atof(kv.c_str() + eq + 1);
  bool found = false;
  core::forEachField(*p, [&](const core::FieldInfo& info, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if (info.name != k) return;
    if constexpr (std::is_same_v<T, bool>) {
      field = v != 0.0;
      found = true;
    } else if constexpr (std::is_same_v<T, int>) {
      field = static_cast<int>(v);
      found = true;
    } else if constexpr (std::is_same_v<T, double>) {
      field = v;
      found = true;
    }
  });
  return found;
}

// KITTI object frames: share of the points of labelled objects (inside their 3-D boxes, above
// the ground band, rules of eval_datasets.h) that end up in the foreground, per class.
void evalKittiObject(const std::string& dir, const core::GridSegmenterParams& params,
                     double ascii_half_m) {
  core::KittiObjectSegmentation r;
  if (!core::evaluateKittiObjectSegmentation(dir, params, &r)) {
    std::printf("\nKITTI object: no frames in %s/velodyne (skipped)\n", dir.c_str());
    return;
  }
  if (ascii_half_m > 0.0 && r.frames > 0) printAscii(*r.segmenter_on, ascii_half_m);
  std::printf(
      "\nKITTI object %s, %d frames: object points (in boxes, above the ground band) in "
      "the foreground\n| class | points | fg hough on | fg hough off |\n",
      dir.c_str(), r.frames);
  for (const auto& kv : r.per_class) {
    std::printf("| %-14s | %6ld | %6.4f | %6.4f |\n", kv.first.c_str(), kv.second[0],
                core::segRatio(kv.second[1], kv.second[0]),
                core::segRatio(kv.second[2], kv.second[0]));
  }
}

void usage(const char* argv0, FILE* out) {
  std::fprintf(
      out,
      "usage: %s [DIR] [options]                     SemanticKITTI sequence (velodyne/, labels/)\n"
      "       %s --sim GTFILE --pcap PCAP [options]  simulated drive (urban_detection_simulate)\n"
      "       %s --kitti-object [DIR] [options]      KITTI object frames\n"
      "options:\n"
      "  --config FILE        segmentation.yaml style file (repeatable; in order with --set)\n"
      "  --set name=value     a GridSegmenterParams field (repeatable), e.g. hough.votes=30\n"
      "  --calibration FILE   (--sim) the calibration the drive was simulated with\n"
      "  --max-frames N       (--sim) score the first N revolutions only\n"
      "  --json FILE          write the figures as JSON\n"
      "  -v                   confusion matrices\n"
      "  --dump DIR           per-point x y z group class text files\n"
      "  --ascii HALF_SIDE_M  cell classes of the last frame around the sensor\n",
      argv0, argv0, argv0);
}

}  // namespace

int main(int argc, char** argv) {
  const char* env = std::getenv("UD_SHARED_DATA");
  const std::string shared = env ? env : "../shared/data";
  std::string dir = shared + "/semantic_kitti/sequences/00";
  core::GridSegmenterParams params;
  bool verbose = false;
  std::string kitti_object_dir;  // evaluate KITTI object frames instead of SemanticKITTI
  double ascii_half_m = 0.0;     // print the cell classes of the last scan within this half side
  std::string dump_dir;          // per-point x y z group class text files, for analysis
  std::string sim_gt, sim_pcap, calibration_path, json_path;
  long max_frames = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "error: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--config") {
      const std::string path = value();
      std::string err;
      if (!core::loadPipelineParamsYaml(path, &params, nullptr, nullptr, &err)) {
        std::fprintf(stderr, "error: %s\n", err.c_str());
        return 2;
      }
    } else if (a == "--set") {
      const std::string kv = value();
      if (!setParam(&params, kv)) {
        std::fprintf(stderr, "unknown parameter in --set %s\n", kv.c_str());
        return 2;
      }
    } else if (a == "--dump") {
      dump_dir = value();
    } else if (a == "--ascii") {
      ascii_half_m = std::atof(value().c_str());
    } else if (a == "--sim") {
      sim_gt = value();
    } else if (a == "--pcap") {
      sim_pcap = value();
    } else if (a == "--calibration") {
      calibration_path = value();
    } else if (a == "--json") {
      json_path = value();
    } else if (a == "--max-frames") {
      const std::string v = value();
      char* end = nullptr;
      max_frames = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || max_frames < 1) {
        std::fprintf(stderr, "error: --max-frames needs a positive integer, not '%s'\n", v.c_str());
        return 2;
      }
    } else if (a == "--kitti-object") {
      kitti_object_dir = shared + "/kitti_object";
      if (i + 1 < argc && argv[i + 1][0] != '-') kitti_object_dir = argv[++i];
    } else if (a == "-v") {
      verbose = true;
    } else if (a == "-h" || a == "--help") {
      usage(argv[0], stdout);
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "error: unknown option %s\n", a.c_str());
      usage(argv[0], stderr);
      return 2;
    } else {
      dir = a;
    }
  }
  if (sim_gt.empty() != sim_pcap.empty()) {
    std::fprintf(stderr, "error: --sim GTFILE and --pcap PCAP go together\n");
    return 2;
  }
  if (sim_gt.empty() && (!calibration_path.empty() || max_frames > 0)) {
    std::fprintf(stderr, "error: --calibration and --max-frames apply to --sim only\n");
    return 2;
  }
  if (!kitti_object_dir.empty()) {
    evalKittiObject(kitti_object_dir, params, ascii_half_m);
    return 0;
  }

  core::SegmentationEvaluator ev(params);
  std::string dataset, source;
  if (!sim_gt.empty()) {
    std::string error;
    if (!core::evaluateSimulatedSegmentation(sim_gt, sim_pcap, calibration_path, max_frames,
                                             dump_dir, &ev, &error)) {
      std::fprintf(stderr, "error: %s\n", error.c_str());
      return 1;
    }
    dataset = "sim";
    source = sim_pcap;
    std::printf(
        "Simulated drive %s, %d revolutions, exact per-point classes (walls = facades, "
        "cyclist = rider with bicycle, other vehicle = van)\n",
        sim_pcap.c_str(), ev.on().frames);
  } else {
    if (!core::evaluateSemanticKittiSegmentation(dir, dump_dir, &ev)) {
      std::fprintf(stderr, "no SemanticKITTI scans in %s/velodyne (data absent?)\n", dir.c_str());
      return 1;
    }
    dataset = "semantic_kitti";
    source = dir;
    std::printf("SemanticKITTI %s, %d scans (points with label unlabeled/outlier ignored)\n",
                dir.c_str(), ev.on().frames);
  }
  if (ascii_half_m > 0.0) {
    printAscii(ev.segmenterOn(), ascii_half_m);
    printAscii(ev.segmenterOff(), ascii_half_m);
  }
  printTable(ev.on(), ev.off());
  if (dataset == "sim") {
    std::printf("bins and benches in the foreground: hough on %.4f, off %.4f (%ld points)\n",
                core::foreground(ev.on().of(SegGroup::kStreetObject)),
                core::foreground(ev.off().of(SegGroup::kStreetObject)),
                ev.on().of(SegGroup::kStreetObject).total);
  }
  if (verbose) {
    printConfusion("on", ev.on());
    printConfusion("off", ev.off());
  }
  if (!json_path.empty() &&
      !core::writeSegmentationJson(json_path, dataset, source, ev.on(), ev.off())) {
    std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
    return 1;
  }
  return 0;
}
