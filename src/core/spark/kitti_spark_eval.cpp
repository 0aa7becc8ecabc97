#include "urban_detection/core/spark/kitti_spark_eval.h"

#include <cmath>
#include <opencv2/imgcodecs.hpp>

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

}  // namespace core
}  // namespace urban_detection
