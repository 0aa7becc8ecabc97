// urban_detection_fit_density: fits the distance weight polynomial of the hierarchical grid
// detector (paper Sec. 4, Fig. 5) on recorded sweeps.
//
//   urban_detection_fit_density [--yaml OUT.yaml] [--png OUT.png] [--max-weight W]
//                               [--degree 6] DIR_OR_FILE...
//
// DIR_OR_FILE: directories of KITTI .bin or PCD sweeps (e.g. ../shared/data/kitti_raw/*), or
// single files. Density per 1 m ring of horizontal distance from 1 to 80 m, normalised by the
// ring area and by its maximum; least-squares polynomial fit of its logarithm (--linear: of
// the density itself, the paper's literal reading; see distance_weight.h); prints and writes the
// YAML `weight:` block of config/hierarchical_grid.yaml and a PNG of density, fit and resulting
// weight.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "tool_common.h"
#include "urban_detection/core/detection/distance_weight.h"

using namespace urban_detection;

int main(int argc, char** argv) {
  std::string yaml_path, png_path;
  double max_weight = core::DistanceWeightParams().max_weight;
  int degree = 6;
  bool log_fit = true;
  std::vector<std::string> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--yaml" && i + 1 < argc) {
      yaml_path = argv[++i];
    } else if (a == "--png" && i + 1 < argc) {
      png_path = argv[++i];
    } else if (a == "--max-weight" && i + 1 < argc) {
      max_weight = std::atof(argv[++i]);
    } else if (a == "--degree" && i + 1 < argc) {
      degree = std::atoi(argv[++i]);
    } else if (a == "--linear") {
      log_fit = false;
    } else if (a == "-h" || a == "--help" || a.rfind("--", 0) == 0) {
      std::fprintf(stderr,
                   "usage: %s [--yaml OUT.yaml] [--png OUT.png] [--max-weight W] [--degree N] "
                   "[--linear] DIR_OR_FILE...\n",
                   argv[0]);
      return a == "-h" || a == "--help" ? 0 : 2;
    } else {
      inputs.push_back(a);
    }
  }
  if (inputs.empty() || degree < 1 || degree > 12 || !(max_weight >= 1.0)) {
    std::fprintf(stderr, "need at least one input, degree in [1, 12], max weight >= 1\n");
    return 2;
  }

  core::RingDensity rings(1.0, 80.0, 1.0);
  CloudXYZIRT cloud;
  std::size_t files = 0;
  for (const std::string& in : inputs) {
    const std::vector<std::string> sweeps = tools::listSweeps(in);
    if (sweeps.empty()) std::fprintf(stderr, "warning: no .bin/.pcd sweep in %s\n", in.c_str());
    for (const std::string& f : sweeps) {
      std::string err;
      if (!tools::readSweep(f, &cloud, &err)) {
        std::fprintf(stderr, "warning: skipping %s: %s\n", f.c_str(), err.c_str());
        continue;
      }
      rings.add(cloud);
      ++files;
    }
  }
  if (files == 0) {
    std::fprintf(stderr, "no sweep could be read\n");
    return 1;
  }

  const std::vector<double> density = rings.density();
  const std::vector<double> norm = rings.normalisedDensity();
  std::vector<double> d(rings.rings());
  std::size_t imax = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    d[i] = rings.ringCenter(i);
    if (norm[i] > norm[imax]) imax = i;
  }
  // Empty rings (possible with few sweeps) have no logarithm: they are left out of the fit.
  std::vector<double> fx, fy;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (log_fit && !(norm[i] > 0.0)) continue;
    fx.push_back(d[i]);
    fy.push_back(log_fit ? std::log(norm[i]) : norm[i]);
  }
  const std::vector<double> c = core::fitPolynomial(fx, fy, degree);
  if (c.empty()) {
    std::fprintf(stderr, "fit failed\n");
    return 1;
  }
  core::DistanceWeightParams wp;
  wp.coefficients = c;
  wp.log_fit = log_fit;
  {
    // d0: the maximum of the fitted density (0.1 m steps over the fitted range).
    core::DistanceWeightParams probe = wp;
    probe.coefficients = c;
    probe.log_fit = log_fit;
    const core::DistanceWeight f(probe);
    double best = -1e300;
    for (double x = d.front(); x <= d.back(); x += 0.1) {
      if (f.fitted(x) > best) {
        best = f.fitted(x);
        wp.full_density_distance_m = std::round(x * 10.0) / 10.0;
      }
    }
  }
  std::printf("# densest measured ring at %.1f m, fitted density maximum at %.1f m\n", d[imax],
              wp.full_density_distance_m);
  wp.max_distance_m = 80.0;
  wp.max_weight = max_weight;
  const core::DistanceWeight weight(wp);

  std::printf("# %zu sweeps; ring [m]  points/m^2/sweep  normalised  fit  weight\n", files);
  double rms = 0.0;
  auto fitted = [&](double x) {
    const double p = core::evalPolynomial(c, x);
    return log_fit ? std::exp(p) : p;
  };
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double f = fitted(d[i]);
    rms += (f - norm[i]) * (f - norm[i]);
    std::printf("%5.1f %12.4f %10.5f %9.5f %8.3f\n", d[i], density[i], norm[i], f,
                weight.exact(d[i]));
  }
  rms = std::sqrt(rms / d.size());

  char buf[4096];
  std::string yaml = "# urban_detection_fit_density on " + std::to_string(files) +
                     " sweeps; fit rms " + std::to_string(rms) + "\n";
  yaml += std::string("weight:\n  enabled: true\n  log_fit: ") + (log_fit ? "true" : "false") +
          "\n  coefficients: [";
  for (std::size_t k = 0; k < c.size(); ++k) {
    std::snprintf(buf, sizeof(buf), "%s%.10e", k ? ", " : "", c[k]);
    yaml += buf;
  }
  std::snprintf(buf, sizeof(buf),
                "]\n  full_density_distance_m: %.1f\n  max_distance_m: %.1f\n  max_weight: %.1f\n",
                wp.full_density_distance_m, wp.max_distance_m, wp.max_weight);
  yaml += buf;
  std::printf("\n%s", yaml.c_str());
  if (!yaml_path.empty()) {
    std::ofstream(yaml_path) << yaml;
    std::printf("wrote %s\n", yaml_path.c_str());
  }
  if (!png_path.empty()) {
    // log10 axes: the density spans four decades between 5 and 80 m.
    std::vector<double> ld, fit(d.size()), w(d.size()), dd;
    for (std::size_t i = 0; i < d.size(); ++i) {
      if (norm[i] > 0.0) {
        dd.push_back(d[i]);
        ld.push_back(std::log10(norm[i]));
      }
      fit[i] = std::log10(std::max(fitted(d[i]), 1e-5));
      w[i] = std::log10(weight.exact(d[i]));
    }
    const bool ok =
        tools::plotSeries(png_path, "log10: normalised ring density, polynomial fit, weight w(d)",
                          "horizontal distance from the sensor [m]",
                          {{dd, ld, cv::Scalar(200, 80, 0), "normalised density (rings)", true},
                           {d, fit, cv::Scalar(0, 0, 220), "fitted density", false},
                           {d, w, cv::Scalar(0, 150, 0), "weight w(d) (clamped)", false}},
                          -5.0, 4.0);
    std::printf(ok ? "wrote %s\n" : "could not write %s\n", png_path.c_str());
  }
  return 0;
}
