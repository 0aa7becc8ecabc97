/// \file frame_picture.h
/// Debug pictures of the detection scoring (urban_detection_eval --png DIR): a top view of one
/// frame, the ground truth left (points in their object's class colour, don't-care grey,
/// background dimmed outside the foreground), the detections right (class colours, or one
/// colour per detection when unclassified); red boxes around false detections, yellow boxes
/// around missed objects. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"

namespace urban_detection {
namespace core {

/// The area shown.
struct PngView {
  double cx = 0.0, cy = 0.0, half_m = 30.0;  ///< [m] centre and half side of the view
  double px_per_m = 20.0;
};

/// Writes the picture of frame `f` (`fg`: its foreground; `dets` scored as `m`) to `path`.
/// Returns false when the image cannot be written.
bool writeFramePng(const std::string& path, const Frame& f, const LabeledCloud& fg,
                   const std::vector<DetectedObject>& dets, const FrameMatch& m, const PngView& v);

}  // namespace core
}  // namespace urban_detection
