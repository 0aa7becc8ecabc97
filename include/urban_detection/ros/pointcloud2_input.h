/// \file pointcloud2_input.h
/// Conversion of any sensor_msgs/PointCloud2 carrying x y z (and optionally intensity, ring,
/// time) to a CloudXYZIRT, by field name, so KITTI bags (x y z intensity only) are accepted
/// without PCL's per-message "failed to find match for field" warnings.
#pragma once

#include <cstddef>
#include <string>

#include <sensor_msgs/PointCloud2.h>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace ros_conv {

/// What fromPointCloud2 found in the message.
struct PointCloud2InputInfo {
  bool has_intensity = false;
  bool has_ring = false;
  bool has_time = false;
  std::size_t non_finite = 0;  // points with a NaN or infinite x, y or z (kept, see below)
};

/// Converts `msg` to `cloud` (header copied, stamp in microseconds as PCL does). Fields are
/// looked up by name and may be of any numeric PointField type; missing intensity, ring or time
/// are filled with 0. Returns false with a reason in `error` (and `cloud` cleared) when x, y or
/// z is missing (the fields present are listed), the message is big endian, or its data is
/// shorter than its declared size. Non-finite points are kept (indices stay those of `msg`)
/// and counted; the segmenter labels them unknown, so they never reach the detectors.
bool fromPointCloud2(const sensor_msgs::PointCloud2& msg, CloudXYZIRT* cloud,
                     PointCloud2InputInfo* info, std::string* error);

}  // namespace ros_conv
}  // namespace urban_detection
