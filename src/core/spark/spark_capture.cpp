#include "urban_detection/core/spark/spark_capture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <type_traits>

namespace urban_detection {
namespace core {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

// cv::FileNode numbers: JSON integers come back as INT, others as REAL.
bool readNumber(const cv::FileNode& n, double* value) {
  if (!n.isInt() && !n.isReal()) return false;
  *value = static_cast<double>(n);
  return true;
}

}  // namespace

bool validateCapturePath(const CapturePathParams& p, std::string* error) {
  if (p.path.empty()) {
    *error = "'path' needs at least one [x, y, z] point";
    return false;
  }
  for (const Eigen::Vector3d& v : p.path) {
    if (!v.allFinite() || v.cwiseAbs().maxCoeff() > 1e7) {
      *error = "'path' points must be finite (and within 1e7 m)";
      return false;
    }
  }
  *error = checkFieldRanges(p);
  if (!error->empty()) return false;
  if (p.colour != "rgb" && p.colour != "intensity" && p.colour != "height") {
    *error = "'colour' must be \"rgb\", \"intensity\" or \"height\"";
    return false;
  }
  if (!(p.height_max_m > p.height_min_m) || !std::isfinite(p.height_min_m) ||
      !std::isfinite(p.height_max_m)) {
    *error = "'height_min_m' must be below 'height_max_m'";
    return false;
  }
  return true;
}

bool readCapturePathJson(const std::string& path, CapturePathParams* params, std::string* error) {
  CapturePathParams p;
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON);
    if (!fs.isOpened()) {
      *error = "cannot open capture path file '" + path + "'";
      return false;
    }
    const cv::FileNode root = fs.root();
    if (!root.isMap()) {
      *error = "'" + path + "' must hold a JSON object";
      return false;
    }
    std::set<std::string> known = {"path"};
    forEachField(p, [&](const FieldInfo& info, const auto&) { known.insert(info.name); });
    for (const std::string& key : root.keys()) {
      if (!known.count(key)) {
        *error = "unknown key '" + key + "' in '" + path + "'";
        return false;
      }
    }
    const cv::FileNode pts = root["path"];
    if (!pts.isSeq()) {
      *error = "'path' must be a list of [x, y, z] points";
      return false;
    }
    for (const cv::FileNode& pt : pts) {
      Eigen::Vector3d v;
      if (!pt.isSeq() || pt.size() != 3 || !readNumber(pt[0], &v.x()) ||
          !readNumber(pt[1], &v.y()) || !readNumber(pt[2], &v.z())) {
        *error = "'path' entries must be [x, y, z] numbers";
        return false;
      }
      p.path.push_back(v);
    }
    auto number = [&](const char* key, double* value) {
      const cv::FileNode n = root[key];
      if (n.empty() || n.isNone()) return true;
      if (readNumber(n, value)) return true;
      *error = std::string("'") + key + "' must be a number";
      return false;
    };
    auto integer = [&](const char* key, int* value) {
      double v = *value;
      if (!number(key, &v)) return false;
      if (v != std::floor(v) || std::fabs(v) > 1e9) {
        *error = std::string("'") + key + "' must be an integer";
        return false;
      }
      *value = static_cast<int>(v);
      return true;
    };
    bool ok = true;
    forEachField(p, [&](const FieldInfo& info, auto& field) {
      using T = std::decay_t<decltype(field)>;
      if (!ok) return;
      if constexpr (std::is_same_v<T, int>) {
        ok = integer(info.name.c_str(), &field);
      } else if constexpr (std::is_same_v<T, double>) {
        ok = number(info.name.c_str(), &field);
      } else {
        const cv::FileNode n = root[info.name];
        if (n.empty() || n.isNone()) return;
        if (!n.isString()) {
          *error = "'" + info.name + "' must be a string";
          ok = false;
          return;
        }
        field = static_cast<std::string>(n);
      }
    });
    if (!ok) return false;
  } catch (const cv::Exception& e) {
    *error = "cannot parse '" + path + "' as JSON: " + e.what();
    return false;
  }
  if (!validateCapturePath(p, error)) return false;
  *params = p;
  return true;
}

OrthoCamera OrthoCamera::make(const Eigen::Vector3d& position, double yaw_deg, double pitch_deg,
                              int width_px, int height_px, double metres_per_pixel,
                              double max_depth_m) {
  OrthoCamera c;
  c.position = position;
  c.yaw_deg = yaw_deg;
  c.pitch_deg = pitch_deg;
  c.width_px = width_px;
  c.height_px = height_px;
  c.metres_per_pixel = metres_per_pixel;
  c.max_depth_m = max_depth_m;
  const double yaw = yaw_deg * kDegToRad, pitch = pitch_deg * kDegToRad;
  const Eigen::Vector3d forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                                std::sin(pitch));
  // Right stays horizontal (no roll); at the nadir it follows the yaw like everywhere else.
  const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0.0);
  const Eigen::Vector3d down = forward.cross(right);
  c.rotation.row(0) = right.transpose();
  c.rotation.row(1) = down.transpose();
  c.rotation.row(2) = forward.transpose();
  return c;
}

void OrthoCamera::project(const Eigen::Vector3d& p, double* x_px, double* y_px,
                          double* depth_m) const {
  const Eigen::Vector3d local = rotation * (p - position);
  *x_px = local.x() / metres_per_pixel + 0.5 * width_px;
  *y_px = local.y() / metres_per_pixel + 0.5 * height_px;
  *depth_m = local.z();
}

Eigen::Vector3d OrthoCamera::unproject(double x_px, double y_px, double depth_m) const {
  const Eigen::Vector3d local((x_px - 0.5 * width_px) * metres_per_pixel,
                              (y_px - 0.5 * height_px) * metres_per_pixel, depth_m);
  return position + rotation.transpose() * local;
}

