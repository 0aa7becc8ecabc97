/// \file object_class.h
/// Ground-truth classes of the simulated urban scene (ROS-free).
///
/// Every surface of the simulator carries one of these classes, and every simulated return is
/// labelled with the class of the surface it hit. Values are stable: they are written into the
/// ground-truth file and into urban_detection/GroundTruth messages (whose constants mirror them).
#pragma once

#include <cstdint>

namespace urban_detection {
namespace core {

/// Class of a scene surface / of a ground-truth point.
enum class ObjectClass : std::uint8_t {
  kUnlabeled = 0,   // not a scene surface (never emitted for a real return)
  kGround = 1,      // road, curb, sidewalk, paved ground
  kWall = 2,        // building facades
  kVegetation = 3,  // tree crowns, hedges, bushes
  kTrunk = 4,       // tree trunks
  kPole = 5,        // lamp posts, sign posts
  kSign = 6,        // traffic-sign plates
  kCar = 7,         // passenger cars
  kVan = 8,         // vans
  kPedestrian = 9,  // pedestrians
  kCyclist = 10,    // cyclists with their bicycle
  kBin = 11,        // waste bins
  kBench = 12,      // benches
  kTerrain = 13,    // natural ground: grass verges, lawns, garden beds
};

/// Number of classes (one past the largest value).
constexpr int kNumObjectClasses = 14;

/// Lower-case name of a class ("car", "pedestrian", ...); "unlabeled" for unknown values.
inline const char* toString(ObjectClass c) {
  switch (c) {
    case ObjectClass::kGround:
      return "ground";
    case ObjectClass::kWall:
      return "wall";
    case ObjectClass::kVegetation:
      return "vegetation";
    case ObjectClass::kTrunk:
      return "trunk";
    case ObjectClass::kPole:
      return "pole";
    case ObjectClass::kSign:
      return "sign";
    case ObjectClass::kCar:
      return "car";
    case ObjectClass::kVan:
      return "van";
    case ObjectClass::kPedestrian:
      return "pedestrian";
    case ObjectClass::kCyclist:
      return "cyclist";
    case ObjectClass::kBin:
      return "bin";
    case ObjectClass::kBench:
      return "bench";
    case ObjectClass::kTerrain:
      return "terrain";
    default:
      return "unlabeled";
  }
}

/// True for the short street objects the detectors of paper Sec. 3.2 must find (vehicles,
/// pedestrians, cyclists, bins, benches). Tall structures (trees, poles, signs, walls), the
/// ground and the low vegetation and terrain (hedges, bushes, grass) are not, as in the paper's
/// segmentation (Sec. 3.1).
inline bool isStreetObject(ObjectClass c) {
  switch (c) {
    case ObjectClass::kCar:
    case ObjectClass::kVan:
    case ObjectClass::kPedestrian:
    case ObjectClass::kCyclist:
    case ObjectClass::kBin:
    case ObjectClass::kBench:
      return true;
    default:
      return false;
  }
}

}  // namespace core
}  // namespace urban_detection
