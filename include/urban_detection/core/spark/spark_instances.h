/// \file spark_instances.h
/// 3-D side of the SPARK workflow (second seed paper, Sec. 3.4 and 3.5): mask pixels cast back
/// into the cloud (first point hit, from the renderer's z-buffer) vote a class per point; the
/// classified points of each class are clustered with DBSCAN into instances with boxes, which
/// are exported as JSON and cut out as sub-clouds. ROS-free.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/spark/spark_capture.h"
#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace core {

/// Parameters of back-projection and clustering, mirrored in config/spark.json ("spark").
struct SparkParams {
  int mask_stride_px = 4;          ///< [px] every n-th mask pixel in x and y is cast back
  int min_point_votes = 1;         ///< [-] a point needs this many votes to be classified
  double dbscan_eps_m = 0.5;       ///< [m] DBSCAN neighbourhood radius
  int dbscan_min_points = 4;       ///< [-] DBSCAN core point: this many neighbours (itself incl.)
  int min_instance_points = 10;    ///< [-] smaller clusters are dropped
  double box_margin_m = 0.1;       ///< [m] boxes are enlarged by this for sub-clouds and cuts
  std::vector<bool> kept_classes;  ///< by class id, true = classified; empty = all classes
};

/// Accumulates the class votes of cast-back pixels per cloud point.
class PointClassVotes {
 public:
  /// Forgets all votes; the cloud has `n_points` points.
  void reset(std::size_t n_points);
  /// Casts every `stride`-th pixel (x and y multiples of stride) of the last image rendered by
  /// `zbuffer` back into the cloud: a pixel with a kept class and a hit point adds its
  /// confidence to that point's class. `scores` may have any resolution (sampled at the scaled
  /// pixel). Returns the number of votes added.
  std::size_t castBack(const OrthoRenderer& zbuffer, const SegmentationScores& scores, int stride,
                       const std::vector<bool>& kept_classes);
  /// Per point: the class with the most votes (ties: lower id; the vote count decides, summed
  /// confidence breaks ties), -1 with fewer than `min_votes` votes or none.
  void classify(int min_votes, std::vector<int>* point_class);
  std::size_t votes() const { return votes_.size(); }

 private:
  struct Vote {
    std::uint32_t point;
    std::int32_t class_id;
    float confidence;
  };
  std::size_t n_points_ = 0;
  std::vector<Vote> votes_;
};

/// DBSCAN (Ester et al. 1996) of the points `members` of `cloud` (positions into `cloud`) on a
/// PCL kd-tree. `cluster` receives, per member, its cluster id 0..K-1 or -1 for noise; returns
/// K. A core point has at least `min_points` points (itself included) within `eps_m`; border
/// points join the first cluster that reaches them. Non-finite points are noise.
int dbscan(const CloudXYZIRT& cloud, const std::vector<std::uint32_t>& members, double eps_m,
           int min_points, std::vector<int>* cluster);

/// One segmented object instance.
struct SparkInstance {
  std::uint32_t id = 0;  ///< 1..N
  int class_id = -1;
  std::vector<std::uint32_t> indices;  ///< classified points of the cluster (cloud positions)
  Eigen::Vector3f min_pt = Eigen::Vector3f::Zero();    ///< [m] axis-aligned box
  Eigen::Vector3f max_pt = Eigen::Vector3f::Zero();    ///< [m]
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  ///< [m] mean of the indices' points
};

/// Clusters the classified points (`point_class`, one per cloud point) class by class into
/// instances (sorted by class, then by size descending; ids 1..N in that order).
void buildInstances(const CloudXYZIRT& cloud, const std::vector<int>& point_class,
                    const SparkParams& params, std::vector<SparkInstance>* instances);

/// Positions of all cloud points inside the instance box enlarged by `margin_m` (the paper's
/// sub-point cloud "with all points between the bounding box").
void pointsInBox(const CloudXYZIRT& cloud, const SparkInstance& instance, double margin_m,
                 std::vector<std::uint32_t>* positions);

/// Positions of the cloud points outside every box (enlarged by `margin_m`) of the instances
/// whose class is in `cut` (by class id): the cloud with those classes cut out.
void cutOutClasses(const CloudXYZIRT& cloud, const std::vector<SparkInstance>& instances,
                   const std::vector<bool>& cut, double margin_m,
                   std::vector<std::uint32_t>* kept_positions);

/// Writes the instances as JSON: {"cloud": ..., "classes": [...], "instances": [{"id",
/// "class", "class_id", "point_count", "box": {"min", "max", "center", "size"}, "centroid",
/// "indices"}]}. Names come from `class_names` ("class_<id>" when missing). False on I/O error.
bool writeInstancesJson(const std::string& path, const std::string& cloud_path,
                        const std::vector<SparkInstance>& instances,
                        const std::vector<std::string>& class_names, std::string* error);

/// Writes the record of one capture as JSON (image file, pose, projection) so the image can be
/// related to the cloud again: {"image", "index", "position", "yaw_deg", "pitch_deg",
/// "rotation" (rows right, down, forward), "width_px", "height_px", "metres_per_pixel",
/// "max_depth_m", "projection"}.
bool writeCaptureRecordJson(const std::string& path, const std::string& image_file, int index,
                            const OrthoCamera& camera, std::string* error);

}  // namespace core
}  // namespace urban_detection
