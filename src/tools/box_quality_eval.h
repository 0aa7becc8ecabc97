// Box quality of urban_detection_eval on KITTI object frames (--kitti-object): each labelled
// vehicle (Car, Van, Truck), Pedestrian and Cyclist that the detection scoring matched to a
// detection (point sets, IoU >= 0.5, evaluation.h) is compared with the detection's box in
// the bird's-eye view (core/evaluation/box_quality.h): centre error, heading error modulo
// 180 deg, bird's-eye IoU; per class and range bin, printed and in the JSON (`box_quality`).
// Labelled objects the ground truth ignores (fewer than --min-points points) are left out.
// Beside it, the box fitting alone: the same BoxFitter on each labelled object's own points
// (the points in its box, without the ground band) with its labelled class, so a missed or
// misclassified detection does not hide how well the boxes are fitted. UD_BOX_DEBUG=1 prints
// each labelled object's box and its fitted box (the second table) on stderr.
// Not a tool itself (only src/tools/*.cpp are executables).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/evaluation/box_quality.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"

#include "tool_common.h"

namespace urban_detection {
namespace tools {

namespace core = urban_detection::core;

class KittiBoxQuality {
 public:
  KittiBoxQuality(const std::string& dir, const core::BoxFittingParams& params)
      : dir_(dir), fitter_(params) {}

  // One frame: `gt` as built by KittiObjectDataset (object id = label line number), the
  // detections and their match.
  void addFrame(const std::string& frame_id, const CloudXYZIRT& cloud, const core::EvalFrame& gt,
                const std::vector<core::DetectedObject>& objects, const core::FrameMatch& match) {
    std::vector<core::KittiLabel> labels;
    core::KittiCalibration calib;
    std::string error;
    if (!core::readKittiLabels(dir_ + "/label_2/" + frame_id + ".txt", &labels, &error) ||
        !core::readKittiCalibration(dir_ + "/calib/" + frame_id + ".txt", &calib, &error)) {
      return;  // the dataset reader reported the frame already
    }
    std::vector<std::vector<Eigen::Vector2f>> points(gt.objects.size());
    for (std::size_t i = 0; i < cloud.size() && i < gt.object_of_point.size(); ++i) {
      const std::int32_t g = gt.object_of_point[i];
      if (g < 0 || (i < gt.role.size() && gt.role[i] == core::PointRole::kExcluded)) continue;
      points[static_cast<std::size_t>(g)].emplace_back(cloud[i].x, cloud[i].y);
    }
    for (std::size_t g = 0; g < gt.objects.size(); ++g) {
      const core::EvalObject& o = gt.objects[g];
      if (o.ignored || o.id == 0 || o.id > labels.size()) continue;
      const core::KittiLabel& l = labels[o.id - 1];
      const core::ObjectCategory c = core::categoryOfClassName(l.type);
      if (c != core::ObjectCategory::kVehicle && c != core::ObjectCategory::kPedestrian &&
          c != core::ObjectCategory::kCyclist) {
        continue;
      }
      const auto corners = core::kittiBoxCornersVelo(l, calib);
      core::GroundBox box;
      const Eigen::Vector3d front = 0.5 * (corners[0] + corners[1]);
      const Eigen::Vector3d back = 0.5 * (corners[2] + corners[3]);
      box.center = (0.25 * (corners[0] + corners[1] + corners[2] + corners[3])).head<2>();
      box.yaw_rad = std::atan2(front.y() - back.y(), front.x() - back.x());
      box.length_m = l.length_m;
      box.width_m = l.width_m;
      const int d = g < match.matched_detection.size() ? match.matched_detection[g] : -1;
      core::GroundBox det;
      if (d >= 0) det = core::groundBoxOf(objects[static_cast<std::size_t>(d)]);
      samples_.push_back(core::scoreBox(c, box, d >= 0 ? &det : nullptr));
      if (points[g].empty()) {
        own_.push_back(core::scoreBox(c, box, nullptr));
        continue;
      }
      const core::BevBox fitted = fitter_.fitPoints(points[g].data(), points[g].size(), c);
      core::GroundBox own;
      own.center = fitted.center.cast<double>();
      own.length_m = fitted.size.x();
      own.width_m = fitted.size.y();
      own.yaw_rad = fitted.yaw_rad;
      own_.push_back(core::scoreBox(c, box, &own));
      if (std::getenv("UD_BOX_DEBUG")) {
        const core::BoxQualitySample& q = own_.back();
        std::fprintf(stderr,
                     "%s %s %zu pts at (%.1f, %.1f) gt %.2fx%.2f yaw %.1f; fit (%.1f, %.1f) "
                     "%.2fx%.2f yaw %.1f: centre %.2f heading %.1f IoU %.2f\n",
                     frame_id.c_str(), l.type.c_str(), points[g].size(), box.center.x(),
                     box.center.y(), box.length_m, box.width_m, box.yaw_rad * 57.2958,
                     own.center.x(), own.center.y(), own.length_m, own.width_m,
                     own.yaw_rad * 57.2958, q.center_error_m, q.heading_error_deg, q.iou);
      }
    }
  }

