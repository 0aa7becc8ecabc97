// urban_detection_seg_eval: accuracy of the grid segmentation (paper Sec. 3.1) on SemanticKITTI
// scans, with and without the Hough wall refinement.
//
//   urban_detection_seg_eval [DIR] [--set name=value ...]
//   DIR defaults to $UD_SHARED_DATA/semantic_kitti/sequences/00 (or ../shared/data/...); it holds
//   velodyne/*.bin and labels/*.label. Points labelled unlabeled (0) or outlier (1) are ignored.
#include "urban_detection/core/point_types.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "urban_detection/core/eval_datasets.h"
#include "urban_detection/core/grid_segmenter.h"
#include "urban_detection/core/kitti_io.h"

namespace fs = std::filesystem;
namespace core = urban_detection::core;
namespace sk = urban_detection::core::semantic_kitti;
using core::SegmentClass;

namespace {

struct Counts {
  long ground_tp = 0, ground_fp = 0, ground_fn = 0;
  long wall_total = 0, wall_not_fg = 0;  // building + fence
  long car_total = 0, car_fg = 0;
  long person_total = 0, person_fg = 0;
  long cyclist_total = 0, cyclist_fg = 0;  // bicyclist + motorcyclist
  long vehicle_total = 0, vehicle_fg = 0;  // truck, other-vehicle, bicycle, motorcycle
  long veg_total = 0, veg_fg = 0;          // vegetation, trunk, pole, sign (for information)
  long confusion[5][5] = {};  // [ground, wall, car, person+cyclist, other][SegmentClass]
  double ms_total = 0.0;
  int frames = 0;
};

double ratio(long a, long b) { return b > 0 ? static_cast<double>(a) / static_cast<double>(b) : 0.0; }

void accumulate(const std::vector<std::uint32_t>& gt, const std::vector<SegmentClass>& pred,
                Counts* c) {
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const std::uint16_t cls = core::semanticKittiStaticClass(gt[i]);
    if (cls == sk::kUnlabeled || cls == sk::kOutlier) continue;
    const bool is_ground = core::isSemanticKittiGround(cls);
    const bool pred_ground = pred[i] == SegmentClass::kGround;
    const bool fg = pred[i] == SegmentClass::kShort;
    if (is_ground && pred_ground) ++c->ground_tp;
    if (!is_ground && pred_ground) ++c->ground_fp;
    if (is_ground && !pred_ground) ++c->ground_fn;
    const int group = is_ground ? 0
                      : (cls == sk::kBuilding || cls == sk::kFence) ? 1
                      : cls == sk::kCar ? 2
                      : (cls == sk::kPerson || cls == sk::kBicyclist || cls == sk::kMotorcyclist)
                          ? 3 : 4;
    ++c->confusion[group][static_cast<int>(pred[i]) % 5];
    switch (cls) {
      case sk::kBuilding: case sk::kFence: ++c->wall_total; c->wall_not_fg += !fg; break;
      case sk::kCar: ++c->car_total; c->car_fg += fg; break;
      case sk::kPerson: ++c->person_total; c->person_fg += fg; break;
      case sk::kBicyclist: case sk::kMotorcyclist: ++c->cyclist_total; c->cyclist_fg += fg; break;
      case sk::kTruck: case sk::kOtherVehicle: case sk::kBicycle: case sk::kMotorcycle:
        ++c->vehicle_total; c->vehicle_fg += fg; break;
      case sk::kVegetation: case sk::kTrunk: case sk::kPole: case sk::kTrafficSign:
        ++c->veg_total; c->veg_fg += fg; break;
      default: break;
    }
  }
}

