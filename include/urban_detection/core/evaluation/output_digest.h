/// \file output_digest.h
/// Digests of the detectors' outputs, to check that a speed change leaves them bit-identical
/// (urban_detection_bench_detection --digest): 64-bit FNV-1a over the bytes of every output
/// field, frame by frame. ROS-free.
#pragma once

#include <cstdint>
#include <cstdio>
#include <vector>

#include <Eigen/Core>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

/// FNV-1a over the bytes of the values added.
class Fnv1aDigest {
 public:
  template <typename T>
  void add(const T& v) {
    const unsigned char* b = reinterpret_cast<const unsigned char*>(&v);
    for (std::size_t i = 0; i < sizeof(T); ++i) h_ = (h_ ^ b[i]) * 1099511628211ull;
  }
  void add(const Eigen::Vector3f& v) {
    for (int i = 0; i < 3; ++i) add(v[i]);
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 14695981039346656037ull;
};

/// The digest of `det` run on every frame: per frame the object count, then per object its
/// id, index count, indices and the bit patterns of centroid, box, oriented box and yaw. With
/// `dump`, also one text line per object (frame, id, point count, then the 16 box floats with
/// 9 significant digits) to compare two builds field by field.
std::uint64_t detectionsDigest(ObjectDetector* det, const std::vector<LabeledCloud>& frames,
                               std::FILE* dump = nullptr);

}  // namespace core
}  // namespace urban_detection
