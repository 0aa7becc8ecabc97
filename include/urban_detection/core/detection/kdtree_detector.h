/// \file kdtree_detector.h
/// The paper's baseline (Sec. 5, "Connected Component Analysis [14]"): Euclidean cluster
/// extraction over a kd-tree (PCL EuclideanClusterExtraction), on the same foreground and with
/// the same output as HierarchicalGridDetector. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/detection/object_geometry.h"

namespace urban_detection {
namespace core {

/// Parameters of KdTreeDetector, mirrored in config/kdtree.yaml.
struct KdTreeDetectorParams {
  double cluster_tolerance_m = 0.4;      // [m] points closer than this (3-D) are connected
  int min_cluster_size = 5;              // [-] smaller clusters are dropped
  int max_cluster_size = 1000000;        // [-] larger clusters are dropped (PCL semantics)
  double max_extent_m = 20.0;            // [m] objects with a longer xy box side are dropped
  double max_abs_coordinate_m = 1000.0;  // [m] points with a larger |x|, |y| or |z| are ignored
  // [-] true: the kd-tree sorts every radius search's neighbours by distance (PCL's default
  // for pcl::search::KdTree, as in PCL's clustering tutorial). Clustering does not use the
  // order, so the clusters are the same either way; unsorted is ~2.2x faster on KITTI raw
  // foregrounds (sorting took about half of the baseline's time).
  bool sorted_search = false;
};

/// KdTreeDetectorParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<KdTreeDetectorParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"cluster_tolerance_m", "m", 0.01, 10.0, "points closer than this (3-D) are connected"},
      p.cluster_tolerance_m);
    f({"min_cluster_size", "points", 1, 100000000, "smaller clusters are dropped"},
      p.min_cluster_size);
    f({"max_cluster_size", "points", 1, 100000000,
       "larger clusters are dropped (at least min_cluster_size)"},
      p.max_cluster_size);
    f({"max_extent_m", "m", 0.1, 1000.0, "objects with a longer xy box side are dropped"},
      p.max_extent_m);
    f({"max_abs_coordinate_m", "m", 1.0, 1e5, "points with a larger |x|, |y| or |z| are ignored"},
      p.max_abs_coordinate_m);
    f({"sorted_search", "sort every radius search's neighbours (same clusters, slower)"},
      p.sorted_search);
  }
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
