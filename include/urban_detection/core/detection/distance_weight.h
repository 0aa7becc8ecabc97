/// \file distance_weight.h
/// Sensor-distance weight of grid-cell densities (paper Sec. 4, "Data characteristic
/// analysis"), and the ring-density statistics and least-squares fit that produce it. ROS-free.
///
/// The paper measures the point density in 1 m wide rings around the sensor (1..80 m),
/// normalises it by the ring area and then by its maximum, and fits a sixth-degree polynomial
/// to this normalised density rho(d) (~1 where the sensor sees most, towards 0 far away). It
/// then "enriches" the density of far cells so that, after weighting, the sub-cells of an
/// object have densities of the same order wherever the object stands: the weight is the
/// inverse of the fitted normalised density.
///
/// On real HDL-64E sweeps rho falls by four orders of magnitude between 5 and 80 m, and a
/// sixth-degree polynomial fitted to rho itself oscillates around zero beyond ~20 m (negative
/// "densities", fit rms ~0.1 on ../shared/data/kitti_raw; urban_detection_fit_density
/// --linear shows it). So by default (`log_fit`) the sixth-degree polynomial p(d) is fitted
/// to ln rho(d), and the fitted density is exp(p(d)) > 0. The weight applied here is
///
///     w(d) = 1                                               for d <= d0
///     w(d) = clamp(f(d0) / f(min(d, max_distance_m)), 1, max_weight)   otherwise
///     f = exp(p) with log_fit, f = p without (w = max_weight where f <= 0)
///
/// with d0 = full_density_distance_m, the maximum of the fitted density (so the weight is the
/// inverse of the fitted density normalised by its maximum, continuous at d0).
/// where d is the horizontal distance of the (sub-)cell centre from the sensor [m]. Below the
/// distance of the density maximum rho is low only because the lowest beam meets the road a
/// few metres out, not because objects there are sparse, so no enrichment is applied there;
/// beyond the fitted range the polynomial is not extrapolated; and the clamp bounds the gain
/// (the ring density is dominated by the road, whose density falls faster with distance than
/// that of vertical object surfaces, so the unclamped weight over-compensates far away). A
/// weighted density is n * w(d).
#pragma once

#include <cstddef>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Parameters of the distance weight; defaults are the fit on ../shared/data/kitti_raw (both
/// drives, 62 sweeps: `urban_detection_fit_density ../shared/data/kitti_raw/drive_0005
/// ../shared/data/kitti_raw/drive_0048`, fit rms 0.094), mirrored in config/hierarchical_grid.yaml.
struct DistanceWeightParams {
  bool enabled = true;  // false: w(d) = 1 everywhere (no density compensation)
  bool log_fit = true;  // true: the polynomial is of ln(normalised density), see above
  /// Polynomial p(d) = sum_k coefficients[k] * d^k, d in [m].
  std::vector<double> coefficients = {-3.2283822161e+00, 7.9045388742e-01,  -8.6082372620e-02,
                                      3.3503074472e-03,  -6.2757445375e-05, 5.6547142417e-07,
                                      -1.9682182937e-09};
  double full_density_distance_m = 7.0;  // [m] d0: w = 1 up to here (fitted density maximum)
  double max_distance_m = 80.0;          // [m] p is evaluated at most here (fitted range)
  double max_weight = 20.0;              // [-] upper clamp of w (>= 1)
};

/// DistanceWeightParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<DistanceWeightParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"enabled", "false: w(d) = 1 everywhere (no density compensation)"}, p.enabled);
    f({"log_fit", "the polynomial is of ln(normalised density)"}, p.log_fit);
    f({"coefficients", "polynomial p(d) = sum_k c[k] d^k, d in m (1..16 finite numbers)"},
      p.coefficients);
    f({"full_density_distance_m", "m", 0.0, 1000.0, "d0: w = 1 up to here"},
      p.full_density_distance_m);
    f({"max_distance_m", "m", 0.1, 1000.0, "p is evaluated at most here"}, p.max_distance_m);
    f({"max_weight", "", 1.0, 1e6, "upper clamp of w"}, p.max_weight);
  }
};

/// "" when `p` is usable: the table's ranges, 1..16 finite coefficients and
/// full_density_distance_m < max_distance_m; else why not.
std::string validate(const DistanceWeightParams& p);

/// Evaluates w(d) (see the file comment), through a lookup table of `step_m` resolution built
/// once, so the per-cell cost is one multiply and one load.
class DistanceWeight {
 public:
  explicit DistanceWeight(const DistanceWeightParams& params = DistanceWeightParams(),
                          double table_range_m = 120.0, double step_m = 0.05);
  /// Fitted normalised density f(d) at `d_m` [m] (exp of the polynomial with log_fit).
  double fitted(double d_m) const;
  /// Exact weight at horizontal distance `d_m` [m] (no table).
  double exact(double d_m) const;
  /// Table weight at horizontal distance `d_m` [m]; distances beyond the table range use the
  /// last entry. NaN gives the weight at 0.
  float operator()(float d_m) const {
    if (!(d_m > 0.0f)) return table_[0];
    const std::size_t i = static_cast<std::size_t>(d_m * inv_step_);
    return i < table_.size() ? table_[i] : table_.back();
  }
  const DistanceWeightParams& params() const { return params_; }

 private:
  DistanceWeightParams params_;
  float inv_step_;
  std::vector<float> table_;
};

/// Evaluates sum_k c[k] * x^k (Horner).
double evalPolynomial(const std::vector<double>& c, double x);

/// Least-squares polynomial of degree `degree` through (x[i], y[i]): returns c[0..degree] in
/// the units of x (the fit is done on x scaled to [-1, 1] with a column-pivoting QR for
/// conditioning, then converted back). Requires x.size() == y.size() > degree; otherwise
/// returns an empty vector.
std::vector<double> fitPolynomial(const std::vector<double>& x, const std::vector<double>& y,
                                  int degree);

/// Accumulates point counts per 1 m (configurable) ring of horizontal distance over many
/// sweeps (paper Sec. 4: rings 1..80 m).
class RingDensity {
 public:
  RingDensity(double min_m = 1.0, double max_m = 80.0, double ring_width_m = 1.0);
  /// Adds the finite points of one sweep. Returns the number of points that fell in a ring.
  std::size_t add(const CloudXYZIRT& cloud);
  /// Adds one point at horizontal distance `d_m` (for tests and other cloud types).
  void addDistance(double d_m);
  std::size_t rings() const { return counts_.size(); }
  /// Centre distance of ring i [m].
  double ringCenter(std::size_t i) const { return min_m_ + (i + 0.5) * width_m_; }
  /// Points per square metre per sweep in ring i (count / ring area / sweeps).
  std::vector<double> density() const;
  /// density() divided by its maximum (all zeros when no point was added).
  std::vector<double> normalisedDensity() const;
  std::size_t sweeps() const { return sweeps_; }

 private:
  double min_m_, max_m_, width_m_;
  std::vector<double> counts_;
  std::size_t sweeps_ = 0;
};

}  // namespace core
}  // namespace urban_detection
