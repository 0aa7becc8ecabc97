// urban_detection_bench: per-stage timing of the core pipeline on recorded data, one process,
// one thread (run it pinned to one core: taskset -c 0). Reports median and p95 ms per
// revolution of each stage, the pipeline rate and the peak resident memory, and times the
// hierarchical grid and the kd-tree detector on the same foregrounds in the same run.
//
//   urban_detection_bench [--pcd-dir DIR]... [--bin-dir DIR]... [--pcap FILE
//                         [--calibration FILE]] [--config FILE]... [--repeat N]
//                         [--max-frames N] [--label NAME] [--json FILE] [--no-kdtree]
//                         [--early SECTORS]
//
// Inputs are streamed from disk (file reading is not timed); packets are decoded as they
// come, cut into revolutions as the driver does, and the decode time of a revolution's
// packets is its "packet_decode" stage.
//
// "pipeline" = packet_decode (pcap input only) + segmentation (Hough refinement included) +
// foreground_extraction + hierarchical_detection + classification (features and forest, when
// the config's classifier section enables it, as config/classification.yaml does) + box_fitting
// (core::Pipeline::process(), stage by stage), i.e. packets -> objects on a
// pcap (the simulated drive of scripts/run bench) and cloud -> objects on PCD / .bin sweeps (KITTI
// raw comes as motion-compensated clouds, not packets); the JSON says which
// (pipeline_includes_packet_decode). The pipeline's stages run back to back per revolution
// (markers after them, timed but not in the pipeline figure); kdtree_detection and the
// standalone hough_refinement are timed in a second pass over the same revolutions, so they do
// not evict the pipeline's buffers from the caches between its revolutions. When the config's
// kd-tree uses the unsorted neighbour search (kdtree/sorted_search: false, the default), the
// baseline is also timed with PCL's default sorted search (kdtree_detection_pcl_default: the
// same clusters), so both speed-ups come from one run. --no-kdtree skips the baseline (on the
// simulated drive's dense near-range blobs it takes seconds per revolution); the speed-ups are
// then not measured (null in the JSON). --early SECTORS also runs the early-objects chain
// beside it (core::Pipeline::addSector over SECTORS equal parts of each revolution in sweep
// order, then finishRevolution): "early_sectors" is the time of all its sectors of one
// revolution, "early_seam" that of the seam, and it prints how many objects were given before
// the seam. A Debug build (no NDEBUG) refuses to run.
#include <sched.h>
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/evaluation/bench_sources.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/tracker_bench.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/segmentation/hough_wall_refiner.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/ros/object_conversions.h"
#include "urban_detection/ros/object_markers.h"

#include "tool_common.h"

namespace core = urban_detection::core;
using urban_detection::CloudXYZIRT;
using Clock = std::chrono::steady_clock;

using urban_detection::core::msSince;
using urban_detection::core::StageTimer;
using urban_detection::core::threadCpuMs;
using urban_detection::tools::jsonEscape;
using urban_detection::tools::jsonNumber;
using urban_detection::tools::median;
using urban_detection::tools::percentile;

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: urban_detection_bench [--pcd-dir DIR]... [--bin-dir DIR]...\n"
               "         [--pcap FILE [--calibration FILE]] [--config FILE]... [--repeat N]\n"
               "         [--max-frames N] [--label NAME] [--json FILE] [--no-kdtree]\n"
               "         [--early SECTORS]\n"
               "Run it pinned to one core (taskset -c 0) from a Release build.\n");
}

}  // namespace

