/// \file sweep_file.h
/// Reads one recorded LiDAR sweep from disk: KITTI velodyne `.bin` (float32 x y z reflectance)
/// or PCD (binary or ascii, float32 fields including x y z, optional intensity), as used by
/// ../shared/data/kitti_raw. ROS-free; for offline tools and tests.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/point_types.h"

namespace urban_detection {
namespace core {

/// Reads `path` (format chosen by extension: .bin or .pcd) into `cloud` (ring = 0, time = 0;
/// KITTI reflectance in [0, 1] is scaled to intensity [0, 255]). Returns "" on success or an
/// error message; on error `cloud` is left empty.
std::string readSweepFile(const std::string& path, CloudXYZIRT* cloud);

/// Sorted list of the .bin and .pcd files directly inside `dir` (empty if none or missing).
std::vector<std::string> listSweepFiles(const std::string& dir);

}  // namespace core
}  // namespace urban_detection
