#include "urban_detection/core/spark/camera_labeller.h"

#include <algorithm>
#include <utility>

namespace urban_detection {
namespace core {

CameraLabeller::CameraLabeller(const CameraFusionParams& fusion,
                               const ImageLabelTransferParams& transfer,
                               std::vector<std::string> names, CameraClassMap class_map)
    : fusion_(fusion),
      transfer_(transfer),
      names_(std::move(names)),
      class_map_(std::move(class_map)) {}

const ObjectClassVote* CameraLabeller::voteOf(std::uint32_t id) const {
  const auto it =
      std::lower_bound(votes_.begin(), votes_.end(), id,
                       [](const ObjectClassVote& v, std::uint32_t i) { return v.object_id < i; });
  return it != votes_.end() && it->object_id == id ? &*it : nullptr;
}

std::string CameraLabeller::className(int class_id) const {
  if (class_id < 0) return "unknown";
  const auto id = static_cast<std::size_t>(class_id);
  return id < names_.size() && !names_[id].empty() ? names_[id] : "class_" + std::to_string(id);
}

void CameraLabeller::label(const LabeledCloud& points, const Eigen::Isometry3d& camera_from_lidar,
                           const PinholeCamera& camera, const SegmentationScores& scores,
                           std::vector<ObjectClassLabel>* objects) {
  if (fusion_.mode == FusionMode::kLidar) return;
  transfer_.transfer(points, camera_from_lidar, camera, scores, &votes_);
  const auto min_visible = static_cast<std::uint32_t>(fusion_.min_visible_points);
  for (ObjectClassLabel& o : *objects) {
    const ObjectClassVote* v = voteOf(o.id);
    if (fusion_.mode == FusionMode::kCamera) {
      if (v == nullptr || v->considered < min_visible) continue;  // unseen: LiDAR class stays
      o.class_label = className(v->class_id);
      o.class_confidence = v->class_id < 0 ? 0.0f : v->confidence;
      continue;
    }
    CameraEvidence e;
    if (v != nullptr) {
      e = cameraEvidence(transfer_.classScores(static_cast<std::size_t>(v - votes_.data())),
                         transfer_.classBound(), v->considered, class_map_);
    }
    ObjectCategory lidar = ObjectCategory::kUnknown;
    if (!parseObjectCategory(o.class_label, &lidar)) lidar = ObjectCategory::kUnknown;
    const FusedClass fused = fuseObjectClass(lidar, o.class_confidence, e, fusion_);
    o.vetoed = fused.vetoed;
    if (!fused.camera_used) continue;  // unseen: label kept verbatim
    o.class_label = toString(fused.category);
    o.class_confidence = fused.category == ObjectCategory::kUnknown ? 0.0f : fused.confidence;
  }
}

}  // namespace core
}  // namespace urban_detection
