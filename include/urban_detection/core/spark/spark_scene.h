/// \file spark_scene.h
/// A small coloured street scene with known object classes for the SPARK tests, the tool's
/// --synthetic demo and its benchmark: a grey ground plane, red cars, a green tree crown and a
/// blue pole, colours matching test/spark_colour_model.py (class ids 1 car, 2 vegetation,
/// 3 pole). ROS-free.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// One object of the scene: its class id, true axis-aligned box and point range.
struct SparkSceneObject {
  int class_id = 0;                ///< 1 car, 2 vegetation, 3 pole
  Eigen::Vector3f min_pt, max_pt;  ///< [m] true box
  std::uint32_t first = 0;         ///< first point position in the cloud
  std::uint32_t count = 0;         ///< number of points (contiguous)
};

/// Builds the scene: ground (z = 0, x in [-5, 40], y in [-15, 15]) then the objects, with the
/// surface sampled every `step_m`. `rgb` receives one BGR colour per point.
void makeSparkScene(double step_m, CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb,
                    std::vector<SparkSceneObject>* objects);

}  // namespace core
}  // namespace urban_detection
