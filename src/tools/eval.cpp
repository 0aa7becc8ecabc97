// urban_detection_eval: offline F-rate evaluation of the core pipeline (segmentation + object
// detector) on a labelled dataset, scored as in the paper (Sec. 5). No ROS master needed.
//
//   urban_detection_eval (--kitti-object DIR | --semantic-kitti DIR | --sim GTFILE --pcap PCAP)
//                        [--detector hierarchical|kdtree|both] [--config FILE]...
//                        [--json FILE] [--max-frames N] [--min-gt-points N] [--details]
//
// The ground-truth rules of each dataset are documented in eval_datasets.h.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/eval_datasets.h"
#include "urban_detection/core/evaluation.h"
#include "urban_detection/core/grid_segmenter.h"
#include "urban_detection/core/hierarchical_grid_detector.h"
#include "urban_detection/core/kdtree_detector.h"
#include "urban_detection/core/kitti_io.h"
#include "urban_detection/core/params_yaml.h"
#include "urban_detection/ros/segmentation_params.h"

#include "tool_common.h"

namespace core = urban_detection::core;
namespace fs = std::filesystem;

namespace {

// ------------------------------------------------------------------------------------------
// Datasets

struct Frame {
  std::string id;
  urban_detection::CloudXYZIRT cloud;
  core::EvalFrame gt;
  std::vector<std::uint16_t> point_class;  // dataset class per point, for diagnostics
};

class Dataset {
 public:
  virtual ~Dataset() = default;
  virtual std::string name() const = 0;
  virtual std::size_t size() const = 0;
  virtual bool load(std::size_t i, Frame* f, std::string* error) = 0;
  virtual std::string className(std::uint16_t c) const = 0;
};

class KittiObjectDataset : public Dataset {
 public:
  // Point classes for diagnostics.
  enum : std::uint16_t { kBackground = 0, kOutOfView = 1, kDontCareBox = 2, kExcluded = 3,
                         kInBox = 4 };
  KittiObjectDataset(const std::string& dir, const core::KittiGroundTruthParams& p)
      : dir_(dir), params_(p), bins_(core::listFiles(dir + "/velodyne", ".bin")) {}
  std::string name() const override { return "kitti_object"; }
  std::size_t size() const override { return bins_.size(); }
  bool load(std::size_t i, Frame* f, std::string* error) override {
    const std::string stem = fs::path(bins_[i]).stem().string();
    f->id = stem;
    if (!core::readKittiBin(bins_[i], &f->cloud, error)) return false;
    core::KittiCalibration calib;
    if (!core::readKittiCalibration(dir_ + "/calib/" + stem + ".txt", &calib, error)) {
      return false;
    }
    std::vector<core::KittiLabel> labels;
    if (!core::readKittiLabels(dir_ + "/label_2/" + stem + ".txt", &labels, error)) return false;
    int w = params_.image_width_px, h = params_.image_height_px;
    core::readPngSize(dir_ + "/image_2/" + stem + ".png", &w, &h);  // keeps defaults if absent
    core::buildKittiGroundTruth(f->cloud, labels, calib, params_, w, h, &f->gt);
    f->point_class.resize(f->cloud.size());
    for (std::size_t k = 0; k < f->cloud.size(); ++k) {
      std::uint16_t c = kBackground;
      if (f->gt.object_of_point[k] >= 0) {
        c = kInBox;
      } else if (f->gt.role[k] == core::PointRole::kExcluded) {
        c = kExcluded;
      } else if (f->gt.role[k] == core::PointRole::kDontCare) {
        double u, v;
        const auto& p = f->cloud[k];
        c = calib.project({p.x, p.y, p.z}, &u, &v) && u >= 0 && u < w && v >= 0 && v < h
                ? kDontCareBox
                : kOutOfView;
      }
      f->point_class[k] = c;
    }
    return true;
  }
  std::string className(std::uint16_t c) const override {
    static const char* names[] = {"unlabelled_in_view", "out_of_camera_view", "dontcare_box",
                                  "ground_under_box", "labelled_box"};
    return c < 5 ? names[c] : "?";
  }

