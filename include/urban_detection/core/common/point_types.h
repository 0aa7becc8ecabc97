/// \file point_types.h
/// Point types shared by every stage of the pipeline (ROS-free).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#define PCL_NO_PRECOMPILE
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace urban_detection {

/// A decoded Velodyne return. Field names (x y z intensity ring time) match
/// velodyne_pointcloud's XYZIRT so existing tools and rviz configs work unchanged.
struct EIGEN_ALIGN16 PointXYZIRT {
  PCL_ADD_POINT4D;     // [m] x, y, z in the sensor (or target) frame
  float intensity;     // [0..255] calibrated intensity
  std::uint16_t ring;  // laser index ordered by vertical angle, 0 = lowest beam
  float time;          // [s] time of the firing relative to the revolution start
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};

/// A point carrying a label and the index of the point in the cloud it came from.
/// `label` is a SegmentClass value on segmentation outputs and an object id on detector
/// outputs; `index` is the position of the point in the input cloud of the segmentation,
/// so detections can be matched to per-point ground truth.
struct EIGEN_ALIGN16 LabeledPoint {
  PCL_ADD_POINT4D;      // [m]
  float intensity;      // [0..255]
  std::uint32_t label;  // class or object id, see above
  std::uint32_t index;  // index into the input cloud
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};

namespace detail {
/// A point of type PointT with x, y, z, intensity and the fourth coordinate 1 (as PCL's own
/// points have it); the type's other fields are left to the caller.
template <typename PointT>
inline PointT pointXyzi(float x, float y, float z, float intensity) {
  PointT p;
  p.x = x;
  p.y = y;
  p.z = z;
  p.data[3] = 1.0f;
  p.intensity = intensity;
  return p;
}
}  // namespace detail

/// A return with every field set.
inline PointXYZIRT makePoint(float x, float y, float z, float intensity = 0.0f,
                             std::uint16_t ring = 0, float time = 0.0f) {
  PointXYZIRT p = detail::pointXyzi<PointXYZIRT>(x, y, z, intensity);
  p.ring = ring;
  p.time = time;
  return p;
}

/// A labelled point with every field set.
inline LabeledPoint makeLabeledPoint(float x, float y, float z, std::uint32_t label,
                                     std::uint32_t index, float intensity = 0.0f) {
  LabeledPoint p = detail::pointXyzi<LabeledPoint>(x, y, z, intensity);
  p.label = label;
  p.index = index;
  return p;
}

using CloudXYZIRT = pcl::PointCloud<PointXYZIRT>;
using LabeledCloud = pcl::PointCloud<LabeledPoint>;

/// True when x, y and z are all finite (no NaN, no infinity).
template <typename PointT>
inline bool isFinitePoint(const PointT& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

}  // namespace urban_detection

POINT_CLOUD_REGISTER_POINT_STRUCT(urban_detection::PointXYZIRT,
                                  (float, x, x)(float, y, y)(float, z,
                                                             z)(float, intensity,
                                                                intensity)(std::uint16_t, ring,
                                                                           ring)(float, time, time))

POINT_CLOUD_REGISTER_POINT_STRUCT(urban_detection::LabeledPoint,
                                  (float, x, x)(float, y, y)(float, z, z)(float, intensity,
                                                                          intensity)(
                                      std::uint32_t, label, label)(std::uint32_t, index, index))