void print(const char* name, const Counts& c) {
  const double p = ratio(c.ground_tp, c.ground_tp + c.ground_fp);
  const double r = ratio(c.ground_tp, c.ground_tp + c.ground_fn);
  const double f1 = p + r > 0 ? 2 * p * r / (p + r) : 0.0;
  std::printf("| %-9s | %6.4f | %6.4f | %6.4f | %6.4f (%ld) | %6.4f (%ld) | %6.4f (%ld) | %6.4f (%ld) "
              "| %6.4f (%ld) | %6.4f | %6.2f |\n",
              name, p, r, f1, ratio(c.wall_not_fg, c.wall_total), c.wall_total,
              ratio(c.car_fg, c.car_total), c.car_total, ratio(c.person_fg, c.person_total),
              c.person_total, ratio(c.cyclist_fg, c.cyclist_total), c.cyclist_total,
              ratio(c.vehicle_fg, c.vehicle_total), c.vehicle_total, ratio(c.veg_fg, c.veg_total),
              c.frames > 0 ? c.ms_total / c.frames : 0.0);
}

void printConfusion(const char* name, const Counts& c) {
  static const char* groups[5] = {"ground", "building+fence", "car", "person+cyclist", "other"};
  std::printf("confusion (hough %s): rows = SemanticKITTI group, columns = predicted share\n", name);
  std::printf("  %-15s %8s %8s %8s %8s %8s\n", "", "unknown", "clutter", "ground", "tall", "short");
  for (int g = 0; g < 5; ++g) {
    long n = 0;
    for (int k = 0; k < 5; ++k) n += c.confusion[g][k];
    std::printf("  %-15s", groups[g]);
    for (int k = 0; k < 5; ++k) std::printf(" %8.4f", ratio(c.confusion[g][k], n));
    std::printf("  (%ld)\n", n);
  }
}

// Cell classes around the sensor: '.' ground, 'T' tall, 's' short, ',' clutter, 'S' sensor.
void printAscii(const core::GridSegmenter& seg, double half_m) {
  const core::SimpleGrid& g = seg.grid();
  const int half = static_cast<int>(half_m / g.params().cell_size_m);
  const int r0 = g.rows() / 2, c0 = g.cols() / 2;
  std::printf("cells of the last scan, +x right, +y up, hough %s\n",
              seg.params().hough.enabled ? "on" : "off");
  for (int r = r0 + half; r >= r0 - half; --r) {
    for (int c = c0 - half; c <= c0 + half; ++c) {
      char ch = ' ';
      if (r == r0 && c == c0) {
        ch = 'S';
      } else if (r >= 0 && r < g.rows() && c >= 0 && c < g.cols()) {
        switch (seg.cellClasses()[static_cast<std::size_t>(r) * g.cols() + c]) {
          case SegmentClass::kGround: ch = '.'; break;
          case SegmentClass::kTall: ch = 'T'; break;
          case SegmentClass::kShort: ch = 's'; break;
          case SegmentClass::kClutter: ch = ','; break;
          default: break;
        }
      }
      std::putchar(ch);
    }
    std::putchar('\n');
  }
}

bool setParam(core::GridSegmenterParams* p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) return false;
  const std::string k = kv.substr(0, eq);
  const double v = std::atof(kv.c_str() + eq + 1);
  std::map<std::string, double*> d = {
      {"sensor_height_m", &p->sensor_height_m}, {"cell_size_m", &p->cell_size_m},
      {"max_range_m", &p->max_range_m}, {"ground_max_range_m", &p->ground_max_range_m},
      {"ground_tolerance_m", &p->ground_tolerance_m}, {"ground_max_step_m", &p->ground_max_step_m},
      {"seed_radius_m", &p->seed_radius_m}, {"ground_max_gap_m", &p->ground_max_gap_m},
      {"seed_max_abs_height_m", &p->seed_max_abs_height_m},
      {"terrain_max_offset_m", &p->terrain_max_offset_m},
      {"fov_top_elevation_deg", &p->fov_top_elevation_deg},
      {"tall_min_height_m", &p->tall_min_height_m}, {"tall_min_range_m", &p->tall_min_range_m},
      {"hough.max_range_m", &p->hough.max_range_m},
      {"hough.min_line_length_m", &p->hough.min_line_length_m},
      {"hough.max_line_gap_m", &p->hough.max_line_gap_m},
      {"hough.theta_resolution_deg", &p->hough.theta_resolution_deg},
      {"hough.min_tall_fraction", &p->hough.min_tall_fraction}};
  std::map<std::string, int*> di = {{"min_points_per_cell", &p->min_points_per_cell},
                                    {"terrain_fill_iterations", &p->terrain_fill_iterations},
                                    {"hough.votes", &p->hough.votes},
                                    {"hough.line_half_width_cells", &p->hough.line_half_width_cells}};
  if (k == "hough.extend_lines") { p->hough.extend_lines = v != 0.0; return true; }
  if (k == "ground_in_sparse_cells") { p->ground_in_sparse_cells = v != 0.0; return true; }
  if (d.count(k)) { *d[k] = v; return true; }
  if (di.count(k)) { *di[k] = static_cast<int>(v); return true; }
  return false;
}

