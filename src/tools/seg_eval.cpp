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
#include <utility>
#include <vector>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/ground_truth.h"

#include "tool_common.h"

namespace fs = std::filesystem;
namespace core = urban_detection::core;
namespace sk = urban_detection::core::semantic_kitti;
using core::ObjectClass;
using core::SegmentClass;

namespace {

// What a point of either dataset is, for these figures.
enum class Group : std::uint8_t {
  kIgnore,  // unlabeled / outlier
  kGround,  // SemanticKITTI road, sidewalk, parking, other-ground, terrain, lane-marking;
            // simulated road, curb, sidewalk, terrain
  kWall,    // building + fence; simulated facades
  kCar,
  kPerson,
  kCyclist,       // bicyclist + motorcyclist; simulated cyclists with their bicycle
  kOtherVehicle,  // truck, other-vehicle, bicycle, motorcycle; simulated vans
  kVegPole,       // vegetation, trunk, pole, traffic sign (for information)
  kStreetObject,  // simulated bins and benches (short street objects)
  kOther,
};

Group semanticKittiGroup(std::uint32_t label) {
  const std::uint16_t cls = core::semanticKittiStaticClass(label);
  if (cls == sk::kUnlabeled || cls == sk::kOutlier) return Group::kIgnore;
  if (core::isSemanticKittiGround(cls)) return Group::kGround;
  switch (cls) {
    case sk::kBuilding:
    case sk::kFence:
      return Group::kWall;
    case sk::kCar:
      return Group::kCar;
    case sk::kPerson:
      return Group::kPerson;
    case sk::kBicyclist:
    case sk::kMotorcyclist:
      return Group::kCyclist;
    case sk::kTruck:
    case sk::kOtherVehicle:
    case sk::kBicycle:
    case sk::kMotorcycle:
      return Group::kOtherVehicle;
    case sk::kVegetation:
    case sk::kTrunk:
    case sk::kPole:
    case sk::kTrafficSign:
      return Group::kVegPole;
    default:
      return Group::kOther;
  }
}

Group simulatedGroup(std::uint8_t c) {
  switch (static_cast<ObjectClass>(c)) {
    case ObjectClass::kGround:
    case ObjectClass::kTerrain:
      return Group::kGround;
    case ObjectClass::kWall:
      return Group::kWall;
    case ObjectClass::kCar:
      return Group::kCar;
    case ObjectClass::kVan:
      return Group::kOtherVehicle;
    case ObjectClass::kPedestrian:
      return Group::kPerson;
    case ObjectClass::kCyclist:
      return Group::kCyclist;
    case ObjectClass::kVegetation:
    case ObjectClass::kTrunk:
    case ObjectClass::kPole:
    case ObjectClass::kSign:
      return Group::kVegPole;
    case ObjectClass::kBin:
    case ObjectClass::kBench:
      return Group::kStreetObject;
    default:
      return Group::kIgnore;
  }
}

// Points of one group, and how many of them the segmenter put in the foreground (short).
struct Share {
  long total = 0, fg = 0;
};

struct Counts {
  long ground_tp = 0, ground_fp = 0, ground_fn = 0;
  Share group[static_cast<int>(Group::kOther) + 1];
  long confusion[5][5] = {};  // [ground, wall, car, person+cyclist, other][SegmentClass]
  double ms_total = 0.0;
  int frames = 0;
  const Share& of(Group g) const { return group[static_cast<int>(g)]; }
};

double ratio(long a, long b) {
  return b > 0 ? static_cast<double>(a) / static_cast<double>(b) : 0.0;
}

void accumulate(const std::vector<Group>& gt, const std::vector<SegmentClass>& pred, Counts* c) {
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const Group g = gt[i];
    if (g == Group::kIgnore) continue;
    const bool is_ground = g == Group::kGround;
    const bool pred_ground = pred[i] == SegmentClass::kGround;
    c->ground_tp += is_ground && pred_ground;
    c->ground_fp += !is_ground && pred_ground;
    c->ground_fn += is_ground && !pred_ground;
    const int row = is_ground                                       ? 0
                    : g == Group::kWall                             ? 1
                    : g == Group::kCar                              ? 2
                    : (g == Group::kPerson || g == Group::kCyclist) ? 3
                                                                    : 4;
    ++c->confusion[row][static_cast<int>(pred[i]) % 5];
    Share& s = c->group[static_cast<int>(g)];
    ++s.total;
    s.fg += pred[i] == SegmentClass::kShort;
  }
}