  // Tables on stdout.
  void print() const {
    printTable("matched detections (the pipeline)", samples_);
    printTable("box fitting alone, on each labelled object's own points", own_);
  }

  // The JSON object of `box_quality`.
  std::string json() const {
    return "{\"iou_threshold\": 0.5, \"detections\": " + jsonRows(samples_) +
           ", \"labelled_points\": " + jsonRows(own_) + "}";
  }

 private:
  static void printTable(const char* what, const std::vector<core::BoxQualitySample>& samples) {
    std::printf(
        "\nbox quality (bird's-eye view) vs KITTI 3-D boxes, %s:\n"
        "%-11s %-9s %8s %8s %10s %12s %9s %10s\n",
        what, "class", "range", "labelled", "matched", "centre_m", "heading_deg", "IoU_med",
        "IoU>=0.5");
    for (const Row& r : rows()) {
      const core::BoxQualitySummary s = core::summarize(samples, r.category, r.min_m, r.max_m, 0.5);
      if (s.labelled == 0) continue;
      std::printf("%-11s %-9s %8zu %8zu %10.3f %12.2f %9.3f %10.3f\n", core::toString(r.category),
                  r.name.c_str(), s.labelled, s.matched, s.median_center_error_m,
                  s.median_heading_error_deg, s.median_iou, s.share_iou_at_least);
    }
  }

  static std::string jsonRows(const std::vector<core::BoxQualitySample>& samples) {
    std::ostringstream o;
    o << "[";
    bool first = true;
    for (const Row& r : rows()) {
      const core::BoxQualitySummary s = core::summarize(samples, r.category, r.min_m, r.max_m, 0.5);
      if (s.labelled == 0) continue;
      o << (first ? "" : ", ") << "{\"class\": \"" << core::toString(r.category)
        << "\", \"range\": \"" << r.name << "\", \"labelled\": " << s.labelled
        << ", \"matched\": " << s.matched
        << ", \"median_center_error_m\": " << jsonNumber(s.median_center_error_m)
        << ", \"median_heading_error_deg\": " << jsonNumber(s.median_heading_error_deg)
        << ", \"median_bev_iou\": " << jsonNumber(s.median_iou)
        << ", \"share_bev_iou_at_least_0_5\": " << jsonNumber(s.share_iou_at_least) << "}";
      first = false;
    }
    o << "]";
    return o.str();
  }

  struct Row {
    core::ObjectCategory category;
    std::string name;
    double min_m, max_m;
  };
  static std::vector<Row> rows() {
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<Row> out;
    for (const core::ObjectCategory c :
         {core::ObjectCategory::kVehicle, core::ObjectCategory::kPedestrian,
          core::ObjectCategory::kCyclist}) {
      out.push_back({c, "0-20m", 0.0, 20.0});
      out.push_back({c, "20-40m", 20.0, 40.0});
      out.push_back({c, "40m+", 40.0, inf});
      out.push_back({c, "0-40m", 0.0, 40.0});
      out.push_back({c, "all", 0.0, inf});
    }
    return out;
  }
  std::string dir_;
  core::BoxFitter fitter_;
  std::vector<core::BoxQualitySample> samples_, own_;  // detections, labelled points
};

}  // namespace tools
}  // namespace urban_detection
