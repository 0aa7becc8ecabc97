#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

ObjectCategory categoryOfClassName(const std::string& name) {
  static const char* const kVehicles[] = {"car",
                                          "truck",
                                          "bus",
                                          "other-vehicle",
                                          "on-rails",
                                          "moving-car",
                                          "moving-bus",
                                          "moving-truck",
                                          "moving-other-vehicle",
                                          "moving-on-rails",
                                          "Car",
                                          "Van",
                                          "Truck",
                                          "Tram",
                                          "van",
                                          "vehicle"};
  static const char* const kPedestrians[] = {"person", "moving-person", "Pedestrian",
                                             "Person_sitting", "pedestrian"};
  static const char* const kCyclists[] = {"bicyclist",  "motorcyclist",     "bicycle",
                                          "motorcycle", "moving-bicyclist", "moving-motorcyclist",
                                          "Cyclist",    "cyclist"};
  static const char* const kOthers[] = {"other-object", "Misc", "bin", "bench", "other_object"};
  for (const char* n : kVehicles) {
    if (name == n) return ObjectCategory::kVehicle;
  }
  for (const char* n : kPedestrians) {
    if (name == n) return ObjectCategory::kPedestrian;
  }
  for (const char* n : kCyclists) {
    if (name == n) return ObjectCategory::kCyclist;
  }
  for (const char* n : kOthers) {
    if (name == n) return ObjectCategory::kOtherObject;
  }
  return ObjectCategory::kUnknown;
}

}  // namespace core
}  // namespace urban_detection
