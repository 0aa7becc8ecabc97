/// \file kdtree_detector.h
/// The paper's baseline (Sec. 5, "Connected Component Analysis [14]"): Euclidean cluster
/// extraction over a kd-tree (PCL EuclideanClusterExtraction), on the same foreground and with
/// the same output as HierarchicalGridDetector. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/point_types.h"  // first: PCL_NO_PRECOMPILE

#include "urban_detection/core/object_detector.h"
#include "urban_detection/core/object_geometry.h"

namespace urban_detection {
namespace core {

/// Parameters of KdTreeDetector, mirrored in config/kdtree.yaml.
struct KdTreeDetectorParams {
  double cluster_tolerance_m = 0.4;   // [m] points closer than this (3-D) are connected
  int min_cluster_size = 5;           // [-] smaller clusters are dropped
  int max_cluster_size = 1000000;     // [-] larger clusters are dropped (PCL semantics)
  double max_extent_m = 20.0;         // [m] objects with a longer xy box side are dropped
  double max_abs_coordinate_m = 1000.0;  // [m] points with a larger |x|, |y| or |z| are ignored
  // [-] true: the kd-tree sorts every radius search's neighbours by distance (PCL's default
  // for pcl::search::KdTree, as in PCL's clustering tutorial). Clustering does not use the
  // order, so the clusters are the same either way; unsorted is ~2.2x faster on KITTI raw
  // foregrounds (sorting took about half of the baseline's time).
  bool sorted_search = false;
};

/// Returns "" when `p` is usable, else a message naming the first bad field and its range.
std::string validate(const KdTreeDetectorParams& p);

/// Euclidean clustering baseline. Objects are ordered by their first point in the input cloud
/// (as the hierarchical detector's), ids 1..N.
class KdTreeDetector : public ObjectDetector {
 public:
  /// Throws std::invalid_argument when validate(params) is not empty.
  explicit KdTreeDetector(const KdTreeDetectorParams& params = KdTreeDetectorParams());
  std::string name() const override { return "kdtree"; }
  void detect(const LabeledCloud& foreground, std::vector<DetectedObject>* objects) override;
  const KdTreeDetectorParams& params() const { return params_; }

 private:
  KdTreeDetectorParams params_;
  ObjectGeometry geometry_;
  std::vector<std::uint32_t> positions_;
};

}  // namespace core
}  // namespace urban_detection
