#include "urban_detection/core/spark/image_label_transfer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace urban_detection {
namespace core {

std::string validate(const ImageLabelTransferParams& params) {
  return checkFieldRanges(params);
}

bool PinholeCamera::valid() const {
  return width_px > 0 && height_px > 0 && projection.allFinite() && projection(0, 0) > 0.0 &&
         projection(1, 1) > 0.0;
}

bool PinholeCamera::project(const Eigen::Vector3d& p_camera, double min_depth_m, double* u,
                            double* v) const {
  if (!(p_camera.z() > min_depth_m)) return false;
  const Eigen::Vector3d h = projection.leftCols<3>() * p_camera + projection.col(3);
  if (!(h.z() > 0.0)) return false;
  *u = h.x() / h.z();
  *v = h.y() / h.z();
  return std::isfinite(*u) && std::isfinite(*v);
}

void ImageLabelTransfer::transfer(const LabeledCloud& object_points,
                                  const Eigen::Isometry3d& camera_from_lidar,
                                  const PinholeCamera& camera, const SegmentationScores& scores,
                                  std::vector<ObjectClassVote>* votes) {
  stats_ = ImageLabelTransferStats{};
  stats_.points = static_cast<std::uint32_t>(object_points.size());
  votes->clear();
  bound_ = 0;

  // Object id -> vote slot. Detector ids are 1..N, so a direct table is the common case (linear
  // time); arbitrary large ids fall back to a sorted id list and binary search.
  ids_.clear();
  std::uint32_t max_id = 0;
  for (const LabeledPoint& p : object_points) max_id = std::max(max_id, p.label);
  const bool table =
      !object_points.empty() && static_cast<std::size_t>(max_id) <= 4 * object_points.size() + 1024;
  if (table) {
    slot_of_id_.assign(static_cast<std::size_t>(max_id) + 1, -1);
    for (const LabeledPoint& p : object_points) slot_of_id_[p.label] = 0;
    for (std::uint32_t id = 0; id <= max_id; ++id) {
      if (slot_of_id_[id] < 0) continue;
      slot_of_id_[id] = static_cast<std::int32_t>(ids_.size());
      ids_.push_back(id);
    }
  } else {
    for (const LabeledPoint& p : object_points) ids_.push_back(p.label);
    std::sort(ids_.begin(), ids_.end());
    ids_.erase(std::unique(ids_.begin(), ids_.end()), ids_.end());
  }
  votes->resize(ids_.size());
  for (std::size_t i = 0; i < ids_.size(); ++i) (*votes)[i].object_id = ids_[i];
  auto slotOf = [this, table](std::uint32_t id) {
    if (table) return slot_of_id_[id];
    return static_cast<std::int32_t>(std::lower_bound(ids_.begin(), ids_.end(), id) - ids_.begin());
  };
  for (const LabeledPoint& p : object_points) ++(*votes)[slotOf(p.label)].points;
  if (ids_.empty() || !camera.valid() || scores.empty() || !camera_from_lidar.matrix().allFinite())
    return;

  // Pass 1: project every point; remember the nearest point of each occlusion cell.
  const bool occlusion = params_.occlusion_margin_m > 0.0 && params_.occlusion_cell_px > 0;
  const int cell = std::max(1, params_.occlusion_cell_px);
  const int cells_x = (camera.width_px + cell - 1) / cell;
  const int cells_y = (camera.height_px + cell - 1) / cell;
  if (occlusion) {
    cell_depth_.assign(static_cast<std::size_t>(cells_x) * cells_y,
                       std::numeric_limits<float>::infinity());
    cell_slot_.assign(cell_depth_.size(), -1);
  }
  const double sx_per_px = static_cast<double>(scores.width()) / camera.width_px;
  const double sy_per_px = static_cast<double>(scores.height()) / camera.height_px;
  projected_.clear();
  const Eigen::Matrix3d r = camera_from_lidar.linear();
  const Eigen::Vector3d t = camera_from_lidar.translation();
  for (const LabeledPoint& p : object_points) {
    if (!isFinitePoint(p)) {
      ++stats_.non_finite;
      continue;
    }
    const Eigen::Vector3d pc = r * Eigen::Vector3d(p.x, p.y, p.z) + t;
    double u = 0.0, v = 0.0;
    if (!camera.project(pc, params_.min_depth_m, &u, &v)) continue;
    if (!(u >= 0.0 && v >= 0.0 && u < camera.width_px && v < camera.height_px)) continue;
    Projected pr;
    pr.slot = slotOf(p.label);
    pr.depth = static_cast<float>(pc.z());
    pr.sx = std::min(scores.width() - 1, static_cast<int>(u * sx_per_px));
    pr.sy = std::min(scores.height() - 1, static_cast<int>(v * sy_per_px));
    pr.cell = -1;
    if (occlusion) {
      pr.cell = static_cast<int>(v) / cell * cells_x + static_cast<int>(u) / cell;
      if (pr.depth < cell_depth_[pr.cell]) {
        cell_depth_[pr.cell] = pr.depth;
        cell_slot_[pr.cell] = pr.slot;
      }
    }
    projected_.push_back(pr);
  }
  stats_.projected = static_cast<std::uint32_t>(projected_.size());

  // Pass 2: visible points vote with their pixel's confidence.
  const int bound = scores.classIdBound();
  bound_ = bound;
  scores_.assign(ids_.size() * static_cast<std::size_t>(bound), 0.0f);
  all_scores_.assign(scores_.size(), 0.0f);
  const auto& kept = params_.kept_classes;
  const float margin = static_cast<float>(params_.occlusion_margin_m);
  for (const Projected& pr : projected_) {
    ObjectClassVote& vote = (*votes)[pr.slot];
    if (occlusion && cell_slot_[pr.cell] != pr.slot && pr.depth > cell_depth_[pr.cell] + margin) {
      ++vote.occluded;
      continue;
    }
    ++vote.considered;
    float conf = 0.0f;
    const int c = scores.classAt(pr.sx, pr.sy, &conf);
    if (c < 0 || c >= bound) continue;
    all_scores_[static_cast<std::size_t>(pr.slot) * bound + c] += conf;
    if (!kept.empty() && (static_cast<std::size_t>(c) >= kept.size() || !kept[c])) continue;
    scores_[static_cast<std::size_t>(pr.slot) * bound + c] += conf;
  }

  for (std::size_t s = 0; s < votes->size(); ++s) {
    ObjectClassVote& vote = (*votes)[s];
    stats_.considered += vote.considered;
    const float* row = scores_.data() + s * bound;
    const int best = static_cast<int>(std::max_element(row, row + bound) - row);
    if (row[best] <= 0.0f || vote.considered == 0) continue;
    vote.best_class_id = best;
    vote.confidence = row[best] / static_cast<float>(vote.considered);
    if (vote.considered >= static_cast<std::uint32_t>(std::max(params_.min_points, 1)) &&
        vote.confidence >= params_.min_confidence) {
      vote.class_id = best;
    }
  }
}

}  // namespace core
}  // namespace urban_detection
