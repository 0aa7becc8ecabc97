/// \file segment_class.h
/// Classes of the simple-grid segmentation (paper Sec. 3.1), ROS-free.
#pragma once

#include <cstdint>

namespace urban_detection {
namespace core {

/// Per-point and per-cell class. Values are stable: they are written into the `label` field
/// of `segmentation/labeled_points` and coloured by rviz.
enum class SegmentClass : std::uint8_t {
  kUnknown = 0,  // not assigned (e.g. non-finite point)
  kClutter = 1,  // too few points in the cell
  kGround = 2,   // road, sidewalk, terrain
  kTall = 3,     // walls, facades, poles, trunks: background for detection
  kShort = 4,    // short street objects: the foreground of the detectors
};

inline const char* toString(SegmentClass c) {
  switch (c) {
    case SegmentClass::kClutter:
      return "clutter";
    case SegmentClass::kGround:
      return "ground";
    case SegmentClass::kTall:
      return "tall";
    case SegmentClass::kShort:
      return "short";
    default:
      return "unknown";
  }
}

}  // namespace core
}  // namespace urban_detection
