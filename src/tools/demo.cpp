// Demo (`scripts/run demo`): the default simulated drive (config/demo_drive.yaml) through every
// pipeline stage: simulation -> packets -> decode -> grid segmentation -> hierarchical-grid and
// kd-tree detection. Prints per-stage time per revolution and, against the simulator's exact
// ground truth, how the segmentation labels each ground-truth class and the detectors' object
// counts and F-rate (paper Sec. 5 scoring via core::DetectionEvaluator; the reference numbers
// come from urban_detection_eval).
//
//   urban_detection_demo [--config FILE] [--revolutions N] [--rpm R] [--calibration FILE]
//                        [--segmentation FILE] [--every K]
#include "urban_detection/core/common/point_types.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <ros/package.h>

#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace uc = urban_detection::core;

namespace {

using Clock = std::chrono::steady_clock;
double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

struct Stage {
  std::string name;
  std::vector<double> ms;
  double median() const { return pct(0.5); }
  double pct(double q) const {
    if (ms.empty()) return 0.0;
    std::vector<double> v = ms;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
  }
};

constexpr std::size_t kMinObjectPoints = 20;  // smaller GT objects are not counted

int usage(const char* argv0) {
  std::fprintf(stderr,
               "usage: %s [--config drive.yaml] [--revolutions N] [--rpm R (300..1200)]\n"
               "          [--calibration FILE] [--segmentation segmentation.yaml] [--every K]\n"
               "          [--kdtree-every K (the slow baseline runs on every K-th revolution)]\n",
               argv0);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string pkg = ros::package::getPath("urban_detection");
  std::string config_path = pkg.empty() ? "" : pkg + "/config/demo_drive.yaml";
  std::string seg_path = pkg.empty() ? "" : pkg + "/config/segmentation.yaml";
  std::string calibration_path;
  long revolutions = 0, every = 25, kd_every = 5;
  double rpm = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) return usage(argv[0]);
    if (a == "--config")
      config_path = argv[++i];
    else if (a == "--segmentation")
      seg_path = argv[++i];
    else if (a == "--calibration")
      calibration_path = argv[++i];
    else if (a == "--revolutions")
      revolutions = std::strtol(argv[++i], nullptr, 10);
    else if (a == "--rpm")
      rpm = std::strtod(argv[++i], nullptr);
    else if (a == "--every")
      every = std::max(1L, std::strtol(argv[++i], nullptr, 10));
    else if (a == "--kdtree-every")
      kd_every = std::max(1L, std::strtol(argv[++i], nullptr, 10));
    else
      return usage(argv[0]);
  }
  if (config_path.empty()) {
    std::fprintf(stderr, "package urban_detection not found; pass --config\n");
    return 2;
  }
  try {
    uc::SimulationConfig c = uc::loadSimulationConfig(config_path);
    if (!calibration_path.empty()) c.calibration_file = calibration_path;
    if (rpm > 0.0) c.sensor.rpm = rpm;
    uc::validate(c.sensor);
    const uc::Calibration cal = uc::loadCalibration(c.calibration_file);
    uc::GridSegmenterParams seg_params;
    std::string error;
    if (!seg_path.empty() && !uc::loadGridSegmenterParamsYaml(seg_path, "", &seg_params, &error)) {
      std::fprintf(stderr, "segmentation parameters: %s\n", error.c_str());
      return 1;
    }
    seg_params.sensor_height_m = c.sensor.height_m;

    const auto g0 = Clock::now();
    uc::LidarSimulator sim(uc::generateScene(c.scene, c.drive), c.scene, c.drive, cal, c.sensor);
    const double gen_ms = ms(g0, Clock::now());
    // Default: the first 100 revolutions (10 s at 600 rpm) keep the demo within a minute.
    const std::size_t n = revolutions > 0 ? static_cast<std::size_t>(revolutions)
                                          : std::min<std::size_t>(100, sim.revolutionsInDrive());
    std::size_t street_objects = 0;
    for (const auto& o : sim.scene().objects) street_objects += uc::isStreetObject(o.object_class);
    std::printf("urban_detection demo: simulated HDL-64E drive\n");
    std::printf("  drive: %s (%.0f m at %.1f m/s, %.0f rpm, sensor %.2f m high)\n",
                config_path.c_str(), c.drive.length(), c.drive.speed_mps, c.sensor.rpm,
                c.sensor.height_m);
    std::printf("  scene: %zu primitives, %zu objects (%zu street objects), generated in %.1f ms\n",
                sim.scene().primitives.size(), sim.scene().objects.size(), street_objects, gen_ms);
    std::printf("  calibration: %s; revolutions: %zu\n\n", cal.source.c_str(), n);

    uc::PacketDecoder decoder(cal, uc::DecoderParams());
    uc::GridSegmenter segmenter(seg_params);
    uc::HierarchicalGridDetector hier;
    uc::KdTreeDetector kdtree;
    uc::DetectionEvaluator eval_hier, eval_kd;
    Stage s_sim{"simulate (ray cast + encode)", {}}, s_dec{"decode", {}},
        s_seg{"segment (grid + Hough)", {}}, s_hier{"detect: hierarchical grid", {}},
        s_kd{"detect: kd-tree baseline", {}};
    urban_detection::LabeledCloud foreground;
    std::vector<uc::DetectedObject> objects_hier, objects_kd;
    uc::EvalFrame gt_frame;
    uc::SimRevolution rev;
    urban_detection::CloudXYZIRT cloud;
    std::vector<uc::SegmentClass> labels;
    std::size_t mismatched = 0, points = 0;
    // confusion[ground-truth class][segment class] over all points
    std::vector<std::vector<std::size_t>> confusion(uc::kNumObjectClasses,
                                                    std::vector<std::size_t>(5, 0));
    std::printf(
        "columns: per-stage ms; gt = ground-truth street objects with >= %zu points, fg = "
        "of them kept as foreground by the segmentation, hier / kd = objects detected\n",
        kMinObjectPoints);
    std::printf("%5s %7s %7s %7s %7s %7s %7s %6s %6s %6s %6s\n", "rev", "points", "sim_ms",
                "dec_ms", "seg_ms", "hier_ms", "kd_ms", "gt", "fg", "hier", "kd");
    for (std::size_t r = 0; r < n; ++r) {
      const auto t0 = Clock::now();
      sim.simulateNext(&rev);
      const auto t1 = Clock::now();
      cloud.clear();
      for (std::size_t i = 0; i < rev.packets.size(); ++i) {
        decoder.decode(rev.packets[i].data(), rev.packets[i].size(),
                       rev.packet_stamps_s[i] - rev.stamp_s, &cloud, nullptr);
      }
      const auto t2 = Clock::now();
      segmenter.segment(cloud, &labels);
      uc::extractForeground(cloud, labels, &foreground);
      const auto t4 = Clock::now();
      hier.detect(foreground, &objects_hier);
      const auto t5 = Clock::now();
      const bool run_kd = r % static_cast<std::size_t>(kd_every) == 0;
      objects_kd.clear();
      if (run_kd) kdtree.detect(foreground, &objects_kd);
      const auto t6 = Clock::now();
      s_sim.ms.push_back(ms(t0, t1));
      s_dec.ms.push_back(ms(t1, t2));
      s_seg.ms.push_back(ms(t2, t4));
      s_hier.ms.push_back(ms(t4, t5));
      if (run_kd) s_kd.ms.push_back(ms(t5, t6));
      points += cloud.size();
      if (cloud.size() != rev.instance_ids.size()) {
        ++mismatched;
        continue;
      }
      // Ground-truth street objects with at least 20 points, and how many of them the
      // segmentation keeps as foreground (a majority of their points labelled short).
      std::map<std::uint32_t, std::pair<std::size_t, std::size_t>> per_obj;  // id -> (pts, short)
      std::size_t short_pts = 0;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto seg = static_cast<std::size_t>(labels[i]);
        ++confusion[rev.classes[i]][std::min<std::size_t>(seg, 4)];
        const bool is_short = labels[i] == uc::SegmentClass::kShort;
        short_pts += is_short;
        const auto cls = static_cast<uc::ObjectClass>(rev.classes[i]);
        if (rev.instance_ids[i] > 0 && uc::isStreetObject(cls)) {
          auto& e = per_obj[rev.instance_ids[i]];
          ++e.first;
          e.second += is_short;
        }
      }
      std::size_t gt_objs = 0, fg_objs = 0;
      for (const auto& kv : per_obj) {
        if (kv.second.first < kMinObjectPoints) continue;
        ++gt_objs;
        fg_objs += 2 * kv.second.second > kv.second.first;
      }
      (void)short_pts;
      // Exact ground truth for the scoring: street objects are the GT objects; tall objects
      // (trees, poles, signs) are real but not targets (don't care); ground and walls count.
      gt_frame.objects.clear();
      gt_frame.reset(cloud.size());
      std::map<std::uint32_t, std::int32_t> slot;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto cls = static_cast<uc::ObjectClass>(rev.classes[i]);
        if (rev.instance_ids[i] > 0 && uc::isStreetObject(cls)) {
          auto it = slot.find(rev.instance_ids[i]);
          if (it == slot.end()) {
            it = slot.emplace(rev.instance_ids[i],
                              static_cast<std::int32_t>(gt_frame.objects.size()))
                     .first;
            uc::EvalObject o;
            o.label = uc::toString(cls);
            o.id = rev.instance_ids[i];
            gt_frame.objects.push_back(o);
          }
          gt_frame.object_of_point[i] = it->second;
        } else if (rev.instance_ids[i] > 0) {
          gt_frame.role[i] = uc::PointRole::kDontCare;
        }
      }
      gt_frame.finalize(kMinObjectPoints);
      uc::FrameMatch m_hier, m_kd;
      eval_hier.evaluate(gt_frame, objects_hier, &m_hier);
      if (run_kd) eval_kd.evaluate(gt_frame, objects_kd, &m_kd);
      if (r % static_cast<std::size_t>(every) == 0 || r + 1 == n) {
        std::printf("%5zu %7zu %7.2f %7.3f %7.2f %7.2f %7.2f %6zu %6zu %6zu %6zu\n", r,
                    cloud.size(), s_sim.ms.back(), s_dec.ms.back(), s_seg.ms.back(),
                    s_hier.ms.back(), s_kd.ms.back(), gt_objs, fg_objs, objects_hier.size(),
                    objects_kd.size());
      }
    }
    std::printf("\nper-stage time per revolution (this machine, %zu revolutions):\n", n);
    for (const Stage* s : {&s_sim, &s_dec, &s_seg, &s_hier, &s_kd}) {
      std::printf("  %-30s median %7.2f ms   p95 %7.2f ms\n", s->name.c_str(), s->median(),
                  s->pct(0.95));
    }
    std::printf("\ndetection vs ground truth (street objects with >= %zu points; IoU >= 0.5):\n",
                kMinObjectPoints);
    for (const auto& e : {std::make_pair("hierarchical grid", &eval_hier),
                          std::make_pair("kd-tree (every K)", &eval_kd)}) {
      const uc::DetectionScore& t = e.second->total();
      std::printf("  %-18s NO %6zu  MO %6zu  FO %6zu  precision %.3f  recall %.3f  F-rate %.3f\n",
                  e.first, t.no, t.mo, t.fo, t.precision(), t.recall(), t.fRate());
    }
    std::printf("\nsegmentation vs ground truth (share of each class's points):\n");
    std::printf("  %-11s %9s %8s %8s %8s %8s\n", "gt class", "points", "ground", "tall", "short",
                "other");
    for (int k = 1; k < uc::kNumObjectClasses; ++k) {
      const auto& row = confusion[k];
      std::size_t tot = 0;
      for (auto v : row) tot += v;
      if (tot == 0) continue;
      const auto pct = [&](std::size_t v) { return 100.0 * v / tot; };
      const std::size_t other = row[0] + row[1];
      std::printf("  %-11s %9zu %7.1f%% %7.1f%% %7.1f%% %7.1f%%\n",
                  uc::toString(static_cast<uc::ObjectClass>(k)), tot, pct(row[2]), pct(row[3]),
                  pct(row[4]), pct(other));
    }
    std::printf(
        "\n%zu points in %zu revolutions; decoded cloud and ground truth %s\n", points, n,
        mismatched == 0 ? "aligned in every revolution" : "DIFFER in some revolutions (see above)");
    return mismatched == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "urban_detection_demo: %s\n", e.what());
    return 1;
  }
}