// KITTI object frames: share of the points of labelled objects (inside their 3-D boxes, above
// the ground band, rules of eval_datasets.h) that end up in the foreground, per class.
void evalKittiObject(const std::string& dir, const core::GridSegmenterParams& params) {
  const std::vector<std::string> bins = core::listFiles(dir + "/velodyne", ".bin");
  if (bins.empty()) {
    std::printf("\nKITTI object: no frames in %s/velodyne (skipped)\n", dir.c_str());
    return;
  }
  std::map<std::string, std::array<long, 3>> per_class;  // points, fg with Hough, fg without
  core::GridSegmenterParams p_on = params, p_off = params;
  p_on.hough.enabled = true;
  p_off.hough.enabled = false;
  core::GridSegmenter seg_on(p_on), seg_off(p_off);
  int frames = 0;
  for (const std::string& bin : bins) {
    const std::string stem = fs::path(bin).stem().string();
    urban_detection::CloudXYZIRT cloud;
    std::vector<core::KittiLabel> labels;
    core::KittiCalibration calib;
    std::string err;
    if (!core::readKittiBin(bin, &cloud, &err) ||
        !core::readKittiLabels(dir + "/label_2/" + stem + ".txt", &labels, &err) ||
        !core::readKittiCalibration(dir + "/calib/" + stem + ".txt", &calib, &err)) {
      std::fprintf(stderr, "skipping KITTI object %s: %s\n", stem.c_str(), err.c_str());
      continue;
    }
    core::KittiGroundTruthParams gp;
    int w = gp.image_width_px, h = gp.image_height_px;
    core::readPngSize(dir + "/image_2/" + stem + ".png", &w, &h);
    core::EvalFrame gt;
    core::buildKittiGroundTruth(cloud, labels, calib, gp, w, h, &gt);
    std::vector<SegmentClass> on, off;
    seg_on.segment(cloud, &on);
    seg_off.segment(cloud, &off);
    ++frames;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const std::int32_t o = gt.object_of_point[i];
      if (o < 0 || gt.objects[o].ignored) continue;
      if (!gt.role.empty() && gt.role[i] != core::PointRole::kScored) continue;
      auto& c = per_class[gt.objects[o].label];
      ++c[0];
      c[1] += on[i] == SegmentClass::kShort;
      c[2] += off[i] == SegmentClass::kShort;
    }
  }
  std::printf("\nKITTI object %s, %d frames: object points (in boxes, above the ground band) in "
              "the foreground\n| class | points | fg hough on | fg hough off |\n", dir.c_str(),
              frames);
  for (const auto& kv : per_class) {
    std::printf("| %-14s | %6ld | %6.4f | %6.4f |\n", kv.first.c_str(), kv.second[0],
                ratio(kv.second[1], kv.second[0]), ratio(kv.second[2], kv.second[0]));
  }
}

}  // namespace

