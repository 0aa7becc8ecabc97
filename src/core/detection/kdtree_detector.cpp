#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include "urban_detection/core/detection/kdtree_detector.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

namespace urban_detection {
namespace core {

std::string validate(const KdTreeDetectorParams& p) {
  std::string error = checkFieldRanges(p);
  if (error.empty() && p.max_cluster_size < p.min_cluster_size) {
    error = "max_cluster_size must be >= min_cluster_size, got " +
            std::to_string(p.max_cluster_size) + " < " + std::to_string(p.min_cluster_size);
  }
  return error;
}

KdTreeDetector::KdTreeDetector(const KdTreeDetectorParams& params) : params_(params) {
  const std::string err = validate(params);
  if (!err.empty()) throw std::invalid_argument("KdTreeDetector: " + err);
}

void KdTreeDetector::detect(const LabeledCloud& foreground, std::vector<DetectedObject>* objects) {
  objects->clear();
  // Only finite points within the coordinate bound go into the tree: FLANN's squared distances
  // overflow on 1e30 coordinates, and NaN would poison the tree.
  pcl::IndicesPtr valid(new pcl::Indices);
  valid->reserve(foreground.size());
  const float lim = static_cast<float>(params_.max_abs_coordinate_m);
  for (std::size_t i = 0; i < foreground.size(); ++i) {
    const LabeledPoint& p = foreground.points[i];
    if (std::fabs(p.x) <= lim && std::fabs(p.y) <= lim && std::fabs(p.z) <= lim) {
      valid->push_back(static_cast<pcl::index_t>(i));  // NaN fails the comparisons
    }
  }
  if (valid->empty()) return;

  LabeledCloud::ConstPtr cloud(&foreground, [](const LabeledCloud*) {});  // non-owning
  pcl::search::KdTree<LabeledPoint>::Ptr tree(
      new pcl::search::KdTree<LabeledPoint>(params_.sorted_search));
  tree->setInputCloud(cloud, valid);
  std::vector<pcl::PointIndices> clusters;
  pcl::EuclideanClusterExtraction<LabeledPoint> ec;
  ec.setClusterTolerance(params_.cluster_tolerance_m);
  ec.setMinClusterSize(params_.min_cluster_size);
  ec.setMaxClusterSize(params_.max_cluster_size);
  ec.setSearchMethod(tree);
  ec.setInputCloud(cloud);
  ec.setIndices(valid);
  ec.extract(clusters);

  for (pcl::PointIndices& c : clusters) std::sort(c.indices.begin(), c.indices.end());
  std::sort(clusters.begin(), clusters.end(),
            [](const pcl::PointIndices& a, const pcl::PointIndices& b) {
              return a.indices.front() < b.indices.front();
            });
  for (const pcl::PointIndices& c : clusters) {
    if (c.indices.empty()) continue;
    positions_.assign(c.indices.begin(), c.indices.end());
    DetectedObject obj;
    obj.indices.resize(positions_.size());
    geometry_.compute(foreground, positions_.data(), positions_.size(), &obj, obj.indices.data());
    if (obj.max_pt.x() - obj.min_pt.x() > params_.max_extent_m ||
        obj.max_pt.y() - obj.min_pt.y() > params_.max_extent_m) {
      continue;
    }
    obj.id = static_cast<std::uint32_t>(objects->size() + 1);
    objects->push_back(std::move(obj));
  }
}

}  // namespace core
}  // namespace urban_detection
