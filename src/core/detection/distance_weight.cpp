#include "urban_detection/core/detection/distance_weight.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace urban_detection {
namespace core {

std::string validate(const DistanceWeightParams& p) {
  std::string error = checkFieldRanges(p);
  if (!error.empty()) return error;
  if (p.coefficients.empty() || p.coefficients.size() > 16) {
    return "coefficients must have 1..16 entries, got " + std::to_string(p.coefficients.size());
  }
  for (const double c : p.coefficients) {
    if (!std::isfinite(c)) return "coefficients must be finite";
  }
  if (!(p.max_distance_m > p.full_density_distance_m)) {
    return "full_density_distance_m (" + std::to_string(p.full_density_distance_m) +
           ") must be below max_distance_m (" + std::to_string(p.max_distance_m) + ")";
  }
  return "";
}

double evalPolynomial(const std::vector<double>& c, double x) {
  double r = 0.0;
  for (std::size_t k = c.size(); k-- > 0;) r = r * x + c[k];
  return r;
}

DistanceWeight::DistanceWeight(const DistanceWeightParams& params, double table_range_m,
                               double step_m)
    : params_(params), inv_step_(static_cast<float>(1.0 / step_m)) {
  const std::size_t n = static_cast<std::size_t>(std::ceil(table_range_m / step_m)) + 1;
  table_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    // The middle of each table bin, so the table error is at most half a step of distance.
    table_[i] = static_cast<float>(exact((i + 0.5) * step_m));
  }
}

double DistanceWeight::fitted(double d_m) const {
  const double p = evalPolynomial(params_.coefficients, d_m);
  return params_.log_fit ? std::exp(p) : p;
}

double DistanceWeight::exact(double d_m) const {
  if (!params_.enabled || !(d_m > params_.full_density_distance_m)) return 1.0;
  const double f = fitted(std::min(d_m, params_.max_distance_m));
  const double f0 = fitted(params_.full_density_distance_m);
  const double w_max = std::max(1.0, params_.max_weight);
  if (!(f > f0 / w_max)) return w_max;  // also f <= 0 and NaN
  return std::clamp(f0 / f, 1.0, w_max);
}

std::vector<double> fitPolynomial(const std::vector<double>& x, const std::vector<double>& y,
                                  int degree) {
  if (degree < 0 || x.size() != y.size() || x.size() <= static_cast<std::size_t>(degree)) {
    return {};
  }
  const auto [lo_it, hi_it] = std::minmax_element(x.begin(), x.end());
  const double mid = 0.5 * (*lo_it + *hi_it);
  const double half = std::max(0.5 * (*hi_it - *lo_it), 1e-12);
  const int m = static_cast<int>(x.size());
  Eigen::MatrixXd a(m, degree + 1);
  Eigen::VectorXd b(m);
  for (int i = 0; i < m; ++i) {
    const double t = (x[i] - mid) / half;
    double p = 1.0;
    for (int k = 0; k <= degree; ++k, p *= t) a(i, k) = p;
    b(i) = y[i];
  }
  const Eigen::VectorXd ct = a.colPivHouseholderQr().solve(b);
  // Convert sum_k ct_k ((x - mid) / half)^k to sum_j c_j x^j by expanding the binomials.
  std::vector<double> c(degree + 1, 0.0);
  for (int k = 0; k <= degree; ++k) {
    const double scale = ct(k) / std::pow(half, k);
    double binom = 1.0;  // C(k, j)
    for (int j = 0; j <= k; ++j) {
      c[j] += scale * binom * std::pow(-mid, k - j);
      binom = binom * (k - j) / (j + 1);
    }
  }
  return c;
}

RingDensity::RingDensity(double min_m, double max_m, double ring_width_m)
    : min_m_(min_m), max_m_(max_m), width_m_(ring_width_m) {
  const double n = std::floor((max_m - min_m) / ring_width_m + 1e-9);
  counts_.assign(n > 0 ? static_cast<std::size_t>(n) : 0, 0.0);
}

void RingDensity::addDistance(double d_m) {
  if (!(d_m >= min_m_) || !(d_m < max_m_)) return;
  const std::size_t i = static_cast<std::size_t>((d_m - min_m_) / width_m_);
  if (i < counts_.size()) counts_[i] += 1.0;
}

std::size_t RingDensity::add(const CloudXYZIRT& cloud) {
  std::size_t used = 0;
  for (const PointXYZIRT& p : cloud.points) {
    if (!isFinitePoint(p)) continue;
    const double d = std::hypot(static_cast<double>(p.x), static_cast<double>(p.y));
    if (d >= min_m_ && d < max_m_) {
      addDistance(d);
      ++used;
    }
  }
  ++sweeps_;
  return used;
}

std::vector<double> RingDensity::density() const {
  std::vector<double> d(counts_.size(), 0.0);
  const double sweeps = std::max<std::size_t>(sweeps_, 1);
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    const double r0 = min_m_ + i * width_m_, r1 = r0 + width_m_;
    d[i] = counts_[i] / (M_PI * (r1 * r1 - r0 * r0)) / sweeps;
  }
  return d;
}

std::vector<double> RingDensity::normalisedDensity() const {
  std::vector<double> d = density();
  const double mx = d.empty() ? 0.0 : *std::max_element(d.begin(), d.end());
  if (mx > 0.0) {
    for (double& v : d) v /= mx;
  }
  return d;
}

}  // namespace core
}  // namespace urban_detection
