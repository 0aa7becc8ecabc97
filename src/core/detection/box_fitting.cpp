#include "urban_detection/core/detection/box_fitting.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace urban_detection {
namespace core {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Size prior (length, width) of a class; false for classes without one.
bool sizePrior(const BoxFittingParams& p, ObjectCategory c, double* length, double* width) {
  switch (c) {
    case ObjectCategory::kVehicle:
      *length = p.vehicle_length_m;
      *width = p.vehicle_width_m;
      return true;
    case ObjectCategory::kPedestrian:
      *length = p.pedestrian_length_m;
      *width = p.pedestrian_width_m;
      return true;
    case ObjectCategory::kCyclist:
      *length = p.cyclist_length_m;
      *width = p.cyclist_width_m;
      return true;
    default:
      return false;
  }
}

// Interval [lo, hi] along one axis grown to `target`, the seen end kept (sensor coordinate s
// along the axis beyond that end), or both ends when the sensor lies between them.
void grow(double s, double target, double* lo, double* hi) {
  const double extent = *hi - *lo;
  if (extent >= target) return;
  if (s <= *lo) {
    *hi = *lo + target;
  } else if (s >= *hi) {
    *lo = *hi - target;
  } else {
    const double mid = 0.5 * (*lo + *hi);
    *lo = mid - 0.5 * target;
    *hi = mid + 0.5 * target;
  }
}

// closenessScore() on points stored apart (x[], y[]), four at a time where SSE2 is there: the
// same criterion, summed in another order (closenessScore is its plain reference, tested).
float closenessScoreSoa(const float* x, const float* y, std::size_t n, float c, float s, float d0) {
  std::size_t i = 0;
  float min1 = std::numeric_limits<float>::max(), max1 = -min1, min2 = min1, max2 = -min1;
#if defined(__SSE2__)
  const __m128 vc = _mm_set1_ps(c), vs = _mm_set1_ps(s);
  __m128 vmin1 = _mm_set1_ps(min1), vmax1 = _mm_set1_ps(max1);
  __m128 vmin2 = vmin1, vmax2 = vmax1;
  for (; i + 4 <= n; i += 4) {
    const __m128 px = _mm_loadu_ps(x + i), py = _mm_loadu_ps(y + i);
    const __m128 u = _mm_add_ps(_mm_mul_ps(px, vc), _mm_mul_ps(py, vs));
    const __m128 v = _mm_sub_ps(_mm_mul_ps(py, vc), _mm_mul_ps(px, vs));
    vmin1 = _mm_min_ps(vmin1, u);
    vmax1 = _mm_max_ps(vmax1, u);
    vmin2 = _mm_min_ps(vmin2, v);
    vmax2 = _mm_max_ps(vmax2, v);
  }
  alignas(16) float a[4], b[4], e[4], f[4];
  _mm_store_ps(a, vmin1);
  _mm_store_ps(b, vmax1);
  _mm_store_ps(e, vmin2);
  _mm_store_ps(f, vmax2);
  for (int k = 0; k < 4; ++k) {
    min1 = std::min(min1, a[k]);
    max1 = std::max(max1, b[k]);
    min2 = std::min(min2, e[k]);
    max2 = std::max(max2, f[k]);
  }
#endif
  for (std::size_t j = i; j < n; ++j) {
    const float u = x[j] * c + y[j] * s, v = y[j] * c - x[j] * s;
    min1 = std::min(min1, u);
    max1 = std::max(max1, u);
    min2 = std::min(min2, v);
    max2 = std::max(max2, v);
  }
  float score = 0.0f;
  i = 0;
#if defined(__SSE2__)
  const __m128 lo1 = _mm_set1_ps(min1), hi1 = _mm_set1_ps(max1);
  const __m128 lo2 = _mm_set1_ps(min2), hi2 = _mm_set1_ps(max2);
  const __m128 floor = _mm_set1_ps(d0), one = _mm_set1_ps(1.0f);
  __m128 acc = _mm_setzero_ps();
  for (; i + 4 <= n; i += 4) {
    const __m128 px = _mm_loadu_ps(x + i), py = _mm_loadu_ps(y + i);
    const __m128 u = _mm_add_ps(_mm_mul_ps(px, vc), _mm_mul_ps(py, vs));
    const __m128 v = _mm_sub_ps(_mm_mul_ps(py, vc), _mm_mul_ps(px, vs));
    const __m128 d1 = _mm_min_ps(_mm_sub_ps(hi1, u), _mm_sub_ps(u, lo1));
    const __m128 d2 = _mm_min_ps(_mm_sub_ps(hi2, v), _mm_sub_ps(v, lo2));
    acc = _mm_add_ps(acc, _mm_div_ps(one, _mm_max_ps(_mm_min_ps(d1, d2), floor)));
  }
  alignas(16) float sum[4];
  _mm_store_ps(sum, acc);
  score = (sum[0] + sum[1]) + (sum[2] + sum[3]);
#endif
  for (std::size_t j = i; j < n; ++j) {
    const float u = x[j] * c + y[j] * s, v = y[j] * c - x[j] * s;
    const float d1 = std::min(max1 - u, u - min1), d2 = std::min(max2 - v, v - min2);
    score += 1.0f / std::max(std::min(d1, d2), d0);
  }
  return score;
}

using Polygon = std::array<Eigen::Vector2d, 16>;

int rectangle(const Eigen::Vector2d& c, double l, double w, double yaw, Polygon* out) {
  const Eigen::Vector2d ax(std::cos(yaw) * 0.5 * l, std::sin(yaw) * 0.5 * l);
  const Eigen::Vector2d ay(-std::sin(yaw) * 0.5 * w, std::cos(yaw) * 0.5 * w);
  (*out)[0] = c + ax + ay;  // counter-clockwise
  (*out)[1] = c - ax + ay;
  (*out)[2] = c - ax - ay;
  (*out)[3] = c + ax - ay;
  return 4;
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double area(const Polygon& p, int n) {
  double s = 0.0;
  for (int k = 0; k < n; ++k) s += cross(p[k], p[(k + 1) % n]);
  return 0.5 * std::fabs(s);
}

}  // namespace

std::string validate(const BoxFittingParams& p) {
  std::string error = checkFieldRanges(p);
  if (!error.empty()) return error;
  const struct {
    const char* name;
    double length, width;
  } priors[] = {{"vehicle", p.vehicle_length_m, p.vehicle_width_m},
                {"pedestrian", p.pedestrian_length_m, p.pedestrian_width_m},
                {"cyclist", p.cyclist_length_m, p.cyclist_width_m}};
  for (const auto& q : priors) {
    if (q.width > q.length) {
      std::ostringstream msg;
      msg << "parameter '" << q.name << "_width_m' = " << q.width << " must not exceed '" << q.name
          << "_length_m' = " << q.length << " m";
      return msg.str();
    }
  }
  return "";
}

double closenessScore(const Eigen::Vector2f* xy, std::size_t n, double theta, double d0) {
  if (n == 0) return 0.0;
  const float c = static_cast<float>(std::cos(theta)), s = static_cast<float>(std::sin(theta));
  float min1 = std::numeric_limits<float>::max(), max1 = -min1, min2 = min1, max2 = -min1;
  for (std::size_t i = 0; i < n; ++i) {
    const float u = xy[i].x() * c + xy[i].y() * s;
    const float v = -xy[i].x() * s + xy[i].y() * c;
    min1 = std::min(min1, u);
    max1 = std::max(max1, u);
    min2 = std::min(min2, v);
    max2 = std::max(max2, v);
  }
  const float floor = static_cast<float>(d0);
  float score = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    const float u = xy[i].x() * c + xy[i].y() * s;
    const float v = -xy[i].x() * s + xy[i].y() * c;
    const float d1 = std::min(max1 - u, u - min1);
    const float d2 = std::min(max2 - v, v - min2);
    score += 1.0f / std::max(std::min(d1, d2), floor);
  }
  return score;
}