int main(int argc, char** argv) {
  const char* env = std::getenv("UD_SHARED_DATA");
  std::string dir = std::string(env ? env : "../shared/data") + "/semantic_kitti/sequences/00";
  core::GridSegmenterParams params;
  bool verbose = false;
  std::string kitti_object_dir;  // evaluate KITTI object frames instead of SemanticKITTI
  double ascii_half_m = 0.0;  // print the cell classes of the last scan within this half side
  std::string dump_dir;  // per-point x y z class label text files, for analysis
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc) {
      if (!setParam(&params, argv[++i])) {
        std::fprintf(stderr, "unknown parameter in --set %s\n", argv[i]);
        return 2;
      }
    } else if (a == "--dump" && i + 1 < argc) {
      dump_dir = argv[++i];
    } else if (a == "--ascii" && i + 1 < argc) {
      ascii_half_m = std::atof(argv[++i]);
    } else if (a == "--kitti-object") {
      kitti_object_dir = std::string(env ? env : "../shared/data") + "/kitti_object";
      if (i + 1 < argc && argv[i + 1][0] != '-') kitti_object_dir = argv[++i];
    } else if (a == "-v") {
      verbose = true;
    } else if (a == "-h" || a == "--help") {
      std::printf("usage: %s [DIR] [-v] [--dump DIR] [--ascii HALF_SIDE_M] [--kitti-object [DIR]] [--set name=value ...]\n", argv[0]);
      return 0;
    } else {
      dir = a;
    }
  }
  if (!kitti_object_dir.empty()) {
    evalKittiObject(kitti_object_dir, params);
    return 0;
  }
  std::vector<std::string> scans;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir + "/velodyne", ec)) {
    if (e.path().extension() == ".bin") scans.push_back(e.path().stem().string());
  }
  if (scans.empty()) {
    std::fprintf(stderr, "no SemanticKITTI scans in %s/velodyne (data absent?)\n", dir.c_str());
    return 1;
  }
  std::sort(scans.begin(), scans.end());

  Counts with_hough, without_hough;
  core::GridSegmenterParams p_off = params;
  p_off.hough.enabled = false;
  core::GridSegmenterParams p_on = params;
  p_on.hough.enabled = true;
  core::GridSegmenter seg_on(p_on), seg_off(p_off);
  urban_detection::CloudXYZIRT cloud;
  std::vector<std::uint32_t> gt;
  std::vector<SegmentClass> labels;
  for (const std::string& s : scans) {
    std::string err;
    if (!core::readKittiBin(dir + "/velodyne/" + s + ".bin", &cloud, &err) ||
        !core::readSemanticKittiLabels(dir + "/labels/" + s + ".label", &gt, &err)) {
      std::fprintf(stderr, "skipping %s: %s\n", s.c_str(), err.c_str());
      continue;
    }
    if (gt.size() != cloud.size()) {
      std::fprintf(stderr, "skipping %s: %zu labels for %zu points\n", s.c_str(), gt.size(),
                   cloud.size());
      continue;
    }
    for (int k = 0; k < 2; ++k) {
      core::GridSegmenter& seg = k == 0 ? seg_on : seg_off;
      Counts& c = k == 0 ? with_hough : without_hough;
      const auto t0 = std::chrono::steady_clock::now();
      seg.segment(cloud, &labels);
      c.ms_total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                        .count();
      ++c.frames;
      accumulate(gt, labels, &c);
      if (ascii_half_m > 0.0 && s == scans.back()) printAscii(seg, ascii_half_m);
      if (!dump_dir.empty()) {
        FILE* f = std::fopen((dump_dir + "/" + s + (k == 0 ? "_on" : "_off") + ".txt").c_str(), "w");
        for (std::size_t i = 0; f && i < cloud.size(); ++i) {
          std::fprintf(f, "%.3f %.3f %.3f %u %d\n", cloud[i].x, cloud[i].y, cloud[i].z,
                       core::semanticKittiStaticClass(gt[i]), static_cast<int>(labels[i]));
        }
        if (f) std::fclose(f);
      }
    }
  }
  std::printf("SemanticKITTI %s, %d scans (points with label unlabeled/outlier ignored)\n",
              dir.c_str(), with_hough.frames);
  std::printf("| hough     | gnd P  | gnd R  | gnd F1 | wall not-fg (n)  | car fg (n)       | "
              "person fg (n)    | cyclist fg (n)   | other veh fg (n) | veg/pole fg | ms/scan |\n");
  print("on", with_hough);
  print("off", without_hough);
  if (verbose) {
    printConfusion("on", with_hough);
    printConfusion("off", without_hough);
  }
  return 0;
}
