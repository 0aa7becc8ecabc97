// urban_detection_eval: offline F-rate evaluation of the core pipeline (segmentation + object
// detector) on a labelled dataset, scored as in the paper (Sec. 5). No ROS master needed.
//
//   urban_detection_eval (--kitti-object DIR | --semantic-kitti DIR | --sim GTFILE --pcap PCAP)
//                        [--detector hierarchical|kdtree|both] [--config FILE]...
//                        [--json FILE] [--max-frames N] [--min-points N] [--details]
//   urban_detection_eval --tracking (--sim GTFILE --pcap PCAP | --semantic-kitti DIR |
//                        --kitti-tracking DIR)  (CLEAR-MOT
//                        of the tracker after the pipeline; rules in tracking_eval.h)
//
// The ground-truth rules of each dataset (KITTI object, SemanticKITTI, simulated drive) are
// documented in eval_datasets.h.
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

#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/kitti_io.h"

#include <Eigen/Core>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "box_quality_eval.h"
#include "datasets.h"
#include "tool_common.h"
#include "tracking_eval.h"

namespace core = urban_detection::core;
namespace fs = std::filesystem;

using urban_detection::tools::Dataset;
using urban_detection::tools::detectionContent;
using urban_detection::tools::Frame;
using urban_detection::tools::jsonEscape;
using urban_detection::tools::jsonNumber;
using urban_detection::tools::KittiObjectDataset;
using urban_detection::tools::mostCommon;
using urban_detection::tools::SemanticKittiDataset;
using urban_detection::tools::SimulatedDriveDataset;

namespace {

// ------------------------------------------------------------------------------------------
// Diagnostics: why was a GT object missed, what are the false detections made of.

struct Diagnostics {
  std::map<std::string, std::size_t> missed_by_cause;
  std::map<std::string, std::size_t> false_by_class;
  std::map<std::string, std::size_t> false_fragments;  // false parts of GT objects, by kind
};

const char* segName(core::SegmentClass c) {
  return core::toString(c);
}

// Explains each missed GT object and each false detection of one frame; appends to `diag`
// and, when `out` is not null, prints one line per object.
void diagnose(const Frame& f, const Dataset& ds, const std::vector<core::SegmentClass>& seg,
              const std::vector<core::DetectedObject>& dets, const core::FrameMatch& m,
              const std::vector<core::DetectedObject>& classifier_rejected,
              const std::string& detector, Diagnostics* diag, FILE* out) {
  const std::size_t n = f.cloud.size();
  // Points of the detections the classifier rejected: the object it took, if any.
  std::vector<std::int32_t> rejected_of_point(n, -1);
  for (std::size_t d = 0; d < classifier_rejected.size(); ++d) {
    for (std::uint32_t idx : classifier_rejected[d].indices) {
      if (idx < n) rejected_of_point[idx] = static_cast<std::int32_t>(d);
    }
  }
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
        std::size_t in_rejected = 0;
        for (std::uint32_t i : pts[g]) in_rejected += rejected_of_point[i] >= 0;
        cause = in_rejected >= 0.5 * fg ? "classifier:rejected_as_non_object"
                                        : "detector:dropped(small_or_noise)";
      } else if (best_n >= 0.5 * np) {
        // Holds most of the object but IoU < 0.5: the detection is much larger.
        std::map<std::string, std::size_t> content;
        for (std::uint32_t i : dets[best].indices) {
          if (i >= n) continue;
          const std::int32_t og = f.gt.object_of_point[i];
          if (og == static_cast<std::int32_t>(g)) continue;
          content[og >= 0 ? "other_object" : ds.className(f.point_class[i])]++;
        }
        cause = "detector:merged_with(" + mostCommon(content) + ")";
      } else if (det_count.size() >= 2) {
        cause = "detector:split";
      } else {
        cause = "partly_foreground";
      }
    }
    ++diag->missed_by_cause[cause];
    if (out) {
      // The detections holding its points: "points of this object/detection size" each.
      std::string pieces;
      for (const auto& kv : det_count) {
        pieces +=
            " " + std::to_string(kv.second) + "/" + std::to_string(dets[kv.first].indices.size());
      }
      std::fprintf(
          out,
          "  %s %-18s missed %-12s id %-5u %6zu pts %5.1f m (%.1f, %.1f)  fg %3.0f%%  %s  in:%s\n",
          f.id.c_str(), detector.c_str(), o.label.c_str(), o.id, pts[g].size(), range, cx / np,
          cy / np, 100.0 * fg / np, cause.c_str(), pieces.c_str());
    }
  }
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (m.verdict[d] != core::DetectionVerdict::kFalse) continue;
    const std::string what = detectionContent(f, ds, dets[d]);
    ++diag->false_by_class[what];
    // A false detection made mostly of a GT object's points: a merge of several objects, the
    // leftover of an object matched by another detection, or a piece of a missed object; with
    // the segmentation of the object's points outside this detection (what cut it off).
    std::string fragment;
    if (what.compare(0, 8, "part_of_") == 0) {
      std::map<std::int32_t, std::size_t> gt_count;
      for (std::uint32_t i : dets[d].indices) {
        if (i < n && f.gt.object_of_point[i] >= 0) ++gt_count[f.gt.object_of_point[i]];
      }
      std::int32_t g = -1;
      std::size_t gn = 0, objects_over_10 = 0;
      for (const auto& kv : gt_count) {
        if (kv.second >= 10) ++objects_over_10;
        if (kv.second > gn) {
          gn = kv.second;
          g = kv.first;
        }
      }
      std::map<core::SegmentClass, std::size_t> rest_seg;
      std::size_t rest_in_other_det = 0;
      for (std::uint32_t i : pts[g]) {
        if (det_of_point[i] == static_cast<std::int32_t>(d)) continue;
        ++rest_seg[i < seg.size() ? seg[i] : core::SegmentClass::kUnknown];
        if (det_of_point[i] >= 0) ++rest_in_other_det;
      }
      fragment = objects_over_10 >= 2          ? "merge"
                 : m.matched_detection[g] >= 0 ? "leftover_of_matched"
                 : 2 * gn >= pts[g].size()     ? "most_of_missed"
                                               : "piece_of_missed";
      ++diag->false_fragments[fragment];
      if (out) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), " %s gt %u %zu/%zu, rest: other det %zu", fragment.c_str(),
                      f.gt.objects[g].id, gn, pts[g].size(), rest_in_other_det);
        fragment = buf;
        for (const auto& kv : rest_seg) {
          fragment += std::string(" ") + segName(kv.first) + " " + std::to_string(kv.second);
        }
        float zmin = 1e9f, zmax = -1e9f;
        for (std::uint32_t i : dets[d].indices) {
          if (i >= n) continue;
          zmin = std::min(zmin, f.cloud[i].z);
          zmax = std::max(zmax, f.cloud[i].z);
        }
        std::snprintf(buf, sizeof(buf), "; z %.2f..%.2f", zmin, zmax);
        fragment += buf;
      }
    }
    if (out) {
      const auto& c = dets[d].centroid;
      std::fprintf(out, "  %s %-18s false  %-28s %6zu pts %5.1f m  (%.1f, %.1f)%s\n", f.id.c_str(),
                   detector.c_str(), what.c_str(), dets[d].indices.size(), std::hypot(c.x(), c.y()),
                   c.x(), c.y(), fragment.c_str());
    }
  }
}

