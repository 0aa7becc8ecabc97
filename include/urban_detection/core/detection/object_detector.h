/// \file object_detector.h
/// The one interface shared by the interchangeable object detectors (hierarchical grid,
/// kd-tree baseline), so nodelets, the benchmark and the evaluator take either. ROS-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Class of a detected object, set by the ObjectClassifier (object_classifier.h). Values 0..4
/// are the classifier model's class numbers (stable: they are stored in model files).
enum class ObjectCategory : std::uint8_t {
  kNonObject = 0,    // vegetation, terrain, building, fence, other structure
  kVehicle = 1,      // cars, vans, trucks, buses, trams, other vehicles
  kPedestrian = 2,   // people on foot
  kCyclist = 3,      // riders and their bicycles or motorcycles, parked two-wheelers
  kOtherObject = 4,  // other street objects (bins, benches, boxes, ...)
  kUnknown = 255,    // not classified
};

/// Lower-case class name ("non_object", "vehicle", "pedestrian", "cyclist", "other_object";
/// "unknown" for kUnknown and any other value).
inline const char* toString(ObjectCategory c) {
  switch (c) {
    case ObjectCategory::kNonObject:
      return "non_object";
    case ObjectCategory::kVehicle:
      return "vehicle";
    case ObjectCategory::kPedestrian:
      return "pedestrian";
    case ObjectCategory::kCyclist:
      return "cyclist";
    case ObjectCategory::kOtherObject:
      return "other_object";
    default:
      return "unknown";
  }
}

/// The classifier's class of a dataset's object class name: SemanticKITTI ("car", "truck",
/// "moving-person", "bicyclist", "other-object", ...), KITTI object ("Car", "Van",
/// "Pedestrian", "Cyclist", "Misc", ...) and the simulator ("car", "van", "pedestrian",
/// "cyclist", "bin", "bench"). kUnknown for anything else (poles, trunks, signs, DontCare).
ObjectCategory categoryOfClassName(const std::string& name);

/// One detected urban object: a distinct group of foreground points.
struct DetectedObject {
  std::uint32_t id = 0;                // 1.. within one frame
  std::vector<std::uint32_t> indices;  // indices of its points in the segmented input cloud
                                       // (the `index` field of the foreground points)
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();    // [m]
  Eigen::Vector3f min_pt = Eigen::Vector3f::Zero();      // [m] axis-aligned box corner
  Eigen::Vector3f max_pt = Eigen::Vector3f::Zero();      // [m] axis-aligned box corner
  Eigen::Vector3f obb_center = Eigen::Vector3f::Zero();  // [m] yaw-oriented box centre
  Eigen::Vector3f obb_size = Eigen::Vector3f::Zero();    // [m] length (along yaw), width, height
  float obb_yaw_rad = 0.0f;                              // [rad] about z
  ObjectCategory category = ObjectCategory::kUnknown;    // set by the ObjectClassifier
  float class_confidence = 0.0f;                         // [0..1] probability of `category`
};

/// Numbers objects 1..N in their order, as the detectors do (after a stage removed some).
inline void renumberObjects(std::vector<DetectedObject>* objects) {
  for (std::size_t k = 0; k < objects->size(); ++k) {
    (*objects)[k].id = static_cast<std::uint32_t>(k + 1);
  }
}

/// Finds objects in a foreground cloud (short street object points of the segmentation).
class ObjectDetector {
 public:
  virtual ~ObjectDetector() = default;
  /// Short stable name ("hierarchical_grid", "kdtree").
  virtual std::string name() const = 0;
  /// `foreground` points carry `index` = index in the segmented input cloud; non-finite points
  /// are ignored. `objects` is cleared and filled; ids are 1..N in output order.
  virtual void detect(const LabeledCloud& foreground, std::vector<DetectedObject>* objects) = 0;
};

}  // namespace core
}  // namespace urban_detection
