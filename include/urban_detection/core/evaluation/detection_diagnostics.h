/// \file detection_diagnostics.h
/// Why the detection scoring went as it did (urban_detection_eval --details): each missed
/// ground-truth object gets a cause (its points not in the foreground and what the segmenter
/// called them; the classifier rejected it; the detector dropped, merged or split it; partly
/// foreground) and each false detection what its points are (detectionContent()), with the
/// kind of fragment when they belong to a ground-truth object (merge, leftover of a matched
/// object, most of / piece of a missed one). ROS-free.
#pragma once

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace core {

/// Counts over the frames.
struct DetectionDiagnostics {
  std::map<std::string, std::size_t> missed_by_cause;
  std::map<std::string, std::size_t> false_by_class;
  std::map<std::string, std::size_t> false_fragments;  ///< false parts of GT objects, by kind
};

/// Explains each missed GT object and each false detection of one frame (`seg`: the segment
/// class per point; `dets` scored as `m`; `classifier_rejected`: the detections the classifier
/// dropped); appends to `diag` and, when `out` is not null, prints one line per object.
void diagnose(const Frame& f, const Dataset& ds, const std::vector<SegmentClass>& seg,
              const std::vector<DetectedObject>& dets, const FrameMatch& m,
              const std::vector<DetectedObject>& classifier_rejected, const std::string& detector,
              DetectionDiagnostics* diag, std::FILE* out);

}  // namespace core
}  // namespace urban_detection
