#include "urban_detection/core/spark/spark_scene.h"

#include <algorithm>
#include <cmath>

namespace urban_detection {
namespace core {

namespace {

void add(CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb, const Eigen::Vector3f& p,
         const cv::Vec3b& colour) {
  cloud->push_back(makePoint(p.x(), p.y(), p.z(), 100.0f));
  rgb->push_back(colour);
}

// Samples the five visible faces of a box (no bottom face).
void addBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, double step,
            const cv::Vec3b& colour, CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb) {
  const auto n = [step](float len) {
    return std::max(1, static_cast<int>(std::lround(len / step)));
  };
  const Eigen::Vector3f size = hi - lo;
  const int nx = n(size.x()), ny = n(size.y()), nz = n(size.z());
  for (int i = 0; i <= nx; ++i) {
    for (int j = 0; j <= ny; ++j) {  // top face
      add(cloud, rgb, {lo.x() + size.x() * i / nx, lo.y() + size.y() * j / ny, hi.z()}, colour);
    }
    for (int k = 0; k < nz; ++k) {  // faces at y = lo, y = hi
      const float z = lo.z() + size.z() * k / nz;
      add(cloud, rgb, {lo.x() + size.x() * i / nx, lo.y(), z}, colour);
      add(cloud, rgb, {lo.x() + size.x() * i / nx, hi.y(), z}, colour);
    }
  }
  for (int j = 1; j < ny; ++j) {
    for (int k = 0; k < nz; ++k) {  // faces at x = lo, x = hi
      const float z = lo.z() + size.z() * k / nz;
      add(cloud, rgb, {lo.x(), lo.y() + size.y() * j / ny, z}, colour);
      add(cloud, rgb, {hi.x(), lo.y() + size.y() * j / ny, z}, colour);
    }
  }
}

}  // namespace

void makeSparkScene(double step_m, CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb,
                    std::vector<SparkSceneObject>* objects) {
  cloud->clear();
  rgb->clear();
  objects->clear();
  const double step = std::max(step_m, 0.02);
  const cv::Vec3b grey(128, 128, 128), red(0, 0, 255), green(0, 200, 0), blue(220, 0, 0);
  for (double x = -5.0; x <= 40.0 + 1e-9; x += 2 * step) {
    for (double y = -15.0; y <= 15.0 + 1e-9; y += 2 * step) {
      add(cloud, rgb, {static_cast<float>(x), static_cast<float>(y), 0.0f}, grey);
    }
  }
  auto begin = [&](int class_id) {
    SparkSceneObject o;
    o.class_id = class_id;
    o.first = static_cast<std::uint32_t>(cloud->size());
    return o;
  };
  auto end = [&](SparkSceneObject o) {
    o.count = static_cast<std::uint32_t>(cloud->size()) - o.first;
    o.min_pt = Eigen::Vector3f::Constant(1e9f);
    o.max_pt = Eigen::Vector3f::Constant(-1e9f);
    for (std::uint32_t i = o.first; i < o.first + o.count; ++i) {
      const Eigen::Vector3f p((*cloud)[i].x, (*cloud)[i].y, (*cloud)[i].z);
      o.min_pt = o.min_pt.cwiseMin(p);
      o.max_pt = o.max_pt.cwiseMax(p);
    }
    objects->push_back(o);
  };
  // Two cars.
  for (const auto& [lo, hi] :
       {std::pair<Eigen::Vector3f, Eigen::Vector3f>{{10.0f, 4.1f, 0.0f}, {14.0f, 5.9f, 1.5f}},
        {{23.0f, -6.0f, 0.0f}, {27.2f, -4.2f, 1.4f}}}) {
    SparkSceneObject o = begin(1);
    addBox(lo, hi, step, red, cloud, rgb);
    end(o);
  }
  // A tree crown: sphere of radius 2 m centred 4 m above (18, 8).
  {
    SparkSceneObject o = begin(2);
    const Eigen::Vector3f c(18.0f, 8.0f, 4.0f);
    const double r = 2.0;
    const int rings = std::max(4, static_cast<int>(M_PI * r / step));
    for (int i = 0; i <= rings; ++i) {
      const double theta = M_PI * i / rings;
      const int around = std::max(1, static_cast<int>(2 * M_PI * r * std::sin(theta) / step));
      for (int j = 0; j < around; ++j) {
        const double phi = 2 * M_PI * j / around;
        add(cloud, rgb,
            c + Eigen::Vector3f(static_cast<float>(r * std::sin(theta) * std::cos(phi)),
                                static_cast<float>(r * std::sin(theta) * std::sin(phi)),
                                static_cast<float>(r * std::cos(theta))),
            green);
      }
    }
    end(o);
  }
  // A pole: cylinder of radius 0.15 m, 4 m high at (8, -4).
  {
    SparkSceneObject o = begin(3);
    const int around = 12;
    for (double z = 0.0; z <= 4.0 + 1e-9; z += step) {
      for (int j = 0; j < around; ++j) {
        const double phi = 2 * M_PI * j / around;
        add(cloud, rgb,
            {static_cast<float>(8.0 + 0.15 * std::cos(phi)),
             static_cast<float>(-4.0 + 0.15 * std::sin(phi)), static_cast<float>(z)},
            blue);
      }
    }
    end(o);
  }
  cloud->width = static_cast<std::uint32_t>(cloud->size());
  cloud->height = 1;
  cloud->is_dense = true;
}

}  // namespace core
}  // namespace urban_detection
