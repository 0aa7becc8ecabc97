#include "urban_detection/core/evaluation/frame_picture.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace urban_detection {
namespace core {

namespace {

cv::Scalar idColour(std::uint32_t id) {
  std::uint32_t h = id * 2654435761u;
  return cv::Scalar(60 + (h & 0xFF) % 196, 60 + ((h >> 8) & 0xFF) % 196,
                    60 + ((h >> 16) & 0xFF) % 196);
}

// BGR colours of the object classes, those of the rviz markers (ros/object_markers.cpp).
cv::Scalar classColour(ObjectCategory c) {
  switch (c) {
    case ObjectCategory::kVehicle:
      return cv::Scalar(255, 150, 40);
    case ObjectCategory::kPedestrian:
      return cv::Scalar(110, 70, 255);
    case ObjectCategory::kCyclist:
      return cv::Scalar(0, 210, 255);
    case ObjectCategory::kOtherObject:
      return cv::Scalar(200, 230, 0);
    default:
      return cv::Scalar(200, 160, 200);  // unclassified
  }
}

}  // namespace

bool writeFramePng(const std::string& path, const Frame& f, const LabeledCloud& fg,
                   const std::vector<DetectedObject>& dets, const FrameMatch& m, const PngView& v) {
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
      cg = classColour(categoryOfClassName(f.gt.objects[g].label));
    } else if (f.gt.role.size() == n && f.gt.role[i] == PointRole::kDontCare) {
      cg = cv::Scalar(110, 110, 110);
    }
    if (!is_fg[i]) cg *= 0.45;
    img.at<cv::Vec3b>(toPx(p.x, p.y, 0)) = cv::Vec3b(cg[0], cg[1], cg[2]);
    cv::Scalar cd = is_fg[i] ? cv::Scalar(90, 90, 90) : cv::Scalar(35, 35, 35);
    if (det_of[i] >= 0) {
      const ObjectCategory c = dets[static_cast<std::size_t>(det_of[i])].category;
      cd = c == ObjectCategory::kUnknown
               ? idColour(7919u * static_cast<std::uint32_t>(det_of[i] + 1))
               : classColour(c);
    }
    img.at<cv::Vec3b>(toPx(p.x, p.y, 1)) = cv::Vec3b(cd[0], cd[1], cd[2]);
  }
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (m.verdict[d] != DetectionVerdict::kFalse) continue;
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
      {"other_object", classColour(ObjectCategory::kOtherObject)},
      {"cyclist", classColour(ObjectCategory::kCyclist)},
      {"pedestrian", classColour(ObjectCategory::kPedestrian)},
      {"vehicle", classColour(ObjectCategory::kVehicle)}};
  for (const auto& l : legend) {
    cv::putText(img, l.first, cv::Point(side + 15, y), font, 0.45, l.second, 1);
    y -= 16;
  }
  return cv::imwrite(path, img);
}

}  // namespace core
}  // namespace urban_detection
