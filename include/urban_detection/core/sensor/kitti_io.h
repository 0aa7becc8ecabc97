/// \file kitti_io.h
/// Readers for KITTI / SemanticKITTI files: velodyne .bin scans, SemanticKITTI .label files
/// and the binary PCD sweeps of the shared data. ROS-free; they never print, they return false
/// and say why in `error`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Reads a KITTI velodyne scan (float32 x y z reflectance per point, little endian). KITTI's
/// reflectance in [0, 1] is scaled to intensity [0, 255]; ring and time are set to 0.
/// Returns false (cloud cleared) if the file is missing or its size is not a multiple of 16.
bool readKittiBin(const std::string& path, CloudXYZIRT* cloud, std::string* error = nullptr);

/// Reads a SemanticKITTI .label file (uint32 per point: low 16 bits semantic class, high 16
/// bits instance id).
bool readSemanticKittiLabels(const std::string& path, std::vector<std::uint32_t>* labels,
                             std::string* error = nullptr);

/// Reads a PCD file with at least x y z (intensity optional) into a CloudXYZIRT (ring, time 0).
/// Intensity is copied as stored.
bool readPcdXyzi(const std::string& path, CloudXYZIRT* cloud, std::string* error = nullptr);

/// SemanticKITTI semantic ids used by the evaluations (moving classes 252-259 map to the
/// static ones via semanticKittiStaticClass()).
namespace semantic_kitti {
constexpr std::uint16_t kUnlabeled = 0, kOutlier = 1, kCar = 10, kBicycle = 11, kMotorcycle = 15,
                        kTruck = 18, kOtherVehicle = 20, kPerson = 30, kBicyclist = 31,
                        kMotorcyclist = 32, kRoad = 40, kParking = 44, kSidewalk = 48,
                        kOtherGround = 49, kBuilding = 50, kFence = 51, kOtherStructure = 52,
                        kLaneMarking = 60, kVegetation = 70, kTrunk = 71, kTerrain = 72, kPole = 80,
                        kTrafficSign = 81, kOtherObject = 99;
}  // namespace semantic_kitti

/// Maps a SemanticKITTI semantic id (low 16 bits of a label) to its static class: moving-car
/// 252 -> 10, moving-bicyclist 253 -> 31, moving-person 254 -> 30, moving-motorcyclist 255 ->
/// 32, moving-on-rails 256 -> 20, moving-bus 257 -> 20, moving-truck 258 -> 18,
/// moving-other-vehicle 259 -> 20. Other ids are returned unchanged.
std::uint16_t semanticKittiStaticClass(std::uint32_t label);

/// True for the SemanticKITTI ground classes: road, parking, sidewalk, other-ground,
/// lane-marking, terrain.
bool isSemanticKittiGround(std::uint16_t static_class);

}  // namespace core
}  // namespace urban_detection