BevBox completeBox(const Eigen::Vector2f* xy, std::size_t n, double theta, ObjectCategory category,
                   const Eigen::Vector2f& sensor, const BoxFittingParams& p) {
  BevBox box;
  if (n == 0) return box;
  const double c = std::cos(theta), s = std::sin(theta);
  // Axis 1 along (c, s), axis 2 along (-s, c).
  double lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  double hi[2] = {-lo[0], -lo[1]};
  for (std::size_t i = 0; i < n; ++i) {
    const double u = xy[i].x() * c + xy[i].y() * s;
    const double v = -xy[i].x() * s + xy[i].y() * c;
    lo[0] = std::min(lo[0], u);
    hi[0] = std::max(hi[0], u);
    lo[1] = std::min(lo[1], v);
    hi[1] = std::max(hi[1], v);
  }
  const double sensor_u[2] = {sensor.x() * c + sensor.y() * s, -sensor.x() * s + sensor.y() * c};
  double prior_length = 0.0, prior_width = 0.0;
  const double ext[2] = {hi[0] - lo[0], hi[1] - lo[1]};
  int length_axis = ext[0] >= ext[1] ? 0 : 1;
  if (sizePrior(p, category, &prior_length, &prior_width)) {
    if (std::max(ext[0], ext[1]) < prior_width + p.side_margin_m) {
      // No side seen for sure: the length lies along the axis nearer the line of sight.
      const double mid_u = 0.5 * (lo[0] + hi[0]) - sensor_u[0];
      const double mid_v = 0.5 * (lo[1] + hi[1]) - sensor_u[1];
      length_axis = std::fabs(mid_u) >= std::fabs(mid_v) ? 0 : 1;
    }
    grow(sensor_u[length_axis], prior_length, &lo[length_axis], &hi[length_axis]);
    grow(sensor_u[1 - length_axis], prior_width, &lo[1 - length_axis], &hi[1 - length_axis]);
  }
  const double mu = 0.5 * (lo[0] + hi[0]), mv = 0.5 * (lo[1] + hi[1]);
  box.center =
      Eigen::Vector2f(static_cast<float>(mu * c - mv * s), static_cast<float>(mu * s + mv * c));
  const double len = hi[length_axis] - lo[length_axis];
  const double wid = hi[1 - length_axis] - lo[1 - length_axis];
  double yaw = theta + (length_axis == 1 ? 0.5 * kPi : 0.0);
  if (wid > len) {  // only without a prior: the longer side is the length
    yaw += 0.5 * kPi;
  }
  box.size = Eigen::Vector2f(static_cast<float>(std::max(len, wid)),
                             static_cast<float>(std::min(len, wid)));
  while (yaw > 0.5 * kPi) yaw -= kPi;
  while (yaw <= -0.5 * kPi) yaw += kPi;
  box.yaw_rad = static_cast<float>(yaw);
  return box;
}

