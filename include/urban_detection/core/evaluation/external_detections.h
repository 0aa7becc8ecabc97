/// \file external_detections.h
/// Another system's output as a detector (urban_detection_eval --detections DIR): per frame,
/// one uint32 per input point, the point's instance (0 = none); each instance is one detection
/// (centroid, axis-aligned bounds and box). Files: DIR/<frame id>.label, or for SemanticKITTI
/// ids "SEQ/NNNNNN" also DIR/sequences/SEQ/predictions/NNNNNN.label. ROS-free.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/evaluation/datasets.h"

namespace urban_detection {
namespace core {

class ExternalDetections : public ObjectDetector {
 public:
  explicit ExternalDetections(const std::string& dir) : dir_(dir) {}
  std::string name() const override { return "external"; }

  /// Reads the labels of frame `f` (which must outlive the next detect()); false with `error`
  /// set when the file is missing or its size is not one uint32 per point of the frame's
  /// cloud.
  bool load(const Frame& f, std::string* error);

  /// The instances of the loaded frame (the foreground is not used).
  void detect(const LabeledCloud& foreground, std::vector<DetectedObject>* objects) override;

 private:
  std::string dir_;
  std::vector<std::uint32_t> labels_;
  const CloudXYZIRT* cloud_ = nullptr;
};

}  // namespace core
}  // namespace urban_detection
