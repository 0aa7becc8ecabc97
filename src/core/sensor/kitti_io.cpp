#include "urban_detection/core/sensor/kitti_io.h"

#include <cstring>
#include <fstream>

#include <pcl/io/pcd_io.h>

namespace urban_detection {
namespace core {

namespace {

bool fail(std::string* error, const std::string& msg) {
  if (error) *error = msg;
  return false;
}

// Reads a whole binary file; false if it cannot be opened.
bool readAll(const std::string& path, std::vector<char>* bytes) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const std::streamsize size = in.tellg();
  if (size < 0) return false;
  bytes->resize(static_cast<std::size_t>(size));
  in.seekg(0);
  return size == 0 || static_cast<bool>(in.read(bytes->data(), size));
}

}  // namespace

bool readKittiBin(const std::string& path, CloudXYZIRT* cloud, std::string* error) {
  cloud->clear();
  std::vector<char> bytes;
  if (!readAll(path, &bytes)) return fail(error, "cannot read " + path);
  if (bytes.size() % (4 * sizeof(float)) != 0) {
    return fail(error, path + ": size " + std::to_string(bytes.size()) +
                           " is not a multiple of 16 bytes (float32 x y z reflectance)");
  }
  const std::size_t n = bytes.size() / (4 * sizeof(float));
  cloud->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    float v[4];
    std::memcpy(v, bytes.data() + i * sizeof(v), sizeof(v));
    PointXYZIRT& p = (*cloud)[i];
    p.x = v[0];
    p.y = v[1];
    p.z = v[2];
    p.intensity = v[3] * 255.0f;
    p.ring = 0;
    p.time = 0.0f;
  }
  cloud->width = static_cast<std::uint32_t>(n);
  cloud->height = 1;
  cloud->is_dense = false;
  return true;
}

bool readSemanticKittiLabels(const std::string& path, std::vector<std::uint32_t>* labels,
                             std::string* error) {
  labels->clear();
  std::vector<char> bytes;
  if (!readAll(path, &bytes)) return fail(error, "cannot read " + path);
  if (bytes.size() % sizeof(std::uint32_t) != 0) {
    return fail(error, path + ": size is not a multiple of 4 bytes (uint32 labels)");
  }
  labels->resize(bytes.size() / sizeof(std::uint32_t));
  if (!bytes.empty()) std::memcpy(labels->data(), bytes.data(), bytes.size());
  return true;
}

bool readPcdXyzi(const std::string& path, CloudXYZIRT* cloud, std::string* error) {
  cloud->clear();
  pcl::PointCloud<pcl::PointXYZI> xyzi;
  pcl::PCDReader reader;
  if (reader.read(path, xyzi) != 0) return fail(error, "cannot read PCD " + path);
  cloud->resize(xyzi.size());
  for (std::size_t i = 0; i < xyzi.size(); ++i) {
    PointXYZIRT& p = (*cloud)[i];
    p.x = xyzi[i].x;
    p.y = xyzi[i].y;
    p.z = xyzi[i].z;
    p.intensity = xyzi[i].intensity;
    p.ring = 0;
    p.time = 0.0f;
  }
  cloud->width = static_cast<std::uint32_t>(xyzi.size());
  cloud->height = 1;
  cloud->is_dense = xyzi.is_dense;
  return true;
}

std::uint16_t semanticKittiStaticClass(std::uint32_t label) {
  const std::uint16_t c = static_cast<std::uint16_t>(label & 0xFFFFu);
  switch (c) {
    case 252:
      return semantic_kitti::kCar;
    case 253:
      return semantic_kitti::kBicyclist;
    case 254:
      return semantic_kitti::kPerson;
    case 255:
      return semantic_kitti::kMotorcyclist;
    case 256:
      return semantic_kitti::kOtherVehicle;
    case 257:
      return semantic_kitti::kOtherVehicle;
    case 258:
      return semantic_kitti::kTruck;
    case 259:
      return semantic_kitti::kOtherVehicle;
    default:
      return c;
  }
}

bool isSemanticKittiGround(std::uint16_t c) {
  namespace sk = semantic_kitti;
  return c == sk::kRoad || c == sk::kParking || c == sk::kSidewalk || c == sk::kOtherGround ||
         c == sk::kLaneMarking || c == sk::kTerrain;
}

}  // namespace core
}  // namespace urban_detection