int main(int argc, char** argv) {
#ifndef NDEBUG
  std::fprintf(stderr,
               "error: urban_detection_bench was built without NDEBUG (a Debug build); its "
               "timings would be meaningless. Rebuild with -DCMAKE_BUILD_TYPE=Release.\n");
  (void)argc;
  (void)argv;
  return 3;
#else
  std::vector<std::string> pcd_dirs, bin_dirs, configs;
  std::string pcap, calib_path, label = "bench", json_path;
  long repeat = 3, max_frames = -1;
  bool run_kdtree = true;
  long early_sectors = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const urban_detection::tools::OptionArgs arg{argc, argv, &i};
    if (a == "--pcd-dir")
      pcd_dirs.push_back(arg.value("--pcd-dir"));
    else if (a == "--bin-dir")
      bin_dirs.push_back(arg.value("--bin-dir"));
    else if (a == "--pcap")
      pcap = arg.value("--pcap");
    else if (a == "--calibration")
      calib_path = arg.value("--calibration");
    else if (a == "--config")
      configs.push_back(arg.value("--config"));
    else if (a == "--repeat")
      repeat = std::max(1L, arg.count("--repeat"));
    else if (a == "--max-frames")
      max_frames = arg.count("--max-frames");
    else if (a == "--label")
      label = arg.value("--label");
    else if (a == "--json")
      json_path = arg.value("--json");
    else if (a == "--no-kdtree")
      run_kdtree = false;
    else if (a == "--early")
      early_sectors = std::max(1L, arg.count("--early"));
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "error: unknown argument '%s'\n", a.c_str());
      usage();
      return 2;
    }
  }

  core::PipelineParams params;
  if (!urban_detection::tools::loadConfigs(configs, &params)) return 2;

  std::vector<std::unique_ptr<core::RevolutionSource> > sources;
  try {
    sources = core::openRevolutionSources(pcd_dirs, bin_dirs, pcap, calib_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (sources.empty()) {
    std::fprintf(stderr, "error: no input\n");
    usage();
    return 2;
  }

  // The pipeline (hierarchical grid), and beside it: the baseline's chain after the
  // segmentation, PCL's default search, the segmenter without Hough.
  std::unique_ptr<core::Pipeline> pipe, kd_pipe, early_pipe;
  std::unique_ptr<core::GridSegmenter> segmenter_no_hough, segmenter_streamed;
  std::unique_ptr<core::KdTreeDetector> kdtree_pcl_default;
  try {
    params.detector = "hierarchical_grid";
    pipe.reset(new core::Pipeline(params));
    if (early_sectors > 0) early_pipe.reset(new core::Pipeline(params));
    params.detector = "kdtree";
    kd_pipe.reset(new core::Pipeline(params));
    segmenter_streamed.reset(new core::GridSegmenter(params.segmentation));
    core::GridSegmenterParams no_hough = params.segmentation;
    no_hough.hough.enabled = false;
    segmenter_no_hough.reset(new core::GridSegmenter(no_hough));
    if (!params.kdtree.sorted_search) {
      core::KdTreeDetectorParams sorted = params.kdtree;
      sorted.sorted_search = true;
      kdtree_pcl_default.reset(new core::KdTreeDetector(sorted));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: invalid parameters: %s\n", e.what());
    return 2;
  }
  const bool classifier = params.classifier.enabled;
  core::HoughWallRefiner hough(params.segmentation.hough);

  std::map<std::string, std::vector<double> > stage, cpu_stage;  // wall and thread-CPU ms
  std::vector<double> pipeline, pipeline_cpu;
  double points_sum = 0, fg_sum = 0, hier_obj_sum = 0, kd_obj_sum = 0, rejected_sum = 0;
  CloudXYZIRT cloud;
  std::vector<core::SegmentClass> labels_no_hough, labels_streamed;
  std::uint32_t streamed_seq = 0;
  std::vector<core::DetectedObject> pcl_default_objects;
  std::vector<core::SegmentClass> cells;
  urban_detection::DetectedObjectArray object_msg;
  visualization_msgs::MarkerArray markers;
  const urban_detection::ros_conv::ObjectMarkerParams marker_params;
  bool any_packets = false;
  std::size_t frames = 0;
  std::size_t early_given = 0, early_total = 0, early_mismatches = 0;
  std::uint32_t early_seq = 0;
  CloudXYZIRT swept;
  // Every revolution of every source, as the sources give them (decoded from packets or read
  // from disk, not timed here).
  auto forEachFrame = [&](const std::function<void(double, double)>& run) {
    for (auto& src : sources) {
      src->rewind();
      long taken = 0;
      double decode_ms, decode_cpu_ms;
      while ((max_frames < 0 || taken < max_frames) &&
             src->next(&cloud, &decode_ms, &decode_cpu_ms)) {
        ++taken;
        run(decode_ms, decode_cpu_ms);
      }
    }
  };
  for (long r = 0; r < repeat; ++r) {
    // The pipeline's stages back to back per revolution, as the nodelets run them in one
    // manager, and nothing else in between (the measurements beside it run in their own pass
    // below: run between the stages, the kd-tree's ~30 ms of other memory evicted the
    // pipeline's buffers from the caches and slowed every stage of the next revolution).
    forEachFrame([&](double decode_ms, double decode_cpu_ms) {
      double total = 0.0, total_cpu = 0.0;
      if (decode_ms >= 0.0) {
        any_packets = true;
        stage["packet_decode"].push_back(decode_ms);
        cpu_stage["packet_decode"].push_back(decode_cpu_ms);
        total += decode_ms;
        total_cpu += decode_cpu_ms;
      }
      const core::PipelineResult& r = pipe->process(cloud);
      for (const core::StageTiming& t : r.timings) {
        const std::string name =
            std::string(t.name) == "detection" ? "hierarchical_detection" : t.name;
        stage[name].push_back(t.wall_ms);
        cpu_stage[name].push_back(t.cpu_ms);
      }
      total += r.totalWallMs();
      total_cpu += r.totalCpuMs();
      rejected_sum += r.classification.rejected;
      const std::vector<core::DetectedObject>& objects = r.objects;
      hier_obj_sum += objects.size();
      pipeline.push_back(total);
      pipeline_cpu.push_back(total_cpu);

      // Not part of the pipeline (rviz output, built only while someone subscribes): the
      // object message and its markers.
      StageTimer marker_t;
      std_msgs::Header header;
      header.frame_id = "velodyne";
      urban_detection::ros_conv::toMsg(objects, "hierarchical_grid", header, &object_msg);
      urban_detection::ros_conv::buildObjectMarkers(object_msg, marker_params, &markers);
      marker_t.stop("markers", &stage, &cpu_stage);

      points_sum += cloud.size();
      fg_sum += r.foreground.size();
      ++frames;
    });
    // Beside the pipeline, on the same revolutions: the baseline on the same foregrounds
    // (segmented again, not timed), and the Hough refinement alone (it runs inside segment();
    // timed here on the frame's cell classes before refinement and wall evidence, as segment()
    // passes them).
    forEachFrame([&](double decode_ms, double) {
      if (run_kdtree) {
        const urban_detection::LabeledCloud& foreground = pipe->process(cloud).foreground;
        const core::PipelineResult& kd = kd_pipe->detect(foreground);  // as the kd-tree nodelet
        for (const core::StageTiming& t : kd.timings) {
          if (std::string(t.name) != "detection") continue;
          stage["kdtree_detection"].push_back(t.wall_ms);
          cpu_stage["kdtree_detection"].push_back(t.cpu_ms);
        }
        kd_obj_sum += kd.objects.size();
        if (kdtree_pcl_default) {
          StageTimer kd_default_t;
          kdtree_pcl_default->detect(foreground, &pcl_default_objects);
          kd_default_t.stop("kdtree_detection_pcl_default", &stage, &cpu_stage);
        }
      }
      // Live, PacketSource's sectors are binned while the revolution arrives
      // (GridSegmenter::addPoints): the binning of all but the last 1/16 of the points, and
      // the segmentation left at the cut (same labels).
      {
        const std::size_t swept = cloud.size() - cloud.size() / 16;
        StageTimer bin_t;
        segmenter_streamed->addPoints(++streamed_seq, cloud.points.data(), swept);
        bin_t.stop("sweep_binning", &stage, &cpu_stage);
        cloud.header.seq = streamed_seq;
        StageTimer cut_t;
        segmenter_streamed->segment(cloud, &labels_streamed);
        cut_t.stop("segmentation_at_cut", &stage, &cpu_stage);
      }
      if (early_pipe) {
        // Decoded packets come in time order; clouds read from disk are put in sweep order
        // (counter-clockwise from behind the sensor, where KITTI's revolutions start).
        swept = cloud;
        swept.header.seq = ++early_seq;
        if (decode_ms < 0.0) {
          std::vector<std::pair<double, std::size_t> > order(cloud.size());
          for (std::size_t i = 0; i < cloud.size(); ++i) {
            double a = std::atan2(cloud[i].y, cloud[i].x) - M_PI;
            a = std::fmod(a, 2.0 * M_PI);
            if (!(a >= 0.0)) a = std::isfinite(a) ? a + 2.0 * M_PI : 0.0;
            order[i] = {a, i};
          }
          std::stable_sort(order.begin(), order.end());
          for (std::size_t i = 0; i < cloud.size(); ++i) {
            swept.points[i] = cloud[order[i].second];
            swept.points[i].time = static_cast<float>(0.1 * order[i].first / (2.0 * M_PI));
          }
        }
        double wall = 0.0, cpu = 0.0;
        const std::size_t n = swept.size();
        for (long s = 0; s < early_sectors; ++s) {
          const std::size_t a = n * s / early_sectors, b = n * (s + 1) / early_sectors;
          const core::EarlySectorResult& e =
              early_pipe->addSector(early_seq, swept.points.data() + a, b - a);
          for (const core::StageTiming& t : e.timings) wall += t.wall_ms, cpu += t.cpu_ms;
        }
        stage["early_sectors"].push_back(wall);
        cpu_stage["early_sectors"].push_back(cpu);
        const core::PipelineResult& f = early_pipe->finishRevolution(swept);
        stage["early_seam"].push_back(f.totalWallMs());
        cpu_stage["early_seam"].push_back(f.totalCpuMs());
        for (const std::uint8_t g : f.given_early) early_given += g;
        early_total += f.objects.size();
        early_mismatches += f.early_mismatches;
      }
      segmenter_no_hough->segment(cloud, &labels_no_hough);
      cells = segmenter_no_hough->cellClasses();
      const auto& g = segmenter_no_hough->grid();
      StageTimer hough_t;
      hough.refine(g.rows(), g.cols(), params.segmentation.cell_size_m, &cells,
                   &segmenter_no_hough->wallSupport());
      hough_t.stop("hough_refinement", &stage, &cpu_stage);
    });
  }
  if (frames == 0) {
    std::fprintf(stderr, "error: no frame could be read\n");
    return 1;
  }
  // Box fitting and the tracker on a synthetic street of 100 objects
  // (core/evaluation/tracker_bench.h).
  core::benchTracker(100, 300, [&](const char* name, const std::function<void()>& call) {
    StageTimer t;
    call();
    t.stop(name, &stage, &cpu_stage);
  });

  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  const double peak_mb = ru.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
  cpu_set_t set;
  CPU_ZERO(&set);
  const int cpus = sched_getaffinity(0, sizeof(set), &set) == 0 ? CPU_COUNT(&set) : -1;
  double pipeline_sum = 0;
  for (double v : pipeline) pipeline_sum += v;
  const double pipeline_median = median(pipeline);
  const double pipeline_fps = 1000.0 * static_cast<double>(pipeline.size()) / pipeline_sum;
  double pipeline_cpu_sum = 0;
  for (double v : pipeline_cpu) pipeline_cpu_sum += v;
  const double pipeline_cpu_fps =
      1000.0 * static_cast<double>(pipeline_cpu.size()) / pipeline_cpu_sum;
  const double speedup =
      run_kdtree ? median(stage["kdtree_detection"]) / median(stage["hierarchical_detection"])
                 : std::nan("");
  const double speedup_pcl_default =
      stage.count("kdtree_detection_pcl_default")
          ? median(stage["kdtree_detection_pcl_default"]) / median(stage["hierarchical_detection"])
          : std::nan("");

  const char* order[] = {"packet_decode",
                         "segmentation",
                         "sweep_binning",
                         "segmentation_at_cut",
                         "hough_refinement",
                         "foreground_extraction",
                         "hierarchical_detection",
                         "classification",
                         "box_fitting",
                         "markers",
                         "box_fitting_100_objects",
                         "tracker_100_objects",
                         "kdtree_detection",
                         "kdtree_detection_pcl_default",
                         "early_sectors",
                         "early_seam"};
  std::printf("%s: %zu revolutions (%ld pass%s over", label.c_str(), frames, repeat,
              repeat > 1 ? "es" : "");
  for (const auto& s : sources) std::printf(" [%s]", s->describe().c_str());
  std::printf("), %.0f points, %.0f foreground points, %.1f hierarchical objects",
              points_sum / frames, fg_sum / frames, hier_obj_sum / frames);
  if (run_kdtree) std::printf(" / %.1f kd-tree objects", kd_obj_sum / frames);
  std::printf(" per revolution; %d CPU(s) allowed\n", cpus);
  std::printf("  %-28s %10s %10s %14s\n", "stage", "median_ms", "p95_ms", "cpu_median_ms");
  for (const char* name : order) {
    auto it = stage.find(name);
    if (it == stage.end()) continue;
    std::printf("  %-28s %10.3f %10.3f %14.3f%s\n", name, median(it->second),
                percentile(it->second, 0.95), median(cpu_stage[name]),
                std::string(name) == "hough_refinement" ? "  (inside segmentation)"
                : std::string(name) == "sweep_binning"
                    ? "  (live: 15/16 of the points binned while the revolution arrives)"
                : std::string(name) == "segmentation_at_cut"
                    ? "  (live: segmentation left at the revolution's end)"
                : std::string(name) == "markers" ? "  (rviz output, lazy, not in pipeline)"
                : std::string(name) == "tracker_100_objects" ||
                        std::string(name) == "box_fitting_100_objects"
                    ? "  (synthetic street, 100 objects, not in pipeline)"
                : std::string(name) == "kdtree_detection" ? "  (baseline, not in pipeline)"
                : std::string(name) == "kdtree_detection_pcl_default"
                    ? "  (baseline with PCL's default sorted search)"
                : std::string(name) == "early_sectors"
                    ? "  (early objects: all sectors of a revolution)"
                : std::string(name) == "early_seam" ? "  (early objects: the seam)"
                                                    : "");
  }
  std::printf("  %-28s %10.3f %10.3f %14.3f  (%s-> hierarchical objects)\n", "pipeline",
              pipeline_median, percentile(pipeline, 0.95), median(pipeline_cpu),
              any_packets ? "packets " : "cloud ");
  std::printf("  classifier %s: %.1f hierarchical objects rejected per revolution\n",
              classifier ? "on" : "off", rejected_sum / frames);
  if (early_pipe) {
    std::printf(
        "  early objects (%ld sectors): %zu of %zu objects given before the seam (%.1f %%), "
        "%zu mismatches\n",
        early_sectors, early_given, early_total,
        early_total ? 100.0 * early_given / early_total : 0.0, early_mismatches);
  }
  char speedup_text[64] = "not measured (--no-kdtree)";
  if (run_kdtree) std::snprintf(speedup_text, sizeof(speedup_text), "%.1fx", speedup);
  if (std::isfinite(speedup_pcl_default)) {
    const std::size_t used = std::strlen(speedup_text);
    std::snprintf(speedup_text + used, sizeof(speedup_text) - used, " (PCL default: %.1fx)",
                  speedup_pcl_default);
  }
  std::printf(
      "  pipeline_fps %.1f (cpu-time fps %.1f)   hier_vs_kdtree_speedup %s   "
      "peak_rss %.1f MB\n",
      pipeline_fps, pipeline_cpu_fps, speedup_text, peak_mb);

  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << "{\n  \"label\": \"" << jsonEscape(label) << "\",\n  \"inputs\": [";
    for (std::size_t i = 0; i < sources.size(); ++i) {
      out << (i ? ", " : "") << "\"" << jsonEscape(sources[i]->describe()) << "\"";
    }
    out << "],\n  \"revolutions\": " << frames << ",\n  \"repeat\": " << repeat
        << ",\n  \"cpus_allowed\": " << cpus
        << ",\n  \"mean_points\": " << jsonNumber(points_sum / frames)
        << ",\n  \"mean_foreground_points\": " << jsonNumber(fg_sum / frames)
        << ",\n  \"mean_objects_hierarchical\": " << jsonNumber(hier_obj_sum / frames)
        << ",\n  \"mean_objects_kdtree\": "
        << jsonNumber(run_kdtree ? kd_obj_sum / frames : std::nan(""))
        << ",\n  \"mean_rejected_objects_hierarchical\": " << jsonNumber(rejected_sum / frames)
        << ",\n  \"pipeline_includes_packet_decode\": " << (any_packets ? "true" : "false")
        << ",\n  \"stages\": {";
    bool first = true;
    for (const char* name : order) {
      auto it = stage.find(name);
      if (it == stage.end()) continue;
      out << (first ? "\n" : ",\n") << "    \"" << name
          << "\": {\"median_ms\": " << jsonNumber(median(it->second))
          << ", \"p95_ms\": " << jsonNumber(percentile(it->second, 0.95))
          << ", \"cpu_median_ms\": " << jsonNumber(median(cpu_stage[name]))
          << ", \"cpu_p95_ms\": " << jsonNumber(percentile(cpu_stage[name], 0.95)) << "}";
      first = false;
    }
    out << "\n  },\n  \"pipeline_median_ms\": " << jsonNumber(pipeline_median)
        << ",\n  \"pipeline_p95_ms\": " << jsonNumber(percentile(pipeline, 0.95))
        << ",\n  \"pipeline_cpu_median_ms\": " << jsonNumber(median(pipeline_cpu))
        << ",\n  \"pipeline_fps\": " << jsonNumber(pipeline_fps)
        << ",\n  \"pipeline_cpu_fps\": " << jsonNumber(pipeline_cpu_fps)
        << ",\n  \"hier_vs_kdtree_speedup\": " << jsonNumber(speedup)
        << ",\n  \"hier_vs_kdtree_pcl_default_speedup\": " << jsonNumber(speedup_pcl_default)
        << ",\n  \"peak_rss_mb\": " << jsonNumber(peak_mb) << "\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
#endif
}