// ------------------------------------------------------------------------------------------
// Debug pictures (--png DIR): top view of one frame, ground truth left, detections right.

struct PngView {
  double cx = 0.0, cy = 0.0, half_m = 30.0;  // [m] centre and half side of the view
  double px_per_m = 20.0;
};

cv::Scalar idColour(std::uint32_t id) {
  std::uint32_t h = id * 2654435761u;
  return cv::Scalar(60 + (h & 0xFF) % 196, 60 + ((h >> 8) & 0xFF) % 196,
                    60 + ((h >> 16) & 0xFF) % 196);
}

// BGR colours of the object classes, those of the rviz markers (ros/object_markers.cpp).
cv::Scalar classColour(core::ObjectCategory c) {
  switch (c) {
    case core::ObjectCategory::kVehicle:
      return cv::Scalar(255, 150, 40);
    case core::ObjectCategory::kPedestrian:
      return cv::Scalar(110, 70, 255);
    case core::ObjectCategory::kCyclist:
      return cv::Scalar(0, 210, 255);
    case core::ObjectCategory::kOtherObject:
      return cv::Scalar(200, 230, 0);
    default:
      return cv::Scalar(200, 160, 200);  // unclassified
  }
}

void writeFramePng(const std::string& path, const Frame& f, const urban_detection::LabeledCloud& fg,
                   const std::vector<core::DetectedObject>& dets, const core::FrameMatch& m,
                   const PngView& v) {
  const int side = static_cast<int>(2.0 * v.half_m * v.px_per_m);
  cv::Mat img(side, 2 * side + 10, CV_8UC3, cv::Scalar(0, 0, 0));
  auto toPx = [&](double x, double y, int panel) {
    // x forward = up, y left = left.
    return cv::Point(panel * (side + 10) + static_cast<int>((v.half_m - (y - v.cy)) * v.px_per_m),
                     static_cast<int>((v.half_m - (x - v.cx)) * v.px_per_m));
  };
  auto inView = [&](double x, double y) {
    return std::abs(x - v.cx) < v.half_m && std::abs(y - v.cy) < v.half_m;
  };
  const std::size_t n = f.cloud.size();
  std::vector<std::int32_t> det_of(n, -1);
  for (std::size_t d = 0; d < dets.size(); ++d) {
    for (std::uint32_t i : dets[d].indices) {
      if (i < n) det_of[i] = static_cast<std::int32_t>(d);
    }
  }
  std::vector<std::uint8_t> is_fg(n, 0);
  for (const auto& p : fg) {
    if (p.index < n) is_fg[p.index] = 1;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = f.cloud[i];
    if (!inView(p.x, p.y)) continue;
    const std::int32_t g = f.gt.object_of_point[i];
    cv::Scalar cg = cv::Scalar(70, 40, 40);
    if (g >= 0) {
      cg = classColour(core::categoryOfClassName(f.gt.objects[g].label));
    } else if (f.gt.role.size() == n && f.gt.role[i] == core::PointRole::kDontCare) {
      cg = cv::Scalar(110, 110, 110);
    }
    if (!is_fg[i]) cg *= 0.45;
    img.at<cv::Vec3b>(toPx(p.x, p.y, 0)) = cv::Vec3b(cg[0], cg[1], cg[2]);
    cv::Scalar cd = is_fg[i] ? cv::Scalar(90, 90, 90) : cv::Scalar(35, 35, 35);
    if (det_of[i] >= 0) {
      const core::ObjectCategory c = dets[static_cast<std::size_t>(det_of[i])].category;
      cd = c == core::ObjectCategory::kUnknown
               ? idColour(7919u * static_cast<std::uint32_t>(det_of[i] + 1))
               : classColour(c);
    }
    img.at<cv::Vec3b>(toPx(p.x, p.y, 1)) = cv::Vec3b(cd[0], cd[1], cd[2]);
  }
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (m.verdict[d] != core::DetectionVerdict::kFalse) continue;
    const auto& o = dets[d];
    for (int panel = 0; panel < 2; ++panel) {
      cv::rectangle(img, toPx(o.max_pt.x(), o.max_pt.y(), panel) - cv::Point(2, 2),
                    toPx(o.min_pt.x(), o.min_pt.y(), panel) + cv::Point(2, 2),
                    cv::Scalar(0, 0, 255), 1);
    }
  }
  // Missed GT objects: yellow boxes around their points.
  std::vector<Eigen::Vector4d> box(f.gt.objects.size(), Eigen::Vector4d(1e9, 1e9, -1e9, -1e9));
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t g = f.gt.object_of_point[i];
    if (g < 0) continue;
    auto& b = box[g];
    b[0] = std::min<double>(b[0], f.cloud[i].x);
    b[1] = std::min<double>(b[1], f.cloud[i].y);
    b[2] = std::max<double>(b[2], f.cloud[i].x);
    b[3] = std::max<double>(b[3], f.cloud[i].y);
  }
  for (std::size_t g = 0; g < f.gt.objects.size(); ++g) {
    if (f.gt.objects[g].ignored || m.matched_detection[g] >= 0 || box[g][0] > box[g][2]) continue;
    for (int panel = 0; panel < 2; ++panel) {
      cv::rectangle(img, toPx(box[g][2], box[g][3], panel) - cv::Point(3, 3),
                    toPx(box[g][0], box[g][1], panel) + cv::Point(3, 3), cv::Scalar(0, 255, 255),
                    1);
    }
  }
  // 5 m grid ticks and the sensor.
  for (int panel = 0; panel < 2; ++panel) {
    cv::circle(img, toPx(0, 0, panel), 3, cv::Scalar(255, 255, 255), -1);
  }
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(img, f.id + "  ground truth", cv::Point(5, 15), font, 0.5, cv::Scalar(255, 255, 255),
              1);
  cv::putText(img, "detections", cv::Point(side + 15, 15), font, 0.5, cv::Scalar(255, 255, 255), 1);
  // Legend: the classes in their colours, then the marks.
  int y = side - 8;
  const std::pair<const char*, cv::Scalar> legend[] = {
      {"red box: false detection", cv::Scalar(0, 0, 255)},
      {"yellow box: missed object", cv::Scalar(0, 255, 255)},
      {"other_object", classColour(core::ObjectCategory::kOtherObject)},
      {"cyclist", classColour(core::ObjectCategory::kCyclist)},
      {"pedestrian", classColour(core::ObjectCategory::kPedestrian)},
      {"vehicle", classColour(core::ObjectCategory::kVehicle)}};
  for (const auto& l : legend) {
    cv::putText(img, l.first, cv::Point(side + 15, y), font, 0.45, l.second, 1);
    y -= 16;
  }
  cv::imwrite(path, img);
}