 private:
  std::string dir_;
  core::KittiGroundTruthParams params_;
  std::vector<std::string> bins_;
};

class SemanticKittiDataset : public Dataset {
 public:
  SemanticKittiDataset(const std::string& dir, const core::SemanticKittiGroundTruthParams& p)
      : params_(p) {
    // DIR is a sequence folder (velodyne/, labels/) or the dataset root (sequences/NN/).
    std::vector<std::string> seqs;
    if (fs::is_directory(dir + "/velodyne")) {
      seqs.push_back(dir);
    } else {
      for (const auto& s : core::listFiles(dir + "/sequences", "")) {
        if (fs::is_directory(s + "/velodyne")) seqs.push_back(s);
      }
    }
    for (const auto& s : seqs) {
      for (const auto& b : core::listFiles(s + "/velodyne", ".bin")) {
        const std::string stem = fs::path(b).stem().string();
        const std::string l = s + "/labels/" + stem + ".label";
        if (fs::exists(l)) {
          frames_.push_back({b, l, fs::path(s).filename().string() + "/" + stem});
        }
      }
    }
  }
  std::string name() const override { return "semantic_kitti"; }
  std::size_t size() const override { return frames_.size(); }
  bool load(std::size_t i, Frame* f, std::string* error) override {
    f->id = frames_[i].id;
    if (!core::readKittiBin(frames_[i].bin, &f->cloud, error)) return false;
    if (!core::readSemanticKittiLabels(frames_[i].label, &labels_, error)) return false;
    if (labels_.size() != f->cloud.size()) {
      *error = frames_[i].label + ": " + std::to_string(labels_.size()) + " labels for " +
               std::to_string(f->cloud.size()) + " points";
      return false;
    }
    core::buildSemanticKittiGroundTruth(labels_, params_, &f->gt);
    f->point_class.resize(labels_.size());
    for (std::size_t k = 0; k < labels_.size(); ++k) {
      f->point_class[k] = core::semanticKittiClass(labels_[k]);
    }
    return true;
  }
  std::string className(std::uint16_t c) const override {
    return core::semanticKittiClassName(c);
  }

