/// \file class_evidence.h
/// The class of a track as the accumulated evidence of its detections' classes. ROS-free.
///
/// Each detection's class probabilities are multiplied into the track's (summed as logs: a
/// naive-Bayes vote with a uniform prior, the detections taken as independent). A detection
/// carries its class and that class's probability p (DetectedObject::category,
/// class_confidence); the other classes share 1 - p evenly. Probabilities are clamped to
/// [kMinProbability, 1 - kMinProbability] so that one confident detection cannot veto the
/// rest, and the log evidence of each class is kept within kMaxLogSpread of the best one so
/// that a track whose detections change class (a far car first seen as "other object") comes
/// round within a few revolutions instead of never.
#pragma once

#include <array>
#include <cstdint>

#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

class ClassEvidence {
 public:
  static constexpr int kClasses = 5;  // ObjectCategory values 0..4
  static constexpr double kMinProbability = 0.02;
  static constexpr double kMaxLogSpread = 12.0;

  /// Adds one detection of class `category` with probability `confidence` [0..1] (NaN: 0).
  /// kUnknown (unclassified) adds nothing.
  void add(ObjectCategory category, float confidence);
  /// The class with the most evidence; kUnknown before any classified detection.
  ObjectCategory category() const;
  /// Posterior probability of category() [0..1] (0 before any classified detection).
  float probability() const;
  std::uint32_t count() const { return count_; }  // classified detections added

 private:
  std::array<double, kClasses> log_p_{};  // [log] summed log probabilities
  std::uint32_t count_ = 0;
};

}  // namespace core
}  // namespace urban_detection