BoxFitter::BoxFitter(const BoxFittingParams& params) {
  setParams(params);
}

void BoxFitter::setParams(const BoxFittingParams& params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument("BoxFittingParams: " + error);
  params_ = params;
}

double BoxFitter::searchHeading(const Eigen::Vector2f* xy, std::size_t n) {
  // A stride sample keeps the points' spread along the faces at a bounded cost per heading.
  const std::size_t cap = static_cast<std::size_t>(params_.max_fit_points);
  const std::size_t m = std::min(n, cap);
  const double stride = static_cast<double>(n) / static_cast<double>(m);
  sx_.resize(m);
  sy_.resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    const Eigen::Vector2f& q = xy[n > cap ? static_cast<std::size_t>(k * stride) : k];
    sx_[k] = q.x();
    sy_[k] = q.y();
  }
  const float d0 = static_cast<float>(params_.closeness_min_distance_m);
  auto score = [&](double t) {
    return closenessScoreSoa(sx_.data(), sy_.data(), m, static_cast<float>(std::cos(t)),
                             static_cast<float>(std::sin(t)), d0);
  };
  const double coarse = params_.coarse_step_deg * kPi / 180.0;
  const double fine = params_.fine_step_deg * kPi / 180.0;
  double best = 0.0, best_score = -1.0;
  for (double t = 0.0; t < 0.5 * kPi - 1e-9; t += coarse) {
    const double sc = score(t);
    if (sc > best_score) {
      best_score = sc;
      best = t;
    }
  }
  const double centre = best;
  for (double t = centre - coarse + fine; t < centre + coarse - 1e-9; t += fine) {
    if (std::fabs(t - centre) < 1e-9) continue;
    const double sc = score(t);
    if (sc > best_score) {
      best_score = sc;
      best = t;
    }
  }
  best = std::fmod(best, 0.5 * kPi);
  if (best < 0.0) best += 0.5 * kPi;
  return best;
}