// ------------------------------------------------------------------------------------------
// Output

std::string scoreJson(const core::DetectionScore& s) {
  std::ostringstream o;
  o << "\"no\": " << s.no << ", \"mo\": " << s.mo << ", \"fo\": " << s.fo << ", \"tp\": " << s.tp
    << ", \"ignored\": " << s.ignored << ", \"detections\": " << s.detections
    << ", \"precision\": " << jsonNumber(s.precision())
    << ", \"recall\": " << jsonNumber(s.recall()) << ", \"f_rate\": " << jsonNumber(s.fRate());
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

// ------------------------------------------------------------------------------------------
// Another system's output (--detections DIR): per frame, one uint32 per input point, the
// point's instance (0 = none); each instance is one detection.

class ExternalDetections : public core::ObjectDetector {
 public:
  explicit ExternalDetections(const std::string& dir) : dir_(dir) {}
  std::string name() const override { return "external"; }

  // Reads the labels of frame `f`; false with `error` set when the file is missing or its
  // size is not one uint32 per point of the frame's cloud.
  bool load(const Frame& f, std::string* error) {
    std::vector<std::string> candidates = {dir_ + "/" + f.id + ".label"};
    const auto slash = f.id.find('/');
    if (slash != std::string::npos) {
      candidates.push_back(dir_ + "/sequences/" + f.id.substr(0, slash) + "/predictions/" +
                           f.id.substr(slash + 1) + ".label");
    }
    for (const std::string& path : candidates) {
      if (!fs::is_regular_file(path)) continue;
      std::ifstream in(path, std::ios::binary);
      labels_.assign(f.cloud.size(), 0u);
      in.read(reinterpret_cast<char*>(labels_.data()),
              static_cast<std::streamsize>(labels_.size() * sizeof(std::uint32_t)));
      const bool exact = in.gcount() == static_cast<std::streamsize>(labels_.size() * 4) &&
                         in.peek() == std::char_traits<char>::eof();
      if (!exact) {
        *error = path + ": not one uint32 per point of the frame (" +
                 std::to_string(f.cloud.size()) + " points)";
        return false;
      }
      cloud_ = &f.cloud;
      return true;
    }
    *error = "no label file for frame " + f.id + " (tried " + candidates[0] + ")";
    return false;
  }

  void detect(const urban_detection::LabeledCloud& /*foreground*/,
              std::vector<core::DetectedObject>* objects) override {
    objects->clear();
    std::map<std::uint32_t, std::size_t> object_of_label;
    for (std::size_t i = 0; i < labels_.size(); ++i) {
      if (labels_[i] == 0) continue;
      const auto it = object_of_label.emplace(labels_[i], objects->size()).first;
      if (it->second == objects->size()) objects->emplace_back();
      (*objects)[it->second].indices.push_back(static_cast<std::uint32_t>(i));
    }
    for (std::size_t k = 0; k < objects->size(); ++k) {
      core::DetectedObject& o = (*objects)[k];
      o.id = static_cast<std::uint32_t>(k + 1);
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      o.min_pt = Eigen::Vector3f::Constant(1e30f);
      o.max_pt = Eigen::Vector3f::Constant(-1e30f);
      for (const std::uint32_t i : o.indices) {
        const Eigen::Vector3f p((*cloud_)[i].x, (*cloud_)[i].y, (*cloud_)[i].z);
        sum += p;
        o.min_pt = o.min_pt.cwiseMin(p);
        o.max_pt = o.max_pt.cwiseMax(p);
      }
      o.centroid = sum / static_cast<float>(o.indices.size());
      o.obb_center = 0.5f * (o.min_pt + o.max_pt);
      o.obb_size = o.max_pt - o.min_pt;
    }
  }

 private:
  std::string dir_;
  std::vector<std::uint32_t> labels_;
  const urban_detection::CloudXYZIRT* cloud_ = nullptr;
};

void usage() {
  std::fprintf(
      stderr,
      "usage: urban_detection_eval (--kitti-object DIR | --semantic-kitti DIR |\n"
      "                             --sim GTFILE --pcap PCAP [--calibration FILE]\n"
      "                             [--cut-angle DEG])\n"
      "         [--detector hierarchical|kdtree|both] [--config FILE]... [--json FILE]\n"
      "         [--max-frames N] [--min-points N] [--details]\n"
      "         [--features CSV] [--classifier MODEL|off]\n"
      "         [--detections DIR]\n"
      "  --sim GTFILE    ground-truth file of urban_detection_simulate (--gt), with the pcap it\n"
      "                  wrote (--pcap); --calibration is the one the drive was simulated with\n"
      "                  (default: nominal HDL-64E S2), --cut-angle the revolution cut [deg]\n"
      "  --config FILE   a stage's YAML file (config/*.yaml; repeatable) (auto-detected by its\n"
      "                  keys), or a combined file with `segmentation:` / `detection:` maps;\n"
      "                  later files override earlier ones. Without it the in-class defaults\n"
      "                  (mirrored by config/*.yaml) are used.\n"
      "  --features CSV  write the object classifier's features of every detection (before the\n"
      "                  classifier) with its verdict and content\n"
      "  --classifier MODEL|off  the object classifier after the detector (default: classifier/\n"
      "                  of the config, e.g. config/classification.yaml's shipped model; else "
      "off)\n"
      "  --detections DIR  score another system's output instead of this package's detectors:\n"
      "                  per frame a file of one uint32 per input point, the point's instance\n"
      "                  (0 = none), at DIR/<frame>.label (SemanticKITTI: DIR/SEQ/NNNNNN.label\n"
      "                  or DIR/sequences/SEQ/predictions/NNNNNN.label; KITTI object:\n"
      "                  DIR/NNNNNN.label; simulated drive: DIR/revN.label)\n"
      "  --min-points N  objects and detections with fewer than N points count only when\n"
      "                  they match each other (SemanticKITTI's panoptic rule; default 30);\n"
      "                  the all-objects figure (N = 1) is printed beside it\n"
      "  --details       print every missed object and false detection with its cause\n"
      "  --png DIR       write a top view per frame (first detector): ground truth left,\n"
      "                  detections right; yellow boxes missed objects, red false detections\n"
      "  --png-view CX,CY,HALF_M   the square shown [m] (default 0,0,30)\n"
      "  --tracking      with --sim, --semantic-kitti or --kitti-tracking: the tracker after\n"
      "                  the pipeline, scored with CLEAR-MOT\n"
      "  --tracker-config FILE  the tracker's parameters (config/object_tracker.yaml's\n"
      "                  tracker: map; default: the in-class defaults it mirrors)\n"
      "  --kitti-tracking DIR  the same on the KITTI tracking layout (velodyne/<seq>/, label_02/,\n"
      "                  calib/); rules in src/tools/tracking_eval.h, docs/tracking.md\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string kitti_dir, skitti_dir, sim_gt, sim_pcap, calibration_path, json_path,
      detector_arg = "hierarchical";
  double cut_angle_deg = 0.0;
  std::vector<std::string> configs;
  long max_frames = -1;
  long min_points = 30;
  bool details = false;
  std::string png_dir, features_path, classifier_arg, detections_dir;
  PngView png_view;
  bool tracking = false;
  std::string kitti_tracking_dir, tracker_config;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const urban_detection::tools::OptionArgs arg{argc, argv, &i};
    if (a == "--kitti-object")
      kitti_dir = arg.value("--kitti-object");
    else if (a == "--semantic-kitti")
      skitti_dir = arg.value("--semantic-kitti");
    else if (a == "--sim")
      sim_gt = arg.value("--sim");
    else if (a == "--pcap")
      sim_pcap = arg.value("--pcap");
    else if (a == "--calibration")
      calibration_path = arg.value("--calibration");
    else if (a == "--cut-angle") {
      const std::string v = arg.value("--cut-angle");
      char* end = nullptr;
      cut_angle_deg = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(cut_angle_deg)) {
        std::fprintf(stderr, "error: --cut-angle needs a number of degrees, got '%s'\n", v.c_str());
        return 2;
      }
    } else if (a == "--detector")
      detector_arg = arg.value("--detector");
    else if (a == "--config")
      configs.push_back(arg.value("--config"));
    else if (a == "--json")
      json_path = arg.value("--json");
    else if (a == "--max-frames")
      max_frames = arg.count("--max-frames");
    else if (a == "--min-points")
      min_points = arg.count("--min-points");
    else if (a == "--details")
      details = true;
    else if (a == "--features")
      features_path = arg.value("--features");
    else if (a == "--classifier")
      classifier_arg = arg.value("--classifier");
    else if (a == "--detections")
      detections_dir = arg.value("--detections");
    else if (a == "--png")
      png_dir = arg.value("--png");
    else if (a == "--tracking")
      tracking = true;
    else if (a == "--kitti-tracking")
      kitti_tracking_dir = arg.value("--kitti-tracking");
    else if (a == "--tracker-config")
      tracker_config = arg.value("--tracker-config");
    else if (a == "--png-view") {
      const std::string v = arg.value("--png-view");
      if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &png_view.cx, &png_view.cy, &png_view.half_m) !=
              3 ||
          !(png_view.half_m > 0.0 && png_view.half_m <= 100.0)) {
        std::fprintf(stderr, "error: --png-view needs CX,CY,HALF_M (metres), got '%s'\n",
                     v.c_str());
        return 2;
      }
      png_view.px_per_m = std::min(40.0, 600.0 / png_view.half_m);
    } else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "error: unknown argument '%s'\n", a.c_str());
      usage();
      return 2;
    }
  }
  if ((!kitti_dir.empty() + !skitti_dir.empty() + !sim_gt.empty() + !kitti_tracking_dir.empty()) !=
          1 ||
      (tracking && !kitti_dir.empty())) {
    std::fprintf(stderr, "error: give exactly one dataset\n");
    usage();
    return 2;
  }
  if (sim_gt.empty() != sim_pcap.empty()) {
    std::fprintf(stderr, "error: --sim GTFILE and --pcap PCAP go together\n");
    usage();
    return 2;
  }
  if (sim_gt.empty() && (!calibration_path.empty() || cut_angle_deg != 0.0)) {
    std::fprintf(stderr, "error: --calibration and --cut-angle apply to --sim only\n");
    return 2;
  }

  // Parameters: in-class defaults, then each --config file in order.
  core::PipelineParams params;
  if (!urban_detection::tools::loadConfigs(configs, &params)) return 2;
  std::FILE* features_out = nullptr;
  core::ObjectFeatureParams feature_params;
  feature_params.sensor_height_m = params.segmentation.sensor_height_m;
  core::ObjectFeatureExtractor feature_extractor(feature_params);
  std::vector<core::ObjectFeatureVector> feature_rows;
  if (!features_path.empty()) {
    features_out = std::fopen(features_path.c_str(), "w");
    if (!features_out) {
      std::fprintf(stderr, "error: cannot write %s\n", features_path.c_str());
      return 1;
    }
    std::fprintf(features_out, "dataset,frame,detector,verdict,content");
    for (int k = 0; k < core::kNumObjectFeatures; ++k) {
      std::fprintf(features_out, ",%s", core::featureName(k));
    }
    std::fprintf(features_out, "\n");
  }

  // The classifier: the config's, replaced or switched off by --classifier.
  if (classifier_arg == "off") {
    params.classifier.enabled = false;
  } else if (!classifier_arg.empty()) {
    params.classifier.enabled = true;
    params.classifier.model_path = classifier_arg;
  }
  if (!detections_dir.empty() && params.classifier.enabled) {
    if (!classifier_arg.empty()) {
      std::fprintf(stderr, "error: --classifier does not apply to --detections\n");
      return 2;
    }
    params.classifier.enabled = false;
  }
  const bool classifier = params.classifier.enabled;

  // One pipeline per detector (the first one's segmentation serves all).
  std::vector<std::unique_ptr<core::Pipeline>> pipelines;
  ExternalDetections* external = nullptr;
  try {
    auto add = [&](std::unique_ptr<core::ObjectDetector> detector) {
      params.detector = detector->name();
      pipelines.emplace_back(new core::Pipeline(params, std::move(detector)));
    };
    if (!detections_dir.empty()) {
      if (!fs::is_directory(detections_dir)) {
        std::fprintf(stderr, "error: --detections %s is not a directory\n", detections_dir.c_str());
        return 1;
      }
      external = new ExternalDetections(detections_dir);
      add(std::unique_ptr<core::ObjectDetector>(external));
    } else if (detector_arg == "hierarchical" || detector_arg == "both") {
      add(std::make_unique<core::HierarchicalGridDetector>(params.hierarchical_grid));
    }
    if (detector_arg == "kdtree" || detector_arg == "both") {
      add(std::make_unique<core::KdTreeDetector>(params.kdtree));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (pipelines.empty()) {
    std::fprintf(stderr, "error: --detector must be hierarchical, kdtree or both\n");
    return 2;
  }
  if (tracking || !kitti_tracking_dir.empty()) {
    urban_detection::tools::TrackingPipeline tp;
    tp.params = pipelines[0]->params();
    tp.min_gt_points = static_cast<std::size_t>(min_points);
    if (max_frames >= 0) tp.max_frames = static_cast<std::size_t>(max_frames);
    std::string tracker_error;
    if (!tracker_config.empty() &&
        !core::loadTrackerParamsYaml(tracker_config, &tp.params.tracker, &tracker_error)) {
      std::fprintf(stderr, "error: %s\n", tracker_error.c_str());
      return 2;
    }
    if (!kitti_tracking_dir.empty()) {
      return urban_detection::tools::runKittiTracking(tp, kitti_tracking_dir, json_path);
    }
    if (!skitti_dir.empty()) {
      return urban_detection::tools::runSemanticKittiTracking(tp, skitti_dir, json_path);
    }
    try {
      return urban_detection::tools::runSimTracking(
          tp, sim_gt, sim_pcap, core::loadCalibration(calibration_path), cut_angle_deg, json_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
  }

  std::unique_ptr<Dataset> dataset;
  std::string dataset_path;
  if (!kitti_dir.empty()) {
    core::KittiGroundTruthParams p;
    p.min_points = 1;  // the evaluator applies --min-points (small objects count when matched)
    dataset.reset(new KittiObjectDataset(kitti_dir, p));
    dataset_path = kitti_dir;
  } else if (!skitti_dir.empty()) {
    core::SemanticKittiGroundTruthParams p;
    p.min_points = 1;  // the evaluator applies --min-points (small objects count when matched)
    dataset.reset(new SemanticKittiDataset(skitti_dir, p));
    dataset_path = skitti_dir;
  } else {
    core::SimulatedGroundTruthParams p;
    p.min_points = 1;  // the evaluator applies --min-points (small objects count when matched)
    try {
      const core::Calibration cal = core::loadCalibration(calibration_path);
      dataset.reset(new SimulatedDriveDataset(sim_gt, sim_pcap, cal, cut_angle_deg, p));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
    dataset_path = sim_pcap;
  }
  const std::size_t max_frames_n =
      max_frames >= 0 ? static_cast<std::size_t>(max_frames) : static_cast<std::size_t>(-1);

  if (min_points < 1) {
    std::fprintf(stderr, "error: --min-points must be at least 1\n");
    return 2;
  }
  core::EvaluationParams eval_params;
  eval_params.min_points = static_cast<std::size_t>(min_points);
  core::EvaluationParams all_objects = eval_params;
  all_objects.min_points = 1;
  // Per detector: the score under --min-points, the all-objects score (N = 1), and both of
  // the detector's own output before the classifier; where recall goes, before and after.
  std::vector<core::DetectionEvaluator> evaluators(pipelines.size(),
                                                   core::DetectionEvaluator(eval_params));
  std::vector<core::DetectionEvaluator> evaluators_all(pipelines.size(),
                                                       core::DetectionEvaluator(all_objects));
  std::vector<core::DetectionEvaluator> before_classifier(pipelines.size(),
                                                          core::DetectionEvaluator(eval_params));
  std::vector<core::DetectionEvaluator> before_classifier_all(
      pipelines.size(), core::DetectionEvaluator(all_objects));
  std::vector<core::RecallBreakdown> breakdown(pipelines.size()),
      breakdown_before(pipelines.size());
  std::vector<float> gt_range;
  std::vector<Diagnostics> diags(pipelines.size());
  std::vector<std::map<std::string, std::size_t>> classified_out(pipelines.size());
  // Per detector: scores per sequence (SemanticKITTI) and, of the matched detections, the
  // class given against the ground truth's ("vehicle->vehicle", ...).
  std::vector<std::map<std::string, core::DetectionScore>> by_group(pipelines.size());
  std::vector<std::map<std::string, std::size_t>> class_pairs(pipelines.size());
  std::map<std::string, std::size_t> fg_composition;  // foreground points by dataset class
  std::unique_ptr<urban_detection::tools::KittiBoxQuality> box_quality;  // first detector's
  if (!kitti_dir.empty())
    box_quality.reset(new urban_detection::tools::KittiBoxQuality(kitti_dir, params.box_fitting));
  std::ostringstream rows;
  bool first_row = true;
  std::size_t failed = 0, frames = 0;
  Frame f;
  core::FrameMatch match;
  if (details) std::printf("per-object details (missed GT objects, false detections):\n");
  std::size_t trained_on = 0;  // scored scans of sequences the classifier was trained on
  while (frames < max_frames_n) {
    std::string err;
    const Dataset::Status status = dataset->next(&f, &err);
    if (status == Dataset::Status::kEnd) break;
    ++frames;
    if (status == Dataset::Status::kSkipped) {
      std::fprintf(stderr, "warning: skipping frame %zu: %s\n", frames - 1, err.c_str());
      ++failed;
      continue;
    }
    if (external && !external->load(f, &err)) {
      std::fprintf(stderr, "warning: skipping frame %s: %s\n", f.id.c_str(), err.c_str());
      ++failed;
      continue;
    }
    if (classifier && !skitti_dir.empty()) {  // a scan of a sequence the model learned from?
      const auto& seqs = pipelines[0]->classifier().model().trainingGroups();
      trained_on +=
          std::find(seqs.begin(), seqs.end(), f.id.substr(0, f.id.find('/'))) != seqs.end();
    }
    gt_range = core::gtObjectRanges(f.gt, f.cloud);
    // The detector alone (pipeline k): scored before the classifier changes the objects.
    auto detectorAlone = [&](std::size_t k, const urban_detection::LabeledCloud& fg,
                             const std::vector<core::DetectedObject>& objects) {
      before_classifier[k].evaluate(f.gt, objects, &match);
      breakdown_before[k].addFrame(f.gt, match, objects, gt_range, eval_params.min_points);
      before_classifier_all[k].evaluate(f.gt, objects, nullptr);
      if (!features_out) return;
      feature_extractor.computeAll(fg, objects, &feature_rows);
      for (std::size_t d = 0; d < objects.size(); ++d) {
        std::fprintf(features_out, "%s,%s,%s,%s,%s", dataset->name().c_str(), f.id.c_str(),
                     pipelines[k]->detector().name().c_str(), core::toString(match.verdict[d]),
                     detectionContent(f, *dataset, objects[d]).c_str());
        for (const float v : feature_rows[d]) std::fprintf(features_out, ",%.6g", v);
        std::fprintf(features_out, "\n");
      }
    };
    // The first pipeline runs the whole chain; the others take its foreground.
    const core::PipelineResult& first = pipelines[0]->process(
        f.cloud,
        [&](const urban_detection::LabeledCloud& fg,
            const std::vector<core::DetectedObject>& objects) { detectorAlone(0, fg, objects); });
    const std::vector<core::SegmentClass>& seg = first.labels;
    const urban_detection::LabeledCloud& foreground = first.foreground;
    // What the foreground is made of (dataset classes): shows walls or vegetation leaking in.
    for (const auto& p : foreground) {
      if (p.index >= f.point_class.size()) continue;
      const std::int32_t g = f.gt.object_of_point[p.index];
      ++fg_composition[g >= 0 ? "gt_object:" + f.gt.objects[g].label
                              : dataset->className(f.point_class[p.index])];
    }
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      const core::PipelineResult& r =
          k == 0 ? first
                 : pipelines[k]->detect(foreground,
                                        [&](const urban_detection::LabeledCloud& fg,
                                            const std::vector<core::DetectedObject>& objects) {
                                          detectorAlone(k, fg, objects);
                                        });
      const std::vector<core::DetectedObject>& objects = r.objects;
      const std::vector<core::DetectedObject>& rejected = r.rejected;
      for (const auto& o : rejected) ++classified_out[k][detectionContent(f, *dataset, o)];
      evaluators_all[k].evaluate(f.gt, objects, nullptr);
      evaluators[k].evaluate(f.gt, objects, &match);
      breakdown[k].addFrame(f.gt, match, objects, gt_range, eval_params.min_points);
      if (box_quality && k == 0) box_quality->addFrame(f.id, f.cloud, f.gt, objects, match);
      by_group[k][urban_detection::tools::frameGroup(f.id, dataset->name())] += match.score;
      for (std::size_t d = 0; d < objects.size() && classifier; ++d) {
        if (match.verdict[d] != core::DetectionVerdict::kTrue) continue;
        const core::ObjectCategory truth =
            core::categoryOfClassName(f.gt.objects[match.matched_gt[d]].label);
        ++class_pairs[k][std::string(core::toString(truth)) + "->" +
                         core::toString(objects[d].category)];
      }
      diagnose(f, *dataset, seg, objects, match, rejected, pipelines[k]->detector().name(),
               &diags[k], details ? stdout : nullptr);
      if (!png_dir.empty() && k == 0) {
        std::string id = f.id;
        std::replace(id.begin(), id.end(), '/', '_');
        writeFramePng(png_dir + "/" + dataset->name() + "_" + id + ".png", f, foreground, objects,
                      match, png_view);
      }
      rows << (first_row ? "" : ",\n") << "    {\"frame\": \"" << jsonEscape(f.id)
           << "\", \"detector\": \"" << pipelines[k]->detector().name() << "\", "
           << scoreJson(match.score) << "}";
      first_row = false;
    }
  }

  if (features_out) std::fclose(features_out);
  if (frames == 0) {
    std::error_code ec;
    std::fprintf(stderr, "error: %s %s\n", dataset_path.c_str(),
                 fs::exists(dataset_path, ec) ? "holds no frames" : "not found");
    return 1;
  }
  std::printf(
      "\nsmall objects (< %ld points) count only when matched (--min-points %ld); N = 1: "
      "every object counts\n",
      min_points, min_points);
  std::printf("%-15s %-18s %-11s %6s %5s %5s %5s %5s %9s %7s %7s\n", "dataset", "detector",
              "classifier", "frames", "NO", "MO", "FO", "ign", "precision", "recall", "F-rate");
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    const std::pair<const char*, const core::DetectionEvaluator*> rows_k[] = {
        {classifier ? "on" : "off", &evaluators[k]},
        {classifier ? "on, N=1" : "off, N=1", &evaluators_all[k]},
        {"off", &before_classifier[k]},
        {"off, N=1", &before_classifier_all[k]}};
    for (int r = 0; r < (classifier ? 4 : 2); ++r) {
      const core::DetectionScore& t = rows_k[r].second->total();
      std::printf("%-15s %-18s %-11s %6zu %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
                  dataset->name().c_str(), pipelines[k]->detector().name().c_str(), rows_k[r].first,
                  frames - failed, t.no, t.mo, t.fo, t.ignored, t.precision(), t.recall(),
                  t.fRate());
    }
  }
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    std::printf("\n%s, classifier %s:\n%s", pipelines[k]->detector().name().c_str(),
                classifier ? "on" : "off", breakdown[k].table("  ").c_str());
    if (classifier) {
      std::printf("%s, classifier off (the detector alone):\n%s",
                  pipelines[k]->detector().name().c_str(), breakdown_before[k].table("  ").c_str());
    }
  }
  std::printf("\n");
  for (std::size_t k = 0; k < pipelines.size() && by_group[k].size() > 1; ++k) {
    for (const auto& g : by_group[k]) {
      const core::DetectionScore& t = g.second;
      std::printf("%-15s %-18s %6s %5zu %5zu %5zu %5zu %9.3f %7.3f %7.3f\n",
                  (dataset->name() + ":" + g.first).c_str(),
                  pipelines[k]->detector().name().c_str(), "", t.no, t.mo, t.fo, t.ignored,
                  t.precision(), t.recall(), t.fRate());
    }
  }
  if (box_quality) box_quality->print();
  std::printf("classifier: %s\n",
              classifier ? params.classifier.model_path.c_str() : "off (objects unclassified)");
  if (trained_on > 0) {
    std::string seqs;
    for (const std::string& g : pipelines[0]->classifier().model().trainingGroups())
      seqs += " " + g;
    std::printf(
        "note: %zu of the %zu scans scored are of sequences the classifier was trained on "
        "(%s): the classifier-on figures are optimistic there; held-out figures: "
        "urban_detection_train_classifier's leave-one-sequence-out run (scripts/run eval)\n",
        trained_on, frames - failed, seqs.c_str() + 1);
  }
  std::printf("foreground points by class: %s\n", countsJson(fg_composition).c_str());
  for (std::size_t k = 0; k < pipelines.size(); ++k) {
    if (classifier) {
      std::printf(
          "%s: classifier rejected by content %s; matched objects' class "
          "(truth->given) %s\n",
          pipelines[k]->detector().name().c_str(), countsJson(classified_out[k]).c_str(),
          countsJson(class_pairs[k]).c_str());
    }
    std::printf(
        "%s: missed by cause %s; false by content %s\n", pipelines[k]->detector().name().c_str(),
        countsJson(diags[k].missed_by_cause).c_str(), countsJson(diags[k].false_by_class).c_str());
    if (details) {
      std::printf("%s: false parts of GT objects by kind %s\n",
                  pipelines[k]->detector().name().c_str(),
                  countsJson(diags[k].false_fragments).c_str());
    }
  }

  if (!json_path.empty()) {
    std::ofstream out(json_path);
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
    out << "{\n  \"dataset\": \"" << dataset->name() << "\",\n  \"path\": \""
        << jsonEscape(dataset_path) << "\",\n  \"frames_evaluated\": " << frames - failed
        << ",\n  \"frames_failed\": " << failed
        << ",\n  \"min_iou\": " << jsonNumber(evaluators[0].params().min_iou)
        << ",\n  \"min_points\": " << min_points << ",\n  \"classifier\": "
        << (classifier ? "\"" + jsonEscape(params.classifier.model_path) + "\"" : "null")
        << ",\n  \"configs\": [";
    for (std::size_t c = 0; c < configs.size(); ++c) {
      out << (c ? ", " : "") << "\"" << jsonEscape(configs[c]) << "\"";
    }
    out << "],\n  \"detectors\": [";
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      out << (k ? ", " : "") << "\"" << pipelines[k]->detector().name() << "\"";
    }
    out << "],\n  \"frames\": [\n" << rows.str() << "\n  ],\n";
    out << "  \"overall\": {" << scoreJson(evaluators[0].total()) << "},\n";
    out << "  \"by_detector\": {";
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      out << (k ? ",\n" : "\n") << "    \"" << pipelines[k]->detector().name() << "\": {"
          << scoreJson(evaluators[k].total()) << ", \"all_objects\": {"
          << scoreJson(evaluators_all[k].total()) << "}"
          << ", \"classifier_off\": {" << scoreJson(before_classifier[k].total()) << "}"
          << ", \"classifier_off_all_objects\": {" << scoreJson(before_classifier_all[k].total())
          << "}, \"breakdown\": " << breakdown[k].json()
          << ", \"breakdown_classifier_off\": " << breakdown_before[k].json()
          << ", \"missed_by_cause\": " << countsJson(diags[k].missed_by_cause)
          << ", \"false_by_content\": " << countsJson(diags[k].false_by_class)
          << ", \"classifier_rejected_by_content\": " << countsJson(classified_out[k])
          << ", \"class_truth_to_given\": " << countsJson(class_pairs[k]) << ", \"by_sequence\": {";
      bool first_group = true;
      for (const auto& g : by_group[k]) {
        out << (first_group ? "" : ", ") << "\"" << jsonEscape(g.first) << "\": {"
            << scoreJson(g.second) << "}";
        first_group = false;
      }
      out << "}}";
    }
    out << "\n  },\n  \"foreground_points_by_class\": " << countsJson(fg_composition);
    if (box_quality) out << ",\n  \"box_quality\": " << box_quality->json();
    out << "\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: writing %s failed\n", json_path.c_str());
      return 1;
    }
  }
  return failed == frames ? 1 : 0;
}