double groundPrecision(const Counts& c) {
  return ratio(c.ground_tp, c.ground_tp + c.ground_fp);
}
double groundRecall(const Counts& c) {
  return ratio(c.ground_tp, c.ground_tp + c.ground_fn);
}
double groundF1(const Counts& c) {
  const double p = groundPrecision(c), r = groundRecall(c);
  return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
}
double notFg(const Share& s) {
  return ratio(s.total - s.fg, s.total);
}
double fg(const Share& s) {
  return ratio(s.fg, s.total);
}

void print(const char* name, const Counts& c) {
  const Share& wall = c.of(Group::kWall);
  const Share& car = c.of(Group::kCar);
  const Share& person = c.of(Group::kPerson);
  const Share& cyclist = c.of(Group::kCyclist);
  const Share& vehicle = c.of(Group::kOtherVehicle);
  std::printf(
      "| %-9s | %6.4f | %6.4f | %6.4f | %6.4f (%ld) | %6.4f (%ld) | %6.4f (%ld) | %6.4f (%ld) "
      "| %6.4f (%ld) | %6.4f | %6.2f |\n",
      name, groundPrecision(c), groundRecall(c), groundF1(c), notFg(wall), wall.total, fg(car),
      car.total, fg(person), person.total, fg(cyclist), cyclist.total, fg(vehicle), vehicle.total,
      fg(c.of(Group::kVegPole)), c.frames > 0 ? c.ms_total / c.frames : 0.0);
}

void printTable(const Counts& on, const Counts& off) {
  std::printf(
      "| hough     | gnd P  | gnd R  | gnd F1 | wall not-fg (n)  | car fg (n)       | "
      "person fg (n)    | cyclist fg (n)   | other veh fg (n) | veg/pole fg | ms/scan |\n");
  print("on", on);
  print("off", off);
}

// The figures as JSON (keys: dataset, path, frames, hough_on / hough_off with ground_precision,
// ground_recall, ground_f1, wall_not_foreground, car_foreground, person_foreground,
// cyclist_foreground, other_vehicle_foreground, street_object_foreground and point counts).
bool writeJson(const std::string& path, const std::string& dataset, const std::string& source,
               const Counts& on, const Counts& off) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return false;
  std::fprintf(f, "{\n  \"dataset\": \"%s\",\n  \"path\": \"%s\",\n  \"frames\": %d",
               dataset.c_str(), urban_detection::tools::jsonEscape(source).c_str(), on.frames);
  const std::pair<const char*, Group> shares[] = {{"car", Group::kCar},
                                                  {"person", Group::kPerson},
                                                  {"cyclist", Group::kCyclist},
                                                  {"other_vehicle", Group::kOtherVehicle},
                                                  {"street_object", Group::kStreetObject},
                                                  {"veg_pole", Group::kVegPole}};
  for (int k = 0; k < 2; ++k) {
    const Counts& c = k == 0 ? on : off;
    std::fprintf(f,
                 ",\n  \"%s\": {\"ground_precision\": %.6f, \"ground_recall\": %.6f, "
                 "\"ground_f1\": %.6f, \"ground_points\": %ld, \"wall_not_foreground\": %.6f, "
                 "\"wall_points\": %ld",
                 k == 0 ? "hough_on" : "hough_off", groundPrecision(c), groundRecall(c),
                 groundF1(c), c.ground_tp + c.ground_fn, notFg(c.of(Group::kWall)),
                 c.of(Group::kWall).total);
    for (const auto& s : shares) {
      std::fprintf(f, ", \"%s_foreground\": %.6f, \"%s_points\": %ld", s.first, fg(c.of(s.second)),
                   s.first, c.of(s.second).total);
    }
    std::fprintf(f, ", \"ms_per_frame\": %.4f}", c.frames > 0 ? c.ms_total / c.frames : 0.0);
  }
  std::fprintf(f, "\n}\n");
  return std::fclose(f) == 0;
}

