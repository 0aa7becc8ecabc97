/// \file foreground_index.h
/// Finds a foreground point from the input-cloud index a DetectedObject lists (the stages
/// after the detectors look up an object's points this way). ROS-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

class ForegroundIndex {
 public:
  /// Indexes `foreground` (points carry `index`, the position in the segmented cloud). Only
  /// the entries of the previous foreground are reset: no per-frame clearing of the table.
  void build(const LabeledCloud& foreground) {
    for (const std::uint32_t i : touched_) position_[i] = -1;
    touched_.clear();
    for (std::size_t k = 0; k < foreground.size(); ++k) {
      const std::uint32_t idx = foreground[k].index;
      if (idx >= position_.size()) {
        // Input clouds are at most a few 100k points; a corrupt huge index is not found.
        if (idx > (1u << 26)) continue;
        position_.resize(static_cast<std::size_t>(idx) + 1, -1);
      }
      position_[idx] = static_cast<std::int32_t>(k);
      touched_.push_back(idx);
    }
  }

  /// The point of `foreground` (the cloud given to build()) with this input-cloud index, or
  /// nullptr when it is not in the foreground.
  const LabeledPoint* find(const LabeledCloud& foreground, std::uint32_t index) const {
    if (index >= position_.size() || position_[index] < 0) return nullptr;
    return &foreground[static_cast<std::size_t>(position_[index])];
  }

 private:
  std::vector<std::int32_t> position_;  // input-cloud index -> foreground position, or -1
  std::vector<std::uint32_t> touched_;  // entries of position_ set for this foreground
};

}  // namespace core
}  // namespace urban_detection