std::vector<OrthoCamera> capturePoses(const CapturePathParams& p) {
  std::vector<OrthoCamera> poses;
  if (p.path.empty() || p.interval_m <= 0.0 || p.rotations < 1) return poses;
  auto addPoint = [&](const Eigen::Vector3d& pos, double heading_deg) {
    for (int r = 0; r < p.rotations; ++r) {
      const double yaw = std::fmod(heading_deg + 360.0 * r / p.rotations, 360.0);
      poses.push_back(OrthoCamera::make(pos, yaw, p.pitch_deg, p.image_width_px, p.image_height_px,
                                        p.metres_per_pixel, p.max_depth_m));
    }
  };
  if (p.path.size() == 1) {
    addPoint(p.path[0], 0.0);
    return poses;
  }
  // Walk the polyline; `to_next` is the distance left until the next capture point.
  double to_next = 0.0;
  double last_heading = 0.0;
  for (std::size_t i = 0; i + 1 < p.path.size(); ++i) {
    const Eigen::Vector3d a = p.path[i], b = p.path[i + 1];
    const double len = (b - a).norm();
    if (len <= 0.0) continue;
    const double heading = std::atan2(b.y() - a.y(), b.x() - a.x()) / kDegToRad;
    last_heading = heading;
    double s = to_next;
    while (s <= len + 1e-9) {
      addPoint(a + (b - a) * (s / len), heading);
      s += p.interval_m;
    }
    to_next = s - len;
  }
  if (poses.empty()) addPoint(p.path.front(), last_heading);  // all segments degenerate
  return poses;
}

void pointColours(const CloudXYZIRT& cloud, const std::vector<cv::Vec3b>& rgb,
                  const CapturePathParams& params, std::vector<cv::Vec3b>* colours) {
  colours->resize(cloud.size());
  if (params.colour == "rgb") {
    for (std::size_t i = 0; i < cloud.size(); ++i)
      (*colours)[i] = i < rgb.size() ? rgb[i] : cv::Vec3b(128, 128, 128);
    return;
  }
  if (params.colour == "intensity") {
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const float v = cloud[i].intensity;
      const auto g = static_cast<std::uint8_t>(std::isfinite(v) ? std::clamp(v, 0.0f, 255.0f) : 0);
      (*colours)[i] = cv::Vec3b(g, g, g);
    }
    return;
  }
  cv::Mat lut(1, 256, CV_8U);
  for (int i = 0; i < 256; ++i) lut.at<std::uint8_t>(i) = static_cast<std::uint8_t>(i);
  cv::Mat jet;
  cv::applyColorMap(lut, jet, cv::COLORMAP_JET);
  const double span = params.height_max_m - params.height_min_m;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    double t = (cloud[i].z - params.height_min_m) / span;
    if (!std::isfinite(t)) t = 0.0;
    const int k = static_cast<int>(std::lround(std::clamp(t, 0.0, 1.0) * 255.0));
    (*colours)[i] = jet.at<cv::Vec3b>(0, k);
  }
}

std::size_t OrthoRenderer::render(const CloudXYZIRT& cloud, const std::vector<cv::Vec3b>& colours,
                                  const OrthoCamera& camera, int splat_radius_px, cv::Mat* image) {
  width_ = camera.width_px;
  height_ = camera.height_px;
  const std::size_t n_px = static_cast<std::size_t>(width_) * height_;
  depth_.assign(n_px, std::numeric_limits<float>::infinity());
  index_.assign(n_px, -1);
  image->create(height_, width_, CV_8UC3);
  image->setTo(cv::Scalar(0, 0, 0));
  const int r = std::max(0, splat_radius_px);
  const Eigen::Matrix3f rot = camera.rotation.cast<float>();
  const Eigen::Vector3f pos = camera.position.cast<float>();
  const float inv_mpp = static_cast<float>(1.0 / camera.metres_per_pixel);
  const float cx = 0.5f * width_, cy = 0.5f * height_;
  const float max_depth = static_cast<float>(camera.max_depth_m);
  std::size_t drawn = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointXYZIRT& p = cloud[i];
    if (!isFinitePoint(p)) continue;
    const Eigen::Vector3f local = rot * (Eigen::Vector3f(p.x, p.y, p.z) - pos);
    const float d = local.z();
    if (!(d > 0.0f && d <= max_depth)) continue;
    const float fx = local.x() * inv_mpp + cx, fy = local.y() * inv_mpp + cy;
    if (!(fx > -r - 1 && fy > -r - 1 && fx < width_ + r + 1 && fy < height_ + r + 1)) continue;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    bool any = false;
    for (int y = std::max(0, y0 - r); y <= std::min(height_ - 1, y0 + r); ++y) {
      for (int x = std::max(0, x0 - r); x <= std::min(width_ - 1, x0 + r); ++x) {
        const std::size_t k = static_cast<std::size_t>(y) * width_ + x;
        if (d < depth_[k]) {
          depth_[k] = d;
          index_[k] = static_cast<std::int32_t>(i);
          any = true;
        }
      }
    }
    drawn += any;
  }
  for (int y = 0; y < height_; ++y) {
    auto* row = image->ptr<cv::Vec3b>(y);
    const std::int32_t* idx = index_.data() + static_cast<std::size_t>(y) * width_;
    for (int x = 0; x < width_; ++x) {
      if (idx[x] >= 0 && static_cast<std::size_t>(idx[x]) < colours.size())
        row[x] = colours[idx[x]];
    }
  }
  return drawn;
}

}  // namespace core
}  // namespace urban_detection