void printConfusion(const char* name, const Counts& c) {
  static const char* groups[5] = {"ground", "building+fence", "car", "person+cyclist", "other"};
  std::printf("confusion (hough %s): rows = SemanticKITTI group, columns = predicted share\n",
              name);
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
          case SegmentClass::kGround:
            ch = '.';
            break;
          case SegmentClass::kTall:
            ch = 'T';
            break;
          case SegmentClass::kShort:
            ch = 's';
            break;
          case SegmentClass::kClutter:
            ch = ',';
            break;
          default:
            break;
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
      {"sensor_height_m", &p->sensor_height_m},
      {"cell_size_m", &p->cell_size_m},
      {"max_range_m", &p->max_range_m},
      {"ground_max_range_m", &p->ground_max_range_m},
      {"ground_tolerance_m", &p->ground_tolerance_m},
      {"ground_max_step_m", &p->ground_max_step_m},
      {"seed_radius_m", &p->seed_radius_m},
      {"ground_max_gap_m", &p->ground_max_gap_m},
      {"seed_max_abs_height_m", &p->seed_max_abs_height_m},
      {"terrain_max_offset_m", &p->terrain_max_offset_m},
      {"fov_top_elevation_deg", &p->fov_top_elevation_deg},
      {"tall_min_height_m", &p->tall_min_height_m},
      {"tall_min_range_m", &p->tall_min_range_m},
      {"vehicle_max_height_m", &p->vehicle_max_height_m},
      {"vehicle_max_length_m", &p->vehicle_max_length_m},
      {"vehicle_max_width_m", &p->vehicle_max_width_m},
      {"hough.max_range_m", &p->hough.max_range_m},
      {"hough.min_line_length_m", &p->hough.min_line_length_m},
      {"hough.max_line_gap_m", &p->hough.max_line_gap_m},
      {"hough.theta_resolution_deg", &p->hough.theta_resolution_deg},
      {"hough.min_tall_fraction", &p->hough.min_tall_fraction},
      {"hough.min_mixed_wall_length_m", &p->hough.min_mixed_wall_length_m}};
  std::map<std::string, int*> di = {
      {"min_points_per_cell", &p->min_points_per_cell},
      {"terrain_fill_iterations", &p->terrain_fill_iterations},
      {"hough.votes", &p->hough.votes},
      {"hough.line_half_width_cells", &p->hough.line_half_width_cells}};
  if (k == "hough.extend_lines") {
    p->hough.extend_lines = v != 0.0;
    return true;
  }
  if (k == "ground_in_sparse_cells") {
    p->ground_in_sparse_cells = v != 0.0;
    return true;
  }
  if (k == "curb_cells_ground") {
    p->curb_cells_ground = v != 0.0;
    return true;
  }
  if (d.count(k)) {
    *d[k] = v;
    return true;
  }
  if (di.count(k)) {
    *di[k] = static_cast<int>(v);
    return true;
  }
  return false;
}

// KITTI object frames: share of the points of labelled objects (inside their 3-D boxes, above
// the ground band, rules of eval_datasets.h) that end up in the foreground, per class.
void evalKittiObject(const std::string& dir, const core::GridSegmenterParams& params,
                     double ascii_half_m) {
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
  if (ascii_half_m > 0.0 && frames > 0) printAscii(seg_on, ascii_half_m);
  std::printf(
      "\nKITTI object %s, %d frames: object points (in boxes, above the ground band) in "
      "the foreground\n| class | points | fg hough on | fg hough off |\n",
      dir.c_str(), frames);
  for (const auto& kv : per_class) {
    std::printf("| %-14s | %6ld | %6.4f | %6.4f |\n", kv.first.c_str(), kv.second[0],
                ratio(kv.second[1], kv.second[0]), ratio(kv.second[2], kv.second[0]));
  }
}

// Segments every frame with Hough on and off and accumulates both against the frame's groups.
class Evaluator {
 public:
  explicit Evaluator(const core::GridSegmenterParams& params)
      : seg_on_(withHough(params, true)), seg_off_(withHough(params, false)) {}

  // `dump` (when not empty) is the path prefix of per-point "x y z group class" text files.
  void frame(const urban_detection::CloudXYZIRT& cloud, const std::vector<Group>& groups,
             const std::string& dump) {
    for (int k = 0; k < 2; ++k) {
      core::GridSegmenter& seg = k == 0 ? seg_on_ : seg_off_;
      Counts& c = k == 0 ? on_ : off_;
      const auto t0 = std::chrono::steady_clock::now();
      seg.segment(cloud, &labels_);
      c.ms_total +=
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      ++c.frames;
      accumulate(groups, labels_, &c);
      if (!dump.empty()) {
        FILE* f = std::fopen((dump + (k == 0 ? "_on" : "_off") + ".txt").c_str(), "w");
        for (std::size_t i = 0; f && i < cloud.size(); ++i) {
          std::fprintf(f, "%.3f %.3f %.3f %d %d\n", cloud[i].x, cloud[i].y, cloud[i].z,
                       static_cast<int>(groups[i]), static_cast<int>(labels_[i]));
        }
        if (f) std::fclose(f);
      }
    }
  }
  void printAsciiOfLast(double half_m) const {
    printAscii(seg_on_, half_m);
    printAscii(seg_off_, half_m);
  }
  const Counts& on() const { return on_; }
  const Counts& off() const { return off_; }

 private:
  static core::GridSegmenterParams withHough(core::GridSegmenterParams p, bool on) {
    p.hough.enabled = on;
    return p;
  }
  core::GridSegmenter seg_on_, seg_off_;
  Counts on_, off_;
  std::vector<SegmentClass> labels_;
};