BevBox BoxFitter::fitPoints(const Eigen::Vector2f* xy, std::size_t n, ObjectCategory category,
                            const Eigen::Vector2f& sensor, float fallback_yaw) {
  double theta = fallback_yaw;
  if (n >= 3) theta = searchHeading(xy, n);
  return completeBox(xy, n, theta, category, sensor, params_);
}

void BoxFitter::fit(const LabeledCloud& foreground, std::vector<DetectedObject>* objects) {
  if (!params_.enabled || objects->empty()) return;
  index_.build(foreground);
  for (DetectedObject& o : *objects) {
    pts_.clear();
    for (const std::uint32_t idx : o.indices) {
      const LabeledPoint* p = index_.find(foreground, idx);
      if (p && std::isfinite(p->x) && std::isfinite(p->y)) pts_.emplace_back(p->x, p->y);
    }
    if (pts_.empty()) continue;
    const BevBox b =
        fitPoints(pts_.data(), pts_.size(), o.category, Eigen::Vector2f::Zero(), o.obb_yaw_rad);
    o.obb_center.x() = b.center.x();
    o.obb_center.y() = b.center.y();
    o.obb_size.x() = b.size.x();
    o.obb_size.y() = b.size.y();
    o.obb_yaw_rad = b.yaw_rad;
  }
}

double bevIoU(const Eigen::Vector2d& c1, double l1, double w1, double yaw1,
              const Eigen::Vector2d& c2, double l2, double w2, double yaw2) {
  if (!(l1 > 0 && w1 > 0 && l2 > 0 && w2 > 0)) return 0.0;
  // Quick reject on the circumscribed circles.
  const double r1 = 0.5 * std::hypot(l1, w1), r2 = 0.5 * std::hypot(l2, w2);
  if ((c1 - c2).squaredNorm() >= (r1 + r2) * (r1 + r2)) return 0.0;
  // Sutherland-Hodgman: clip rectangle 1 by the four edges of rectangle 2 (both convex).
  Polygon clip, a, b;
  rectangle(c2, l2, w2, yaw2, &clip);
  int n = rectangle(c1, l1, w1, yaw1, &a);
  for (int e = 0; e < 4 && n > 0; ++e) {
    const Eigen::Vector2d& p0 = clip[e];
    const Eigen::Vector2d edge = clip[(e + 1) % 4] - p0;
    int m = 0;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d& cur = a[k];
      const Eigen::Vector2d& nxt = a[(k + 1) % n];
      const double sc = cross(edge, cur - p0), sn = cross(edge, nxt - p0);
      if (sc >= 0) b[m++] = cur;
      if ((sc >= 0) != (sn >= 0)) b[m++] = cur + (nxt - cur) * (sc / (sc - sn));
      if (m >= 14) break;  // cannot happen for two rectangles; keeps the array bounded
    }
    a = b;
    n = m;
  }
  const double inter = n >= 3 ? area(a, n) : 0.0;
  const double uni = l1 * w1 + l2 * w2 - inter;
  return uni > 0 ? std::min(1.0, inter / uni) : 0.0;
}

}  // namespace core
}  // namespace urban_detection
