#include "urban_detection/core/object_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace urban_detection {
namespace core {
namespace {

float cross(const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

}  // namespace

void convexHull2d(std::vector<Eigen::Vector2f>* points, std::vector<Eigen::Vector2f>* hull) {
  std::vector<Eigen::Vector2f>& p = *points;
  hull->clear();
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  const std::size_t n = p.size();
  if (n < 3) {
    hull->assign(p.begin(), p.end());
    return;
  }
  hull->resize(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {  // lower hull
    while (k >= 2 && cross((*hull)[k - 2], (*hull)[k - 1], p[i]) <= 0.0f) --k;
    (*hull)[k++] = p[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {  // upper hull
    while (k >= t && cross((*hull)[k - 2], (*hull)[k - 1], p[i]) <= 0.0f) --k;
    (*hull)[k++] = p[i];
  }
  hull->resize(k - 1);  // the last point repeats the first
}

void minAreaRectangle(const std::vector<Eigen::Vector2f>& hull, Eigen::Vector2f* center,
                      Eigen::Vector2f* size, float* yaw_rad) {
  *center = Eigen::Vector2f::Zero();
  *size = Eigen::Vector2f::Zero();
  *yaw_rad = 0.0f;
  if (hull.empty()) return;
  if (hull.size() == 1) {
    *center = hull[0];
    return;
  }
  // Every hull edge direction is a candidate; the hull is small (tens of vertices) so the
  // quadratic scan is cheaper in practice than maintaining rotating-caliper pointers.
  double best_area = std::numeric_limits<double>::infinity();
  const std::size_t n = hull.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f e = hull[(i + 1) % n] - hull[i];
    const float len = e.norm();
    if (len <= 0.0f) continue;
    const Eigen::Vector2f u = e / len;
    const Eigen::Vector2f v(-u.y(), u.x());
    float umin = std::numeric_limits<float>::max(), umax = -umin;
    float vmin = umin, vmax = -umin;
    for (const Eigen::Vector2f& q : hull) {
      const float a = q.dot(u), b = q.dot(v);
      umin = std::min(umin, a);
      umax = std::max(umax, a);
      vmin = std::min(vmin, b);
      vmax = std::max(vmax, b);
    }
    const double area = static_cast<double>(umax - umin) * static_cast<double>(vmax - vmin);
    if (area < best_area - 1e-12) {
      best_area = area;
      *center = u * (0.5f * (umin + umax)) + v * (0.5f * (vmin + vmax));
      float lu = umax - umin, lv = vmax - vmin;
      float yaw = std::atan2(u.y(), u.x());
      if (lv > lu) {
        std::swap(lu, lv);
        yaw += static_cast<float>(M_PI / 2);
      }
      // Normalise to (-pi/2, pi/2]: a box is symmetric under a half turn.
      while (yaw > static_cast<float>(M_PI / 2)) yaw -= static_cast<float>(M_PI);
      while (yaw <= -static_cast<float>(M_PI / 2)) yaw += static_cast<float>(M_PI);
      *size = Eigen::Vector2f(lu, lv);
      *yaw_rad = yaw;
    }
  }
}

void ObjectGeometry::compute(const LabeledCloud& cloud,
                             const std::vector<std::uint32_t>& cloud_positions,
                             DetectedObject* object) {
  object->centroid.setZero();
  object->min_pt.setZero();
  object->max_pt.setZero();
  object->obb_center.setZero();
  object->obb_size.setZero();
  object->obb_yaw_rad = 0.0f;
  if (cloud_positions.empty()) return;

  // Pass 1: centroid, axis-aligned box and the eight extreme points along x, y, x+y, x-y.
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3f mn = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f mx = -mn;
  float ext[8];  // max of x, -x, y, -y, x+y, -(x+y), x-y, -(x-y)
  Eigen::Vector2f ext_pt[8];
  std::fill(ext, ext + 8, -std::numeric_limits<float>::max());
  for (const std::uint32_t pos : cloud_positions) {
    const LabeledPoint& p = cloud.points[pos];
    sum += Eigen::Vector3d(p.x, p.y, p.z);
    mn = mn.cwiseMin(Eigen::Vector3f(p.x, p.y, p.z));
    mx = mx.cwiseMax(Eigen::Vector3f(p.x, p.y, p.z));
    const float proj[8] = {p.x, -p.x, p.y, -p.y, p.x + p.y, -(p.x + p.y), p.x - p.y, p.y - p.x};
    for (int k = 0; k < 8; ++k) {
      if (proj[k] > ext[k]) {
        ext[k] = proj[k];
        ext_pt[k] = Eigen::Vector2f(p.x, p.y);
      }
    }
  }
  object->centroid = (sum / static_cast<double>(cloud_positions.size())).cast<float>();
  object->min_pt = mn;
  object->max_pt = mx;

  // Pass 2 (Akl-Toussaint): points strictly inside the polygon of the extreme points cannot be
  // hull vertices, which removes most points of a dense object before the O(n log n) hull.
  // Extreme points in counter-clockwise order of their directions (0, 45, ..., 315 deg) are
  // hull vertices in counter-clockwise order.
  static constexpr int kCcw[8] = {0, 4, 2, 7, 1, 5, 3, 6};
  std::vector<Eigen::Vector2f>& poly = poly_;
  poly.clear();
  for (const int k : kCcw) {
    const Eigen::Vector2f& q = ext_pt[k];
    if (poly.empty() || (poly.back() - q).squaredNorm() > 0.0f) poly.push_back(q);
  }
  if (poly.size() > 1 && (poly.front() - poly.back()).squaredNorm() == 0.0f) poly.pop_back();
  pts_.clear();
  const bool filter = poly.size() >= 3;
  for (const std::uint32_t pos : cloud_positions) {
    const Eigen::Vector2f q(cloud.points[pos].x, cloud.points[pos].y);
    bool inside = filter;
    for (std::size_t i = 0; inside && i < poly.size(); ++i) {
      inside = cross(poly[i], poly[(i + 1) % poly.size()], q) > 0.0f;
    }
    if (!inside) pts_.push_back(q);
  }
  for (const Eigen::Vector2f& q : poly) pts_.push_back(q);
  convexHull2d(&pts_, &hull_);
  Eigen::Vector2f c, s;
  float yaw = 0.0f;
  minAreaRectangle(hull_, &c, &s, &yaw);
  object->obb_center = Eigen::Vector3f(c.x(), c.y(), 0.5f * (mn.z() + mx.z()));
  object->obb_size = Eigen::Vector3f(s.x(), s.y(), mx.z() - mn.z());
  object->obb_yaw_rad = yaw;
}

}  // namespace core
}  // namespace urban_detection