// SemanticKITTI scans DIR/velodyne/*.bin with DIR/labels/*.label; false when none was read.
bool evalSemanticKitti(const std::string& dir, const std::string& dump_dir, Evaluator* ev) {
  std::vector<std::string> scans;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir + "/velodyne", ec)) {
    if (e.path().extension() == ".bin") scans.push_back(e.path().stem().string());
  }
  std::sort(scans.begin(), scans.end());
  urban_detection::CloudXYZIRT cloud;
  std::vector<std::uint32_t> labels;
  std::vector<Group> groups;
  for (const std::string& s : scans) {
    std::string err;
    if (!core::readKittiBin(dir + "/velodyne/" + s + ".bin", &cloud, &err) ||
        !core::readSemanticKittiLabels(dir + "/labels/" + s + ".label", &labels, &err)) {
      std::fprintf(stderr, "skipping %s: %s\n", s.c_str(), err.c_str());
      continue;
    }
    if (labels.size() != cloud.size()) {
      std::fprintf(stderr, "skipping %s: %zu labels for %zu points\n", s.c_str(), labels.size(),
                   cloud.size());
      continue;
    }
    groups.resize(labels.size());
    std::transform(labels.begin(), labels.end(), groups.begin(), semanticKittiGroup);
    ev->frame(cloud, groups, dump_dir.empty() ? "" : dump_dir + "/" + s);
  }
  return ev->on().frames > 0;
}

// A simulated drive: the revolutions of PCAP against the per-point classes of GTFILE (matched
// by stamp). Returns 0, or 1 with a message when the files cannot be read or hold no frame.
int evalSimulated(const std::string& gt_path, const std::string& pcap_path,
                  const std::string& calibration_path, long max_frames, const std::string& dump_dir,
                  Evaluator* ev) {
  try {
    core::SimulatedDriveReader reader(pcap_path, gt_path, core::loadCalibration(calibration_path));
    urban_detection::CloudXYZIRT cloud;
    core::GroundTruthFrame gt;
    std::vector<Group> groups;
    std::string message;
    long skipped = 0;
    while (max_frames < 0 || ev->on().frames < max_frames) {
      const auto r = reader.next(&cloud, &gt, &message);
      if (r == core::SimulatedDriveReader::Result::kEnd) break;
      if (r == core::SimulatedDriveReader::Result::kSkipped) {
        ++skipped;
        continue;
      }
      groups.resize(gt.classes.size());
      std::transform(gt.classes.begin(), gt.classes.end(), groups.begin(), simulatedGroup);
      ev->frame(cloud, groups,
                dump_dir.empty() ? "" : dump_dir + "/rev" + std::to_string(gt.revolution));
    }
    if (!message.empty()) std::fprintf(stderr, "warning: %s\n", message.c_str());
    if (skipped > 0) {
      std::fprintf(stderr, "%ld revolutions without a ground-truth frame skipped\n", skipped);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  if (ev->on().frames == 0) {
    std::fprintf(stderr, "error: no revolution of %s matched a frame of %s\n", pcap_path.c_str(),
                 gt_path.c_str());
    return 1;
  }
  return 0;
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

  Evaluator ev(params);
  std::string dataset, source;
  if (!sim_gt.empty()) {
    if (const int rc =
            evalSimulated(sim_gt, sim_pcap, calibration_path, max_frames, dump_dir, &ev)) {
      return rc;
    }
    dataset = "sim";
    source = sim_pcap;
    std::printf(
        "Simulated drive %s, %d revolutions, exact per-point classes (walls = facades, "
        "cyclist = rider with bicycle, other vehicle = van)\n",
        sim_pcap.c_str(), ev.on().frames);
  } else {
    if (!evalSemanticKitti(dir, dump_dir, &ev)) {
      std::fprintf(stderr, "no SemanticKITTI scans in %s/velodyne (data absent?)\n", dir.c_str());
      return 1;
    }
    dataset = "semantic_kitti";
    source = dir;
    std::printf("SemanticKITTI %s, %d scans (points with label unlabeled/outlier ignored)\n",
                dir.c_str(), ev.on().frames);
  }
  if (ascii_half_m > 0.0) ev.printAsciiOfLast(ascii_half_m);
  printTable(ev.on(), ev.off());
  if (dataset == "sim") {
    std::printf("bins and benches in the foreground: hough on %.4f, off %.4f (%ld points)\n",
                fg(ev.on().of(Group::kStreetObject)), fg(ev.off().of(Group::kStreetObject)),
                ev.on().of(Group::kStreetObject).total);
  }
  if (verbose) {
    printConfusion("on", ev.on());
    printConfusion("off", ev.off());
  }
  if (!json_path.empty() && !writeJson(json_path, dataset, source, ev.on(), ev.off())) {
    std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
    return 1;
  }
  return 0;
}