 private:
  struct Item {
    std::string bin, label, id;
  };
  core::SemanticKittiGroundTruthParams params_;
  std::vector<Item> frames_;
  std::vector<std::uint32_t> labels_;
};

// ------------------------------------------------------------------------------------------
// Diagnostics: why was a GT object missed, what are the false detections made of.

struct Diagnostics {
  std::map<std::string, std::size_t> missed_by_cause;
  std::map<std::string, std::size_t> false_by_class;
};

const char* segName(core::SegmentClass c) { return core::toString(c); }

// Explains each missed GT object and each false detection of one frame; appends to `diag`
// and, when `out` is not null, prints one line per object.
void diagnose(const Frame& f, const Dataset& ds, const std::vector<core::SegmentClass>& seg,
              const std::vector<core::DetectedObject>& dets, const core::FrameMatch& m,
              const std::string& detector, Diagnostics* diag, FILE* out) {
  const std::size_t n = f.cloud.size();
  std::vector<std::int32_t> det_of_point(n, -1);
  for (std::size_t d = 0; d < dets.size(); ++d) {
    for (std::uint32_t idx : dets[d].indices) {
      if (idx < n) det_of_point[idx] = static_cast<std::int32_t>(d);
    }
  }
  const bool has_roles = f.gt.role.size() == n;
  // Points of each GT object.
  std::vector<std::vector<std::uint32_t>> pts(f.gt.objects.size());
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t g = f.gt.object_of_point[i];
    if (g >= 0 && !(has_roles && f.gt.role[i] == core::PointRole::kExcluded)) {
      pts[g].push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::size_t g = 0; g < f.gt.objects.size(); ++g) {
    const core::EvalObject& o = f.gt.objects[g];
    if (o.ignored || m.matched_detection[g] >= 0 || pts[g].empty()) continue;
    std::map<core::SegmentClass, std::size_t> seg_count;
    std::map<std::int32_t, std::size_t> det_count;
    double cx = 0, cy = 0;
    for (std::uint32_t i : pts[g]) {
      ++seg_count[i < seg.size() ? seg[i] : core::SegmentClass::kUnknown];
      if (det_of_point[i] >= 0) ++det_count[det_of_point[i]];
      cx += f.cloud[i].x;
      cy += f.cloud[i].y;
    }
    const double np = static_cast<double>(pts[g].size());
    const double range = std::hypot(cx / np, cy / np);
    const std::size_t fg = seg_count[core::SegmentClass::kShort];
    std::string cause;
    if (fg < 0.5 * np) {
      core::SegmentClass worst = core::SegmentClass::kUnknown;
      std::size_t most = 0;
      for (const auto& kv : seg_count) {
        if (kv.first != core::SegmentClass::kShort && kv.second > most) {
          most = kv.second;
          worst = kv.first;
        }
      }
      cause = std::string("segmentation:not_foreground(") + segName(worst) + ")";
    } else {
      std::int32_t best = -1;
      std::size_t best_n = 0, in_dets = 0;
      for (const auto& kv : det_count) {
        in_dets += kv.second;
        if (kv.second > best_n) {
          best_n = kv.second;
          best = kv.first;
        }
      }
      if (in_dets < 0.5 * fg) {
        cause = "detector:dropped(small_or_noise)";
      } else if (best_n >= 0.5 * np) {
        // Holds most of the object but IoU < 0.5: the detection is much larger.
        std::map<std::string, std::size_t> content;
        for (std::uint32_t i : dets[best].indices) {
          if (i >= n) continue;
          const std::int32_t og = f.gt.object_of_point[i];
          if (og == static_cast<std::int32_t>(g)) continue;
          content[og >= 0 ? "other_object" : ds.className(f.point_class[i])]++;
        }
        std::string what = "?";
        std::size_t most = 0;
        for (const auto& kv : content) {
          if (kv.second > most) {
            most = kv.second;
            what = kv.first;
          }
        }
        cause = "detector:merged_with(" + what + ")";
      } else if (det_count.size() >= 2) {
        cause = "detector:split";
      } else {
        cause = "partly_foreground";
      }
    }
    ++diag->missed_by_cause[cause];
    if (out) {
      std::fprintf(out, "  %s %-18s missed %-12s id %-5u %6zu pts %5.1f m  fg %3.0f%%  %s\n",
                   f.id.c_str(), detector.c_str(), o.label.c_str(), o.id, pts[g].size(), range,
                   100.0 * fg / np, cause.c_str());
    }
  }
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (m.verdict[d] != core::DetectionVerdict::kFalse) continue;
    std::map<std::string, std::size_t> content;
    for (std::uint32_t i : dets[d].indices) {
      if (i >= n) continue;
      const std::int32_t og = f.gt.object_of_point[i];
      content[og >= 0 ? "part_of_" + f.gt.objects[og].label : ds.className(f.point_class[i])]++;
    }
    std::string what = "?";
    std::size_t most = 0;
    for (const auto& kv : content) {
      if (kv.second > most) {
        most = kv.second;
        what = kv.first;
      }
    }
    ++diag->false_by_class[what];
    if (out) {
      const auto& c = dets[d].centroid;
      std::fprintf(out, "  %s %-18s false  %-28s %6zu pts %5.1f m  (%.1f, %.1f)\n",
                   f.id.c_str(), detector.c_str(), what.c_str(), dets[d].indices.size(),
                   std::hypot(c.x(), c.y()), c.x(), c.y());
    }
  }
}

// ------------------------------------------------------------------------------------------
// Output

std::string jsonEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o;
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char b[32];
  std::snprintf(b, sizeof(b), "%.6g", v);
  return b;
}

std::string scoreJson(const core::DetectionScore& s) {
  std::ostringstream o;
  o << "\"no\": " << s.no << ", \"mo\": " << s.mo << ", \"fo\": " << s.fo << ", \"tp\": " << s.tp
    << ", \"ignored\": " << s.ignored << ", \"detections\": " << s.detections
    << ", \"precision\": " << num(s.precision()) << ", \"recall\": " << num(s.recall())
    << ", \"f_rate\": " << num(s.fRate());
  return o.str();
}

std::string countsJson(const std::map<std::string, std::size_t>& m) {
  std::ostringstream o;
  o << "{";
  bool first = true;
  for (const auto& kv : m) {
    o << (first ? "" : ", ") << "\"" << jsonEscape(kv.first) << "\": " << kv.second;
    first = false;
  }
  o << "}";
  return o.str();
}

