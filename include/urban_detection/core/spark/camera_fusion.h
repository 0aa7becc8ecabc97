/// \file camera_fusion.h
/// Fusion of the camera's semantic segmentation (SPARK, second seed paper, live variant) with
/// the LiDAR object classifier (object_classifier.h): what a camera class means for an object
/// (CameraClassMap), the camera evidence of one object (its visible points' share per object
/// category, CameraEvidence), and the rule that combines it with the object's LiDAR class
/// (fuseObjectClass). ROS-free; never prints.
///
/// The `fused` rule (docs/spark.md gives the measurements behind it):
/// - fewer than `min_visible_points` object points seen by the camera: the LiDAR class stays
///   (objects outside the image, behind the camera or occluded);
/// - veto: when at least `veto_share` of the visible points fall on background classes
///   (road, sidewalk, building, wall, fence, vegetation, terrain, sky, ...), the object is a
///   non-object (the camera sees no thing where the LiDAR found one);
/// - agreement: when the camera's best object category equals the LiDAR class, the confidence
///   becomes the noisy-or 1 - (1 - p_lidar) (1 - share_camera);
/// - relabel (only with `relabel`): when they disagree and the camera's share reaches
///   `min_camera_share`, the camera's category replaces the LiDAR class;
/// - otherwise the LiDAR class and confidence stay.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace core {

/// Which class the objects of `fused`/`camera` output carry.
enum class FusionMode : std::uint8_t {
  kLidar = 0,   ///< the LiDAR class untouched (the camera stage is a pass-through)
  kCamera = 1,  ///< the camera's class where the camera sees the object, LiDAR's elsewhere
  kFused = 2,   ///< the rule in the file comment
};
/// "lidar", "camera", "fused".
const char* toString(FusionMode m);
/// Parses toString(); false for anything else.
bool parseFusionMode(const std::string& name, FusionMode* mode);

/// The object category of each camera class id (index = network output channel). kNonObject
/// marks background classes (they count towards the veto), kUnknown classes are ignored
/// (neither object nor background: e.g. "Unlabeled", or a class the network confuses, such as
/// Cityscapes "Train" for KITTI facades).
struct CameraClassMap {
  std::vector<ObjectCategory> category_of_class;

  ObjectCategory categoryOf(int class_id) const {
    return class_id >= 0 && static_cast<std::size_t>(class_id) < category_of_class.size()
               ? category_of_class[static_cast<std::size_t>(class_id)]
               : ObjectCategory::kUnknown;
  }
};

/// Builds the map from class names (`names[id]`) and, per category, the names that belong to it
/// (compared case-insensitively; decimal ids also accepted). Returns false with `error` naming
/// the first entry that is no class and the first class listed twice.
bool buildCameraClassMap(const std::vector<std::string>& names,
                         const std::vector<std::string>& vehicle,
                         const std::vector<std::string>& pedestrian,
                         const std::vector<std::string>& cyclist,
                         const std::vector<std::string>& other_object,
                         const std::vector<std::string>& background, CameraClassMap* map,
                         std::string* error);

/// Parameters of the fusion, mirrored in config/image_label_transfer.yaml (`fusion:`).
struct CameraFusionParams {
  FusionMode mode = FusionMode::kCamera;  ///< which class the output carries
  int min_visible_points = 5;             ///< [-] fewer visible points: the camera has no say
  double veto_share = 0.6;        ///< [0..1] background share that makes an object a non-object;
                                  ///< > 1 disables the veto
  double min_camera_share = 0.5;  ///< [0..1] camera category share needed to label (camera
                                  ///< mode) or relabel (fused with `relabel`)
  bool relabel = false;           ///< fused: a confident disagreeing camera class wins
};

/// Empty when valid, else a message naming the first out-of-range field and its range.
std::string validate(const CameraFusionParams& p);

/// CameraFusionParams' field table (core/common/param_fields.h); the mode is the nodelet's
/// `fusion` parameter (lidar | camera | fused), the rest `fusion_rule/<name>`.
template <>
struct ParamFields<CameraFusionParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"min_visible_points", "points", 1, 1000000, "fewer visible points: the camera has no say"},
      p.min_visible_points);
    f({"veto_share", "", 0.01, 1.01,
       "background share that makes an object a non-object (above 1: no veto)"},
      p.veto_share);
    f({"min_camera_share", "", 0.0, 1.0,
       "camera category share needed to label (camera mode) or relabel (fused with relabel)"},
      p.min_camera_share);
    f({"relabel", "fused: a confident disagreeing camera class wins"}, p.relabel);
  }
};

/// What the camera says about one object.
struct CameraEvidence {
  std::uint32_t visible = 0;  ///< [-] object points inside the image, in front, not occluded
  /// [0..1] summed pixel confidence per category / visible points (index = ObjectCategory
  /// value, kNonObject = background).
  std::array<float, kNumObjectCategories> share{};
  ObjectCategory best = ObjectCategory::kUnknown;  ///< object category (not kNonObject) with
                                                   ///< the largest share; kUnknown if none
  float best_share = 0.0f;                         ///< [0..1] its share
  float background_share() const { return share[0]; }
};

/// The evidence from per-class summed confidences (`class_scores`, `class_bound` entries, as
/// ImageLabelTransfer::classScores()) of an object with `visible` visible points. Null scores
/// give empty evidence.
CameraEvidence cameraEvidence(const float* class_scores, int class_bound, std::uint32_t visible,
                              const CameraClassMap& map);

/// Result of the fusion for one object.
struct FusedClass {
  ObjectCategory category = ObjectCategory::kUnknown;
  float confidence = 0.0f;   ///< [0..1]
  bool camera_used = false;  ///< the camera saw the object (>= min_visible_points)
  bool vetoed = false;       ///< fused: turned into a non-object by the veto
};

/// Combines an object's LiDAR class (`lidar`, probability `lidar_p`) with the camera's
/// evidence under `params.mode` (rule in the file comment). In camera mode an object the
/// camera sees gets the camera's category (kNonObject when its background share reaches
/// veto_share or exceeds every object share, kUnknown below min_camera_share).
FusedClass fuseObjectClass(ObjectCategory lidar, float lidar_p, const CameraEvidence& camera,
                           const CameraFusionParams& params);

}  // namespace core
}  // namespace urban_detection
