#include "urban_detection/core/tracking/kitti_tracking.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <Eigen/LU>

namespace urban_detection {
namespace core {

namespace {

// Reads exactly `n` finite numbers from `in`.
bool readNumbers(std::istringstream& in, double* out, int n) {
  for (int k = 0; k < n; ++k) {
    if (!(in >> out[k]) || !std::isfinite(out[k])) return false;
  }
  return true;
}

}  // namespace

bool parseKittiTrackingLine(const std::string& line, KittiTrackingLabel* label) {
  std::istringstream in(line);
  std::string frame, id;
  if (!(in >> frame >> id >> label->type)) return false;
  try {
    std::size_t used = 0;
    label->frame = std::stoi(frame, &used);
    if (used != frame.size() || label->frame < 0) return false;
    label->track_id = std::stoi(id, &used);
    if (used != id.size() || label->track_id < -1) return false;
  } catch (const std::exception&) {
    return false;
  }
  double v[14];
  if (!readNumbers(in, v, 14)) return false;
  label->truncated = v[0];
  label->occluded = static_cast<int>(v[1]);
  label->alpha = v[2];
  label->bbox = {v[3], v[4], v[5], v[6]};
  label->height_m = v[7];
  label->width_m = v[8];
  label->length_m = v[9];
  label->location = Eigen::Vector3d(v[10], v[11], v[12]);
  label->rotation_y = v[13];
  double score = 1.0;
  label->score = (in >> score) && std::isfinite(score) ? score : 1.0;
  return true;
}

bool readKittiTrackingLabels(const std::string& path,
                             std::map<int, std::vector<KittiTrackingLabel>>* by_frame,
                             std::string* error) {
  by_frame->clear();
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    KittiTrackingLabel label;
    if (!parseKittiTrackingLine(line, &label)) {
      *error = path + ":" + std::to_string(number) +
               ": not a KITTI tracking label (frame track_id type truncated occluded alpha "
               "bbox[4] h w l x y z rotation_y [score])";
      return false;
    }
    (*by_frame)[label.frame].push_back(label);
  }
  return true;
}

Eigen::Vector3d KittiTrackingCalibration::veloToRect(const Eigen::Vector3d& p) const {
  return r_rect * (tr_velo_cam.leftCols<3>() * p + tr_velo_cam.col(3));
}

Eigen::Vector3d KittiTrackingCalibration::rectToVelo(const Eigen::Vector3d& p_rect) const {
  const Eigen::Vector3d cam = r_rect.inverse() * p_rect;
  return tr_velo_cam.leftCols<3>().inverse() * (cam - tr_velo_cam.col(3));
}

bool KittiTrackingCalibration::project(const Eigen::Vector3d& p_velo, double* u, double* v) const {
  const Eigen::Vector3d r = veloToRect(p_velo);
  if (r.z() <= 0.1) return false;
  const Eigen::Vector3d h = p2.leftCols<3>() * r + p2.col(3);
  *u = h.x() / h.z();
  *v = h.y() / h.z();
  return std::isfinite(*u) && std::isfinite(*v);
}

bool readKittiTrackingCalibration(const std::string& path, KittiTrackingCalibration* calib,
                                  std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  bool have_p2 = false, have_rect = false, have_tr = false;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string key;
    if (!(s >> key)) continue;
    if (!key.empty() && key.back() == ':') key.pop_back();
    double v[12];
    if (key == "P2") {
      if (!readNumbers(s, v, 12)) break;
      for (int k = 0; k < 12; ++k) calib->p2(k / 4, k % 4) = v[k];
      have_p2 = true;
    } else if (key == "R_rect" || key == "R0_rect") {
      if (!readNumbers(s, v, 9)) break;
      for (int k = 0; k < 9; ++k) calib->r_rect(k / 3, k % 3) = v[k];
      have_rect = true;
    } else if (key == "Tr_velo_cam" || key == "Tr_velo_to_cam") {
      if (!readNumbers(s, v, 12)) break;
      for (int k = 0; k < 12; ++k) calib->tr_velo_cam(k / 4, k % 4) = v[k];
      have_tr = true;
    }
  }
  if (have_p2 && have_rect && have_tr &&
      std::fabs(calib->tr_velo_cam.leftCols<3>().determinant()) > 1e-6 &&
      std::fabs(calib->r_rect.determinant()) > 1e-6) {
    return true;
  }
  *error = path +
           ": needs P2, R_rect (or R0_rect) and Tr_velo_cam (or Tr_velo_to_cam) with "
           "12, 9 and 12 numbers";
  return false;
}

bool insideKittiTrackingBox(const KittiTrackingLabel& label, const KittiTrackingCalibration& calib,
                            const Eigen::Vector3d& p_velo, double margin_m) {
  const Eigen::Vector3d d = calib.veloToRect(p_velo) - label.location;
  // Box frame: x along the length (rotation_y about the camera's y axis, which points down).
  const double c = std::cos(label.rotation_y), s = std::sin(label.rotation_y);
  const double x = c * d.x() - s * d.z();
  const double z = s * d.x() + c * d.z();
  const double up = -d.y();
  return std::fabs(x) <= 0.5 * label.length_m + margin_m &&
         std::fabs(z) <= 0.5 * label.width_m + margin_m && up >= -margin_m &&
         up <= label.height_m + margin_m;
}

Eigen::Vector3d kittiTrackingBoxCenterVelo(const KittiTrackingLabel& label,
                                           const KittiTrackingCalibration& calib) {
  Eigen::Vector3d centre = label.location;
  centre.y() -= 0.5 * label.height_m;  // camera y points down
  return calib.rectToVelo(centre);
}

}  // namespace core
}  // namespace urban_detection
