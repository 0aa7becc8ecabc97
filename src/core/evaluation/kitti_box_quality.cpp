#include "urban_detection/core/evaluation/kitti_box_quality.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/report.h"

namespace urban_detection {
namespace core {

namespace {

std::string jsonRows(const std::vector<BoxQualitySample>& samples) {
  std::ostringstream o;
  o << "[";
  bool first = true;
  for (const KittiBoxQuality::Row& r : KittiBoxQuality::rows()) {
    const BoxQualitySummary s = summarize(samples, r.category, r.min_m, r.max_m, 0.5);
    if (s.labelled == 0) continue;
    o << (first ? "" : ", ") << "{\"class\": \"" << toString(r.category) << "\", \"range\": \""
      << r.name << "\", \"labelled\": " << s.labelled << ", \"matched\": " << s.matched
      << ", \"median_center_error_m\": " << jsonNumber(s.median_center_error_m)
      << ", \"median_heading_error_deg\": " << jsonNumber(s.median_heading_error_deg)
      << ", \"median_bev_iou\": " << jsonNumber(s.median_iou)
      << ", \"share_bev_iou_at_least_0_5\": " << jsonNumber(s.share_iou_at_least) << "}";
    first = false;
  }
  o << "]";
  return o.str();
}

}  // namespace

void KittiBoxQuality::addFrame(const std::string& frame_id, const CloudXYZIRT& cloud,
                               const EvalFrame& gt, const std::vector<DetectedObject>& objects,
                               const FrameMatch& match) {
  std::vector<KittiLabel> labels;
  KittiCalibration calib;
  std::string error;
  if (!readKittiLabels(dir_ + "/label_2/" + frame_id + ".txt", &labels, &error) ||
      !readKittiCalibration(dir_ + "/calib/" + frame_id + ".txt", &calib, &error)) {
    return;  // the dataset reader reported the frame already
  }
  std::vector<std::vector<Eigen::Vector2f>> points(gt.objects.size());
  for (std::size_t i = 0; i < cloud.size() && i < gt.object_of_point.size(); ++i) {
    const std::int32_t g = gt.object_of_point[i];
    if (g < 0 || (i < gt.role.size() && gt.role[i] == PointRole::kExcluded)) continue;
    points[static_cast<std::size_t>(g)].emplace_back(cloud[i].x, cloud[i].y);
  }
  for (std::size_t g = 0; g < gt.objects.size(); ++g) {
    const EvalObject& o = gt.objects[g];
    if (o.ignored || o.id == 0 || o.id > labels.size()) continue;
    const KittiLabel& l = labels[o.id - 1];
    const ObjectCategory c = categoryOfClassName(l.type);
    if (c != ObjectCategory::kVehicle && c != ObjectCategory::kPedestrian &&
        c != ObjectCategory::kCyclist) {
      continue;
    }
    const auto corners = kittiBoxCornersVelo(l, calib);
    GroundBox box;
    const Eigen::Vector3d front = 0.5 * (corners[0] + corners[1]);
    const Eigen::Vector3d back = 0.5 * (corners[2] + corners[3]);
    box.center = (0.25 * (corners[0] + corners[1] + corners[2] + corners[3])).head<2>();
    box.yaw_rad = std::atan2(front.y() - back.y(), front.x() - back.x());
    box.length_m = l.length_m;
    box.width_m = l.width_m;
    const int d = g < match.matched_detection.size() ? match.matched_detection[g] : -1;
    GroundBox det;
    if (d >= 0) det = groundBoxOf(objects[static_cast<std::size_t>(d)]);
    samples_.push_back(scoreBox(c, box, d >= 0 ? &det : nullptr));
    if (points[g].empty()) {
      own_.push_back(scoreBox(c, box, nullptr));
      continue;
    }
    const BevBox fitted = fitter_.fitPoints(points[g].data(), points[g].size(), c);
    GroundBox own;
    own.center = fitted.center.cast<double>();
    own.length_m = fitted.size.x();
    own.width_m = fitted.size.y();
    own.yaw_rad = fitted.yaw_rad;
    own_.push_back(scoreBox(c, box, &own));
    if (std::getenv("UD_BOX_DEBUG")) {
      const BoxQualitySample& q = own_.back();
      std::fprintf(stderr,
                   "%s %s %zu pts at (%.1f, %.1f) gt %.2fx%.2f yaw %.1f; fit (%.1f, %.1f) "
                   "%.2fx%.2f yaw %.1f: centre %.2f heading %.1f IoU %.2f\n",
                   frame_id.c_str(), l.type.c_str(), points[g].size(), box.center.x(),
                   box.center.y(), box.length_m, box.width_m, box.yaw_rad * 57.2958, own.center.x(),
                   own.center.y(), own.length_m, own.width_m, own.yaw_rad * 57.2958,
                   q.center_error_m, q.heading_error_deg, q.iou);
    }
  }
}

std::vector<KittiBoxQuality::Row> KittiBoxQuality::rows() {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Row> out;
  for (const ObjectCategory c :
       {ObjectCategory::kVehicle, ObjectCategory::kPedestrian, ObjectCategory::kCyclist}) {
    out.push_back({c, "0-20m", 0.0, 20.0});
    out.push_back({c, "20-40m", 20.0, 40.0});
    out.push_back({c, "40m+", 40.0, inf});
    out.push_back({c, "0-40m", 0.0, 40.0});
    out.push_back({c, "all", 0.0, inf});
  }
  return out;
}

std::string KittiBoxQuality::tables() const {
  std::string out;
  const std::pair<const char*, const std::vector<BoxQualitySample>*> tables[] = {
      {"matched detections (the pipeline)", &samples_},
      {"box fitting alone, on each labelled object's own points", &own_}};
  for (const auto& t : tables) {
    appendf(&out,
            "\nbox quality (bird's-eye view) vs KITTI 3-D boxes, %s:\n"
            "%-11s %-9s %8s %8s %10s %12s %9s %10s\n",
            t.first, "class", "range", "labelled", "matched", "centre_m", "heading_deg", "IoU_med",
            "IoU>=0.5");
    for (const Row& r : rows()) {
      const BoxQualitySummary s = summarize(*t.second, r.category, r.min_m, r.max_m, 0.5);
      if (s.labelled == 0) continue;
      appendf(&out, "%-11s %-9s %8zu %8zu %10.3f %12.2f %9.3f %10.3f\n", toString(r.category),
              r.name.c_str(), s.labelled, s.matched, s.median_center_error_m,
              s.median_heading_error_deg, s.median_iou, s.share_iou_at_least);
    }
  }
  return out;
}

std::string KittiBoxQuality::json() const {
  return "{\"iou_threshold\": 0.5, \"detections\": " + jsonRows(samples_) +
         ", \"labelled_points\": " + jsonRows(own_) + "}";
}

}  // namespace core
}  // namespace urban_detection
