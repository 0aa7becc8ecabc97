#include "urban_detection/core/spark/camera_fusion.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

namespace urban_detection {
namespace core {

const char* toString(FusionMode m) {
  switch (m) {
    case FusionMode::kLidar:
      return "lidar";
    case FusionMode::kCamera:
      return "camera";
    case FusionMode::kFused:
      return "fused";
  }
  return "fused";
}

bool parseFusionMode(const std::string& name, FusionMode* mode) {
  for (const FusionMode m : {FusionMode::kLidar, FusionMode::kCamera, FusionMode::kFused}) {
    if (name == toString(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Class id of `entry` (a name, case-insensitive, or a decimal id below names.size()), or -1.
int classIdOf(const std::string& entry, const std::vector<std::string>& names) {
  const std::string e = lower(entry);
  for (std::size_t i = 0; i < names.size(); ++i)
    if (!names[i].empty() && lower(names[i]) == e) return static_cast<int>(i);
  char* end = nullptr;
  const long v = std::strtol(entry.c_str(), &end, 10);
  if (!entry.empty() && end != nullptr && *end == '\0' && v >= 0 &&
      v < static_cast<long>(names.size()))
    return static_cast<int>(v);
  return -1;
}

}  // namespace

bool buildCameraClassMap(const std::vector<std::string>& names,
                         const std::vector<std::string>& vehicle,
                         const std::vector<std::string>& pedestrian,
                         const std::vector<std::string>& cyclist,
                         const std::vector<std::string>& other_object,
                         const std::vector<std::string>& background, CameraClassMap* map,
                         std::string* error) {
  map->category_of_class.assign(names.size(), ObjectCategory::kUnknown);
  const std::pair<const std::vector<std::string>*, ObjectCategory> lists[] = {
      {&vehicle, ObjectCategory::kVehicle},
      {&pedestrian, ObjectCategory::kPedestrian},
      {&cyclist, ObjectCategory::kCyclist},
      {&other_object, ObjectCategory::kOtherObject},
      {&background, ObjectCategory::kNonObject}};
  for (const auto& [list, category] : lists) {
    for (const std::string& entry : *list) {
      const int id = classIdOf(entry, names);
      if (id < 0) {
        *error = "camera class '" + entry + "' (listed for " + toString(category) +
                 ") is neither a class name of the names file nor an id in [0, " +
                 std::to_string(static_cast<long>(names.size()) - 1) + "]";
        return false;
      }
      ObjectCategory& slot = map->category_of_class[static_cast<std::size_t>(id)];
      if (slot != ObjectCategory::kUnknown) {
        *error = "camera class '" + entry + "' is listed for both " + toString(slot) + " and " +
                 toString(category);
        return false;
      }
      slot = category;
    }
  }
  return true;
}

std::string validate(const CameraFusionParams& p) {
  return checkFieldRanges(p);
}

CameraEvidence cameraEvidence(const float* class_scores, int class_bound, std::uint32_t visible,
                              const CameraClassMap& map) {
  CameraEvidence e;
  e.visible = visible;
  if (class_scores == nullptr || visible == 0) return e;
  std::array<float, kNumObjectCategories> sum{};
  for (int c = 0; c < class_bound; ++c) {
    const float s = class_scores[c];
    if (!(s > 0.0f)) continue;
    const ObjectCategory cat = map.categoryOf(c);
    if (cat == ObjectCategory::kUnknown) continue;
    sum[static_cast<std::size_t>(cat)] += s;
  }
  for (std::size_t k = 0; k < sum.size(); ++k) {
    e.share[k] = std::min(1.0f, sum[k] / static_cast<float>(visible));
    if (k != static_cast<std::size_t>(ObjectCategory::kNonObject) && e.share[k] > e.best_share) {
      e.best_share = e.share[k];
      e.best = static_cast<ObjectCategory>(k);
    }
  }
  return e;
}

FusedClass fuseObjectClass(ObjectCategory lidar, float lidar_p, const CameraEvidence& camera,
                           const CameraFusionParams& params) {
  FusedClass out;
  out.category = lidar;
  out.confidence = lidar_p;
  if (params.mode == FusionMode::kLidar ||
      camera.visible < static_cast<std::uint32_t>(std::max(params.min_visible_points, 1)))
    return out;
  out.camera_used = true;
  const float background = camera.background_share();
  if (params.mode == FusionMode::kCamera) {
    if (background >= params.veto_share ||
        (background > camera.best_share && background >= params.min_camera_share)) {
      out.category = ObjectCategory::kNonObject;
      out.confidence = background;
    } else if (camera.best != ObjectCategory::kUnknown &&
               camera.best_share >= params.min_camera_share) {
      out.category = camera.best;
      out.confidence = camera.best_share;
    } else {
      out.category = ObjectCategory::kUnknown;
      out.confidence = 0.0f;
    }
    return out;
  }
  // Fused.
  if (background >= params.veto_share) {
    out.category = ObjectCategory::kNonObject;
    out.confidence = background;
    out.vetoed = true;
    return out;
  }
  if (camera.best != ObjectCategory::kUnknown && camera.best == lidar) {
    const float p = std::min(1.0f, std::max(0.0f, lidar_p));
    out.confidence = 1.0f - (1.0f - p) * (1.0f - camera.best_share);
  } else if (params.relabel && camera.best != ObjectCategory::kUnknown &&
             camera.best_share >= params.min_camera_share) {
    out.category = camera.best;
    out.confidence = camera.best_share;
  }
  return out;
}

}  // namespace core
}  // namespace urban_detection
