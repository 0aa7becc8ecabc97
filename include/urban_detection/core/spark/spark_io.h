/// \file spark_io.h
/// The files of the offline SPARK workflow (urban_detection_spark): clouds in (PCD with
/// optional rgb / intensity, or KITTI .bin) and coloured sub-clouds out, class colours and
/// names for label images a person looks at. ROS-free.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/spark/camera_model.h"

namespace urban_detection {
namespace core {

/// Reads a cloud: KITTI .bin (x y z reflectance), else PCD (x y z, with intensity and rgb /
/// rgba fields when present; `rgb` gets one BGR colour per point then, else stays empty).
bool readSparkCloud(const std::string& path, CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb,
                    std::string* error);

/// Writes the points `indices` of `cloud` as a PCD x y z rgb (binary; ASCII when empty), each
/// with its colour in `rgb` (BGR), grey where `rgb` has none. Returns false on failure.
bool writeColouredCloud(const std::string& path, const CloudXYZIRT& cloud,
                        const std::vector<cv::Vec3b>& rgb,
                        const std::vector<std::uint32_t>& indices);

/// The BGR colour of every class id 0..255: line n of `colours_file` ("r g b" or "r,g,b";
/// malformed lines skipped) for class n, a fixed palette after it (or for all without a
/// file), black for 255 (no class). False when the file cannot be read.
bool classColours(const std::string& colours_file, std::vector<cv::Vec3b>* colours,
                  std::string* error);

/// A label image (8-bit class ids) as colours (classColours()).
cv::Mat colourMask(const cv::Mat& labels, const std::vector<cv::Vec3b>& colours);

/// The name of class `id`: names[id] when there is one, "unknown" below 0, else "class_<id>".
std::string sparkClassName(const std::vector<std::string>& names, int id);

/// The model options of urban_detection_spark over the camera stage's parameters (read from
/// --model-config first): --model NET, --model-dir DIR, --colours FILE (into `colours_file`),
/// --classes FILE, --keep a,b, --input-size WxH, --mean r,g,b, --scale r,g,b, and the flags
/// --bgr and --probabilities; --model-config's value is taken and ignored. `value` gives the
/// option's value (called only for options that take one). Returns 1 when `option` is one of
/// them (applied), 0 when it is not, -1 with `error` for a malformed value.
int applyCameraModelOption(const std::string& option, const std::function<std::string()>& value,
                           CameraStageParams* stage, std::string* colours_file, std::string* error);

/// The non-empty items of a comma-separated list ("a,,b" -> {"a", "b"}).
std::vector<std::string> splitCommaList(const std::string& s);

}  // namespace core
}  // namespace urban_detection
