#include "urban_detection/core/spark/kitti_spark_eval.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "urban_detection/core/evaluation/report.h"

#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace core {

bool loadKittiSparkFrame(const std::string& dir, const std::string& id, bool with_image,
                         KittiSparkFrame* f, std::string* error) {
  f->id = id;
  const std::string png = dir + "/image_2/" + id + ".png";
  if (!readKittiCalibration(dir + "/calib/" + id + ".txt", &f->calib, error) ||
      !readKittiLabels(dir + "/label_2/" + id + ".txt", &f->labels, error) ||
      !readKittiBin(dir + "/velodyne/" + id + ".bin", &f->cloud, error))
    return false;
  if (with_image) {
    f->image = cv::imread(png, cv::IMREAD_COLOR);
    if (f->image.empty()) {
      *error = "cannot read " + png;
      return false;
    }
    f->camera.width_px = f->image.cols;
    f->camera.height_px = f->image.rows;
  } else if (!readPngSize(png, &f->camera.width_px, &f->camera.height_px)) {
    *error = "cannot read " + png;
    return false;
  }
  f->camera.projection = f->calib.p2;
  f->camera_from_velo = Eigen::Isometry3d::Identity();
  f->camera_from_velo.linear() = f->calib.r0_rect * f->calib.tr_velo_to_cam.leftCols<3>();
  f->camera_from_velo.translation() = f->calib.r0_rect * f->calib.tr_velo_to_cam.col(3);
  return true;
}

ObjectCategory kittiTypeCategory(const std::string& type) {
  if (type == "Car" || type == "Van" || type == "Truck") return ObjectCategory::kVehicle;
  if (type == "Pedestrian" || type == "Person_sitting") return ObjectCategory::kPedestrian;
  if (type == "Cyclist") return ObjectCategory::kCyclist;
  return ObjectCategory::kUnknown;
}

std::vector<std::size_t> kittiBoxPoints(const KittiSparkFrame& f, const KittiLabel& l,
                                        double ground_band_m) {
  std::vector<std::size_t> in;
  if (l.type == "DontCare") return in;
  for (std::size_t i = 0; i < f.cloud.size(); ++i) {
    const auto& p = f.cloud[i];
    if (!isFinitePoint(p)) continue;
    const Eigen::Vector3d b = kittiBoxLocal(l, f.calib.veloToRect(Eigen::Vector3d(p.x, p.y, p.z)));
    if (std::fabs(b.x()) <= 0.5 * l.length_m && b.y() >= ground_band_m && b.y() <= l.height_m &&
        std::fabs(b.z()) <= 0.5 * l.width_m)
      in.push_back(i);
  }
  return in;
}

void kittiLabelObjects(const KittiSparkFrame& f, LabeledCloud* points, double ground_band_m) {
  points->clear();
  for (std::size_t k = 0; k < f.labels.size(); ++k) {
    for (const std::size_t i : kittiBoxPoints(f, f.labels[k], ground_band_m)) {
      const auto& p = f.cloud[i];
      points->push_back(makeLabeledPoint(p.x, p.y, p.z, static_cast<std::uint32_t>(k + 1),
                                         static_cast<std::uint32_t>(i), p.intensity));
    }
  }
}

double kittiLabelRange(const KittiSparkFrame& f, const KittiLabel& l) {
  // The label's location is the bottom centre in rectified camera coordinates.
  const Eigen::Vector3d centre = l.location - Eigen::Vector3d(0.0, 0.5 * l.height_m, 0.0);
  const Eigen::Vector3d v = f.calib.rectToVelo(centre);
  return std::hypot(v.x(), v.y());
}

cv::Mat kittiBoxOracleMask(const KittiSparkFrame& f, const std::vector<std::string>& names) {
  std::vector<std::size_t> order(f.labels.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return f.labels[a].location.z() > f.labels[b].location.z();
  });
  cv::Mat mask(f.image.rows, f.image.cols, CV_8U, cv::Scalar(0));
  for (const std::size_t k : order) {
    const auto it = std::find(names.begin(), names.end(), f.labels[k].type);
    if (it == names.end()) continue;
    const auto& b = f.labels[k].bbox;
    mask(cv::Rect(cv::Point(static_cast<int>(b[0]), static_cast<int>(b[1])),
                  cv::Point(static_cast<int>(b[2]) + 1, static_cast<int>(b[3]) + 1)) &
         cv::Rect(0, 0, mask.cols, mask.rows))
        .setTo(static_cast<int>(it - names.begin()));
  }
  return mask;
}

std::vector<int> kittiPointOwners(const KittiSparkFrame& f) {
  std::vector<int> owner(f.cloud.size(), -1);
  for (std::size_t k = 0; k < f.labels.size(); ++k) {
    if (f.labels[k].type == "DontCare") continue;
    KittiLabel big = f.labels[k];
    big.length_m += 0.2;
    big.width_m += 0.2;
    big.height_m += 0.1;
    for (const std::size_t i : kittiBoxPoints(f, big, 0.0)) owner[i] = static_cast<int>(k);
  }
  return owner;
}

KittiDetectionTruth kittiDetectionTruth(const KittiSparkFrame& f, const std::vector<int>& owner,
                                        const DetectedObject& o) {
  KittiDetectionTruth t;
  int in_view = 0, in_dontcare = 0;
  std::map<int, int> hits;
  for (const std::uint32_t i : o.indices) {
    const auto& p = f.cloud[i];
    const Eigen::Vector3d pv(p.x, p.y, p.z);
    double u = 0, v = 0;
    if (!f.camera.project(f.camera_from_velo * pv, 0.5, &u, &v) || u < 0 || v < 0 ||
        u >= f.camera.width_px || v >= f.camera.height_px)
      continue;
    ++in_view;
    for (const auto& l : f.labels)
      if (l.type == "DontCare" && u >= l.bbox[0] && u <= l.bbox[2] && v >= l.bbox[1] &&
          v <= l.bbox[3]) {
        ++in_dontcare;
        break;
      }
    ++hits[owner[i]];
  }
  if (2 * in_view < static_cast<int>(o.indices.size())) return t;  // not in the camera view
  int best_hits = 0;
  for (const auto& [k, n] : hits)
    if (k >= 0 && n > best_hits) best_hits = n, t.label = k;
  t.is_true = t.label >= 0 && 2 * best_hits >= in_view;
  if (!t.is_true && 2 * in_dontcare > in_view) return t;  // DontCare region
  t.scored = true;
  if (t.is_true) t.truth = kittiTypeCategory(f.labels[static_cast<std::size_t>(t.label)].type);
  return t;
}

void SparkPrecisionCounts::add(ObjectCategory given, const KittiDetectionTruth& t) {
  if (given == ObjectCategory::kNonObject) {
    ++vetoed;
    vetoed_true += t.is_true;
    return;
  }
  ++kept;
  true_objects += t.is_true;
  class_correct += t.is_true && given == t.truth;
}

std::string SparkPrecisionCounts::json() const {
  std::ostringstream o;
  o << "{\"kept\": " << kept << ", \"true\": " << true_objects
    << ", \"class_correct\": " << class_correct << ", \"vetoed\": " << vetoed
    << ", \"vetoed_true\": " << vetoed_true
    << ", \"precision\": " << jsonNumber(kept ? static_cast<double>(true_objects) / kept : 0.0)
    << ", \"class_precision\": "
    << jsonNumber(kept ? static_cast<double>(class_correct) / kept : 0.0) << "}";
  return o.str();
}

}  // namespace core
}  // namespace urban_detection
