#include "urban_detection/core/evaluation/segmentation_eval.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <utility>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/evaluation/augmentation.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/ground_truth.h"

namespace urban_detection {
namespace core {

namespace fs = std::filesystem;
namespace sk = semantic_kitti;

SegGroup semanticKittiGroup(std::uint32_t label) {
  const std::uint16_t cls = semanticKittiStaticClass(label);
  if (cls == sk::kUnlabeled || cls == sk::kOutlier) return SegGroup::kIgnore;
  if (isSemanticKittiGround(cls)) return SegGroup::kGround;
  switch (cls) {
    case sk::kBuilding:
    case sk::kFence:
      return SegGroup::kWall;
    case sk::kCar:
      return SegGroup::kCar;
    case sk::kPerson:
      return SegGroup::kPerson;
    case sk::kBicyclist:
    case sk::kMotorcyclist:
      return SegGroup::kCyclist;
    case sk::kTruck:
    case sk::kOtherVehicle:
    case sk::kBicycle:
    case sk::kMotorcycle:
      return SegGroup::kOtherVehicle;
    case sk::kVegetation:
    case sk::kTrunk:
    case sk::kPole:
    case sk::kTrafficSign:
      return SegGroup::kVegPole;
    default:
      return SegGroup::kOther;
  }
}

SegGroup simulatedGroup(std::uint8_t c) {
  switch (static_cast<ObjectClass>(c)) {
    case ObjectClass::kGround:
    case ObjectClass::kTerrain:
      return SegGroup::kGround;
    case ObjectClass::kWall:
      return SegGroup::kWall;
    case ObjectClass::kCar:
      return SegGroup::kCar;
    case ObjectClass::kVan:
      return SegGroup::kOtherVehicle;
    case ObjectClass::kPedestrian:
      return SegGroup::kPerson;
    case ObjectClass::kCyclist:
      return SegGroup::kCyclist;
    case ObjectClass::kVegetation:
    case ObjectClass::kTrunk:
    case ObjectClass::kPole:
    case ObjectClass::kSign:
      return SegGroup::kVegPole;
    case ObjectClass::kBin:
    case ObjectClass::kBench:
      return SegGroup::kStreetObject;
    default:
      return SegGroup::kIgnore;
  }
}

double segRatio(long a, long b) {
  return b > 0 ? static_cast<double>(a) / static_cast<double>(b) : 0.0;
}

void accumulate(const std::vector<SegGroup>& gt, const std::vector<SegmentClass>& pred,
                SegCounts* c) {
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const SegGroup g = gt[i];
    if (g == SegGroup::kIgnore) continue;
    const bool is_ground = g == SegGroup::kGround;
    const bool pred_ground = pred[i] == SegmentClass::kGround;
    c->ground_tp += is_ground && pred_ground;
    c->ground_fp += !is_ground && pred_ground;
    c->ground_fn += is_ground && !pred_ground;
    const int row = is_ground                                             ? 0
                    : g == SegGroup::kWall                                ? 1
                    : g == SegGroup::kCar                                 ? 2
                    : (g == SegGroup::kPerson || g == SegGroup::kCyclist) ? 3
                                                                          : 4;
    ++c->confusion[row][static_cast<int>(pred[i]) % 5];
    SegShare& s = c->group[static_cast<int>(g)];
    ++s.total;
    s.fg += pred[i] == SegmentClass::kShort;
  }
}

double groundPrecision(const SegCounts& c) {
  return segRatio(c.ground_tp, c.ground_tp + c.ground_fp);
}
double groundRecall(const SegCounts& c) {
  return segRatio(c.ground_tp, c.ground_tp + c.ground_fn);
}
double groundF1(const SegCounts& c) {
  const double p = groundPrecision(c), r = groundRecall(c);
  return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
}
double notForeground(const SegShare& s) {
  return segRatio(s.total - s.fg, s.total);
}
double foreground(const SegShare& s) {
  return segRatio(s.fg, s.total);
}

namespace {

GridSegmenterParams withHough(GridSegmenterParams p, bool on) {
  p.hough.enabled = on;
  return p;
}

}  // namespace

SegmentationEvaluator::SegmentationEvaluator(const GridSegmenterParams& params)
    : seg_on_(withHough(params, true)), seg_off_(withHough(params, false)) {}

void SegmentationEvaluator::frame(const CloudXYZIRT& cloud, const std::vector<SegGroup>& groups,
                                  const std::string& dump) {
  for (int k = 0; k < 2; ++k) {
    GridSegmenter& seg = k == 0 ? seg_on_ : seg_off_;
    SegCounts& c = k == 0 ? on_ : off_;
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

bool evaluateKittiObjectSegmentation(const std::string& dir, const GridSegmenterParams& params,
                                     KittiObjectSegmentation* out) {
  const std::vector<std::string> bins = listFiles(dir + "/velodyne", ".bin");
  if (bins.empty()) return false;
  std::map<std::string, std::array<long, 3>>& per_class = out->per_class;
  per_class.clear();
  GridSegmenterParams p_on = params, p_off = params;
  p_on.hough.enabled = true;
  p_off.hough.enabled = false;
  out->segmenter_on = std::make_shared<GridSegmenter>(p_on);
  GridSegmenter& seg_on = *out->segmenter_on;
  GridSegmenter seg_off(p_off);
  int& frames = out->frames;
  frames = 0;
  for (const std::string& bin : bins) {
    const std::string stem = fs::path(bin).stem().string();
    CloudXYZIRT cloud;
    std::vector<KittiLabel> labels;
    KittiCalibration calib;
    std::string err;
    if (!readKittiBin(bin, &cloud, &err) ||
        !readKittiLabels(dir + "/label_2/" + stem + ".txt", &labels, &err) ||
        !readKittiCalibration(dir + "/calib/" + stem + ".txt", &calib, &err)) {
      std::fprintf(stderr, "skipping KITTI object %s: %s\n", stem.c_str(), err.c_str());
      continue;
    }
    KittiGroundTruthParams gp;
    int w = gp.image_width_px, h = gp.image_height_px;
    readPngSize(dir + "/image_2/" + stem + ".png", &w, &h);
    EvalFrame gt;
    buildKittiGroundTruth(cloud, labels, calib, gp, w, h, &gt);
    std::vector<SegmentClass> on, off;
    seg_on.segment(cloud, &on);
    seg_off.segment(cloud, &off);
    ++frames;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const std::int32_t o = gt.object_of_point[i];
      if (o < 0 || gt.objects[o].ignored) continue;
      if (!gt.role.empty() && gt.role[i] != PointRole::kScored) continue;
      auto& c = per_class[gt.objects[o].label];
      ++c[0];
      c[1] += on[i] == SegmentClass::kShort;
      c[2] += off[i] == SegmentClass::kShort;
    }
  }
  return true;
}

bool evaluateSemanticKittiSegmentation(const std::string& dir, const std::string& dump_dir,
                                       SegmentationEvaluator* ev) {
  std::vector<std::string> scans;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir + "/velodyne", ec)) {
    if (e.path().extension() == ".bin") scans.push_back(e.path().stem().string());
  }
  std::sort(scans.begin(), scans.end());
  CloudXYZIRT cloud;
  std::vector<std::uint32_t> labels;
  std::vector<SegGroup> groups;
  for (const std::string& s : scans) {
    std::string err;
    if (!readKittiBin(dir + "/velodyne/" + s + ".bin", &cloud, &err) ||
        !readSemanticKittiLabels(dir + "/labels/" + s + ".label", &labels, &err)) {
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

bool evaluateSimulatedSegmentation(const std::string& gt_path, const std::string& pcap_path,
                                   const std::string& calibration_path, long max_frames,
                                   const std::string& dump_dir, SegmentationEvaluator* ev,
                                   std::string* error) {
  try {
    SimulatedDriveReader reader(pcap_path, gt_path, loadCalibration(calibration_path));
    CloudXYZIRT cloud;
    GroundTruthFrame gt;
    std::vector<SegGroup> groups;
    std::string message;
    long skipped = 0;
    while (max_frames < 0 || ev->on().frames < max_frames) {
      const auto r = reader.next(&cloud, &gt, &message);
      if (r == SimulatedDriveReader::Result::kEnd) break;
      if (r == SimulatedDriveReader::Result::kSkipped) {
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
    *error = e.what();
    return false;
  }
  if (ev->on().frames == 0) {
    *error = "no revolution of " + pcap_path + " matched a frame of " + gt_path;
    return false;
  }
  return true;
}

bool writeSegmentationJson(const std::string& path, const std::string& dataset,
                           const std::string& source, const SegCounts& on, const SegCounts& off) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return false;
  std::fprintf(f, "{\n  \"dataset\": \"%s\",\n  \"path\": \"%s\",\n  \"frames\": %d",
               dataset.c_str(), jsonEscape(source).c_str(), on.frames);
  const std::pair<const char*, SegGroup> shares[] = {{"car", SegGroup::kCar},
                                                     {"person", SegGroup::kPerson},
                                                     {"cyclist", SegGroup::kCyclist},
                                                     {"other_vehicle", SegGroup::kOtherVehicle},
                                                     {"street_object", SegGroup::kStreetObject},
                                                     {"veg_pole", SegGroup::kVegPole}};
  for (int k = 0; k < 2; ++k) {
    const SegCounts& c = k == 0 ? on : off;
    std::fprintf(f,
                 ",\n  \"%s\": {\"ground_precision\": %.6f, \"ground_recall\": %.6f, "
                 "\"ground_f1\": %.6f, \"ground_points\": %ld, \"wall_not_foreground\": %.6f, "
                 "\"wall_points\": %ld",
                 k == 0 ? "hough_on" : "hough_off", groundPrecision(c), groundRecall(c),
                 groundF1(c), c.ground_tp + c.ground_fn, notForeground(c.of(SegGroup::kWall)),
                 c.of(SegGroup::kWall).total);
    for (const auto& s : shares) {
      std::fprintf(f, ", \"%s_foreground\": %.6f, \"%s_points\": %ld", s.first,
                   foreground(c.of(s.second)), s.first, c.of(s.second).total);
    }
    std::fprintf(f, ", \"ms_per_frame\": %.4f}", c.frames > 0 ? c.ms_total / c.frames : 0.0);
  }
  std::fprintf(f, "\n}\n");
  return std::fclose(f) == 0;
}

std::string cellClassesAscii(const GridSegmenter& seg, double half_m) {
  std::string out;
  const SimpleGrid& g = seg.grid();
  const int half = static_cast<int>(half_m / g.params().cell_size_m);
  const int r0 = g.rows() / 2, c0 = g.cols() / 2;
  out += std::string("cells of the last scan, +x right, +y up, hough ") +
         (seg.params().hough.enabled ? "on" : "off") + "\n";
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
      out += ch;
    }
    out += '\n';
  }
  return out;
}

}  // namespace core
}  // namespace urban_detection