void usage() {
  std::fprintf(stderr,
      "usage: urban_detection_eval (--kitti-object DIR | --semantic-kitti DIR)\n"
      "         [--detector hierarchical|kdtree|both] [--config FILE]... [--json FILE]\n"
      "         [--max-frames N] [--min-gt-points N] [--details]\n"
      "  --config FILE   segmentation.yaml or detection.yaml style file (auto-detected by its\n"
      "                  keys), or a combined file with `segmentation:` / `detection:` maps;\n"
      "                  later files override earlier ones. Without it the in-class defaults\n"
      "                  (mirrored by config/*.yaml) are used.\n"
      "  --details       print every missed object and false detection with its cause\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string kitti_dir, skitti_dir, json_path, detector_arg = "hierarchical";
  std::vector<std::string> configs;
  long max_frames = -1;
  long min_gt_points = 10;
  bool details = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* what) { return urban_detection::tools::optionValue(argc, argv, &i, what); };
    auto integer = [&](const char* what) { return urban_detection::tools::optionCount(argc, argv, &i, what); };
    if (a == "--kitti-object") kitti_dir = value("--kitti-object");
    else if (a == "--semantic-kitti") skitti_dir = value("--semantic-kitti");
    else if (a == "--detector") detector_arg = value("--detector");
    else if (a == "--config") configs.push_back(value("--config"));
    else if (a == "--json") json_path = value("--json");
    else if (a == "--max-frames") max_frames = integer("--max-frames");
    else if (a == "--min-gt-points") min_gt_points = integer("--min-gt-points");
    else if (a == "--details") details = true;
    else if (a == "-h" || a == "--help") { usage(); return 0; }
    else {
      std::fprintf(stderr, "error: unknown argument '%s'\n", a.c_str());
      usage();
      return 2;
    }
  }
  if ((kitti_dir.empty() + skitti_dir.empty()) != 1) {
    std::fprintf(stderr, "error: give exactly one dataset\n");
    usage();
    return 2;
  }

  // Parameters: in-class defaults, then each --config file in order.
  core::GridSegmenterParams seg_params;
  core::HierarchicalGridDetectorParams hier_params;
  core::KdTreeDetectorParams kd_params;
  for (const std::string& c : configs) {
    std::string err;
    if (!core::loadPipelineParamsYaml(c, &seg_params, &hier_params, &kd_params, &err)) {
      std::fprintf(stderr, "error: %s\n", err.c_str());
      return 2;
    }
  }

  std::vector<std::unique_ptr<core::ObjectDetector>> detectors;
  try {
    if (detector_arg == "hierarchical" || detector_arg == "both") {
      detectors.emplace_back(new core::HierarchicalGridDetector(hier_params));
    }
    if (detector_arg == "kdtree" || detector_arg == "both") {
      detectors.emplace_back(new core::KdTreeDetector(kd_params));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: invalid detector parameters: %s\n", e.what());
    return 2;
  }
  if (detectors.empty()) {
    std::fprintf(stderr, "error: --detector must be hierarchical, kdtree or both\n");
    return 2;
  }
  std::string seg_error;
  if (!urban_detection::ros_conv::validateGridSegmenterParams(seg_params, &seg_error)) {
    std::fprintf(stderr, "error: invalid segmentation parameters: %s\n", seg_error.c_str());
    return 2;
  }
  core::GridSegmenter segmenter(seg_params);

  std::unique_ptr<Dataset> dataset;
  std::string dataset_path;
  if (!kitti_dir.empty()) {
    core::KittiGroundTruthParams p;
    p.min_points = static_cast<std::size_t>(min_gt_points);
    dataset.reset(new KittiObjectDataset(kitti_dir, p));
    dataset_path = kitti_dir;
  } else {
    core::SemanticKittiGroundTruthParams p;
    p.min_points = static_cast<std::size_t>(min_gt_points);
    dataset.reset(new SemanticKittiDataset(skitti_dir, p));
    dataset_path = skitti_dir;
  }
  if (dataset->size() == 0) {
    std::fprintf(stderr, "error: no frames found in %s\n", dataset_path.c_str());
    return 1;
  }
  std::size_t frames = dataset->size();
  if (max_frames >= 0) frames = std::min<std::size_t>(frames, static_cast<std::size_t>(max_frames));

  std::vector<core::DetectionEvaluator> evaluators(detectors.size());
  std::vector<Diagnostics> diags(detectors.size());
  std::map<std::string, std::size_t> fg_composition;  // foreground points by dataset class
  std::ostringstream rows;
  bool first_row = true;
  std::size_t failed = 0;
  Frame f;
  std::vector<core::SegmentClass> seg;
  urban_detection::LabeledCloud foreground;
  std::vector<core::DetectedObject> objects;
  core::FrameMatch match;
  if (details) std::printf("per-object details (missed GT objects, false detections):\n");
  for (std::size_t i = 0; i < frames; ++i) {
    std::string err;
    if (!dataset->load(i, &f, &err)) {
      std::fprintf(stderr, "warning: skipping frame %zu: %s\n", i, err.c_str());
      ++failed;
      continue;
    }
    segmenter.segment(f.cloud, &seg);
    core::extractForeground(f.cloud, seg, &foreground);
    // What the foreground is made of (dataset classes): shows walls or vegetation leaking in.
    for (const auto& p : foreground) {
      if (p.index >= f.point_class.size()) continue;
      const std::int32_t g = f.gt.object_of_point[p.index];
      ++fg_composition[g >= 0 ? "gt_object:" + f.gt.objects[g].label
                              : dataset->className(f.point_class[p.index])];
    }
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      detectors[k]->detect(foreground, &objects);
      evaluators[k].evaluate(f.gt, objects, &match);
      diagnose(f, *dataset, seg, objects, match, detectors[k]->name(), &diags[k],
               details ? stdout : nullptr);
      rows << (first_row ? "" : ",\n") << "    {\"frame\": \"" << jsonEscape(f.id)
           << "\", \"detector\": \"" << detectors[k]->name() << "\", " << scoreJson(match.score)
           << "}";
      first_row = false;
    }
  }

  std::printf("\n%-15s %-18s %6s %5s %5s %5s %5s %9s %7s %7s\n", "dataset", "detector", "frames",
              "NO", "MO", "FO", "ign", "precision", "recall", "F-rate");
  for (std::size_t k = 0; k < detectors.size(); ++k) {
    const core::DetectionScore& t = evaluators[k].total();
    std::printf("%-15s %-18s %6zu %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
                dataset->name().c_str(), detectors[k]->name().c_str(), frames - failed, t.no,
                t.mo, t.fo, t.ignored, t.precision(), t.recall(), t.fRate());
  }
  std::printf("foreground points by class: %s\n", countsJson(fg_composition).c_str());
  for (std::size_t k = 0; k < detectors.size(); ++k) {
    std::printf("%s: missed by cause %s; false by content %s\n", detectors[k]->name().c_str(),
                countsJson(diags[k].missed_by_cause).c_str(),
                countsJson(diags[k].false_by_class).c_str());
  }

  if (!json_path.empty()) {
    std::ofstream out(json_path);
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
    out << "{\n  \"dataset\": \"" << dataset->name() << "\",\n  \"path\": \""
        << jsonEscape(dataset_path) << "\",\n  \"frames_evaluated\": " << frames - failed
        << ",\n  \"frames_failed\": " << failed << ",\n  \"min_iou\": "
        << num(evaluators[0].params().min_iou) << ",\n  \"min_gt_points\": " << min_gt_points
        << ",\n  \"configs\": [";
    for (std::size_t c = 0; c < configs.size(); ++c) {
      out << (c ? ", " : "") << "\"" << jsonEscape(configs[c]) << "\"";
    }
    out << "],\n  \"detectors\": [";
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      out << (k ? ", " : "") << "\"" << detectors[k]->name() << "\"";
    }
    out << "],\n  \"frames\": [\n" << rows.str() << "\n  ],\n";
    out << "  \"overall\": {" << scoreJson(evaluators[0].total()) << "},\n";
    out << "  \"by_detector\": {";
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      out << (k ? ",\n" : "\n") << "    \"" << detectors[k]->name() << "\": {"
          << scoreJson(evaluators[k].total())
          << ", \"missed_by_cause\": " << countsJson(diags[k].missed_by_cause)
          << ", \"false_by_content\": " << countsJson(diags[k].false_by_class) << "}";
    }
    out << "\n  },\n  \"foreground_points_by_class\": " << countsJson(fg_composition) << "\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: writing %s failed\n", json_path.c_str());
      return 1;
    }
  }
  return failed == frames ? 1 : 0;
}
