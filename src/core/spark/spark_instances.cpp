#include "urban_detection/core/spark/spark_instances.h"

#include "urban_detection/core/common/json.h"
#include "urban_detection/core/spark/spark_io.h"

#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

namespace urban_detection {
namespace core {

void PointClassVotes::reset(std::size_t n_points) {
  n_points_ = n_points;
  votes_.clear();
}

std::size_t PointClassVotes::castBack(const OrthoRenderer& zbuffer,
                                      const SegmentationScores& scores, int stride,
                                      const std::vector<bool>& kept_classes) {
  if (scores.empty() || zbuffer.width() <= 0 || zbuffer.height() <= 0) return 0;
  const int step = std::max(1, stride);
  const double sx = static_cast<double>(scores.width()) / zbuffer.width();
  const double sy = static_cast<double>(scores.height()) / zbuffer.height();
  const std::size_t before = votes_.size();
  for (int y = 0; y < zbuffer.height(); y += step) {
    const int ys = std::min(scores.height() - 1, static_cast<int>(y * sy));
    for (int x = 0; x < zbuffer.width(); x += step) {
      const std::int32_t hit = zbuffer.hit(x, y);
      if (hit < 0 || static_cast<std::size_t>(hit) >= n_points_) continue;
      float conf = 0.0f;
      const int c =
          scores.classAt(std::min(scores.width() - 1, static_cast<int>(x * sx)), ys, &conf);
      if (c < 0) continue;
      if (!kept_classes.empty() &&
          (static_cast<std::size_t>(c) >= kept_classes.size() || !kept_classes[c]))
        continue;
      votes_.push_back({static_cast<std::uint32_t>(hit), c, conf});
    }
  }
  return votes_.size() - before;
}

void PointClassVotes::classify(int min_votes, std::vector<int>* point_class) {
  point_class->assign(n_points_, -1);
  std::sort(votes_.begin(), votes_.end(), [](const Vote& a, const Vote& b) {
    return a.point != b.point ? a.point < b.point : a.class_id < b.class_id;
  });
  std::size_t i = 0;
  while (i < votes_.size()) {
    const std::uint32_t point = votes_[i].point;
    int best = -1, best_count = 0, total = 0;
    float best_conf = 0.0f;
    while (i < votes_.size() && votes_[i].point == point) {
      const int c = votes_[i].class_id;
      int count = 0;
      float conf = 0.0f;
      for (; i < votes_.size() && votes_[i].point == point && votes_[i].class_id == c; ++i) {
        ++count;
        conf += votes_[i].confidence;
      }
      total += count;
      if (count > best_count || (count == best_count && conf > best_conf)) {
        best = c;
        best_count = count;
        best_conf = conf;
      }
    }
    if (total >= std::max(1, min_votes)) (*point_class)[point] = best;
  }
}

int dbscan(const CloudXYZIRT& cloud, const std::vector<std::uint32_t>& members, double eps_m,
           int min_points, std::vector<int>* cluster) {
  cluster->assign(members.size(), -1);
  // The kd-tree holds the finite members only; `finite_of` maps its points back to members.
  auto sub = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  std::vector<std::uint32_t> member_of;
  sub->reserve(members.size());
  for (std::size_t m = 0; m < members.size(); ++m) {
    const PointXYZIRT& p = cloud[members[m]];
    if (!isFinitePoint(p)) continue;
    sub->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    member_of.push_back(static_cast<std::uint32_t>(m));
  }
  if (sub->empty() || !(eps_m > 0.0)) return 0;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(sub);
  const std::size_t n = sub->size();
  std::vector<int> label(n, -2);  // -2 unvisited, -1 noise, >= 0 cluster
  std::vector<int> neighbours, queue;
  std::vector<float> dist;
  const float radius = static_cast<float>(eps_m);
  const std::size_t need = static_cast<std::size_t>(std::max(1, min_points));
  int k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (label[i] != -2) continue;
    tree.radiusSearch(static_cast<int>(i), radius, neighbours, dist);
    if (neighbours.size() < need) {
      label[i] = -1;
      continue;
    }
    label[i] = k;
    queue.assign(neighbours.begin(), neighbours.end());
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int j = queue[q];
      if (label[j] == -1) label[j] = k;  // noise reached from a core point: border point
      if (label[j] != -2) continue;
      label[j] = k;
      tree.radiusSearch(j, radius, neighbours, dist);
      if (neighbours.size() >= need)
        queue.insert(queue.end(), neighbours.begin(), neighbours.end());
    }
    ++k;
  }
  for (std::size_t i = 0; i < n; ++i) (*cluster)[member_of[i]] = label[i];
  return k;
}

void buildInstances(const CloudXYZIRT& cloud, const std::vector<int>& point_class,
                    const SparkParams& params, std::vector<SparkInstance>* instances) {
  instances->clear();
  std::map<int, std::vector<std::uint32_t>> by_class;
  for (std::size_t i = 0; i < point_class.size() && i < cloud.size(); ++i) {
    if (point_class[i] >= 0) by_class[point_class[i]].push_back(static_cast<std::uint32_t>(i));
  }
  std::vector<int> cluster;
  for (const auto& [class_id, members] : by_class) {
    const int k = dbscan(cloud, members, params.dbscan_eps_m, params.dbscan_min_points, &cluster);
    std::vector<SparkInstance> found(static_cast<std::size_t>(k));
    for (std::size_t m = 0; m < members.size(); ++m) {
      if (cluster[m] >= 0) found[cluster[m]].indices.push_back(members[m]);
    }
    std::stable_sort(found.begin(), found.end(),
                     [](const SparkInstance& a, const SparkInstance& b) {
                       return a.indices.size() > b.indices.size();
                     });
    for (SparkInstance& inst : found) {
      if (inst.indices.size() < static_cast<std::size_t>(std::max(1, params.min_instance_points)))
        continue;
      inst.class_id = class_id;
      Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
      Eigen::Vector3f hi = -lo;
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (const std::uint32_t i : inst.indices) {
        const Eigen::Vector3f p(cloud[i].x, cloud[i].y, cloud[i].z);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
        sum += p.cast<double>();
      }
      inst.min_pt = lo;
      inst.max_pt = hi;
      inst.centroid = (sum / static_cast<double>(inst.indices.size())).cast<float>();
      inst.id = static_cast<std::uint32_t>(instances->size() + 1);
      instances->push_back(std::move(inst));
    }
  }
}

void pointsInBox(const CloudXYZIRT& cloud, const SparkInstance& instance, double margin_m,
                 std::vector<std::uint32_t>* positions) {
  positions->clear();
  const Eigen::Vector3f m = Eigen::Vector3f::Constant(static_cast<float>(margin_m));
  const Eigen::Vector3f lo = instance.min_pt - m, hi = instance.max_pt + m;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const PointXYZIRT& p = cloud[i];
    if (p.x >= lo.x() && p.x <= hi.x() && p.y >= lo.y() && p.y <= hi.y() && p.z >= lo.z() &&
        p.z <= hi.z()) {
      positions->push_back(static_cast<std::uint32_t>(i));
    }
  }
}

void cutOutClasses(const CloudXYZIRT& cloud, const std::vector<SparkInstance>& instances,
                   const std::vector<bool>& cut, double margin_m,
                   std::vector<std::uint32_t>* kept_positions) {
  std::vector<bool> removed(cloud.size(), false);
  std::vector<std::uint32_t> inside;
  for (const SparkInstance& inst : instances) {
    if (inst.class_id < 0 || static_cast<std::size_t>(inst.class_id) >= cut.size() ||
        !cut[inst.class_id])
      continue;
    pointsInBox(cloud, inst, margin_m, &inside);
    for (const std::uint32_t i : inside) removed[i] = true;
  }
  kept_positions->clear();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!removed[i]) kept_positions->push_back(static_cast<std::uint32_t>(i));
  }
}

namespace {

void writeVec(std::ostream& out, const Eigen::Vector3d& v) {
  out << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
}

bool finish(std::ofstream& out, const std::string& path, std::string* error) {
  out.flush();
  if (!out) {
    *error = "cannot write '" + path + "'";
    return false;
  }
  return true;
}

}  // namespace

bool writeInstancesJson(const std::string& path, const std::string& cloud_path,
                        const std::vector<SparkInstance>& instances,
                        const std::vector<std::string>& class_names, std::string* error) {
  std::ofstream out(path);
  if (!out) {
    *error = "cannot open '" + path + "' for writing";
    return false;
  }
  out.precision(9);
  out << "{\n  \"cloud\": \"" << jsonEscape(cloud_path) << "\",\n  \"classes\": [";
  for (std::size_t c = 0; c < class_names.size(); ++c)
    out << (c ? ", " : "") << "\"" << jsonEscape(class_names[c]) << "\"";
  out << "],\n  \"instances\": [";
  for (std::size_t k = 0; k < instances.size(); ++k) {
    const SparkInstance& inst = instances[k];
    const Eigen::Vector3d lo = inst.min_pt.cast<double>(), hi = inst.max_pt.cast<double>();
    out << (k ? "," : "") << "\n    {\"id\": " << inst.id << ", \"class\": \""
        << jsonEscape(sparkClassName(class_names, inst.class_id))
        << "\", \"class_id\": " << inst.class_id << ", \"point_count\": " << inst.indices.size()
        << ",\n     \"box\": {\"min\": ";
    writeVec(out, lo);
    out << ", \"max\": ";
    writeVec(out, hi);
    out << ", \"center\": ";
    writeVec(out, 0.5 * (lo + hi));
    out << ", \"size\": ";
    writeVec(out, hi - lo);
    out << "},\n     \"centroid\": ";
    writeVec(out, inst.centroid.cast<double>());
    out << ",\n     \"indices\": [";
    for (std::size_t i = 0; i < inst.indices.size(); ++i)
      out << (i ? (i % 20 ? ", " : ",\n       ") : "") << inst.indices[i];
    out << "]}";
  }
  out << "\n  ]\n}\n";
  return finish(out, path, error);
}

bool writeCaptureRecordJson(const std::string& path, const std::string& image_file, int index,
                            const OrthoCamera& camera, std::string* error) {
  std::ofstream out(path);
  if (!out) {
    *error = "cannot open '" + path + "' for writing";
    return false;
  }
  out.precision(12);
  out << "{\n  \"image\": \"" << jsonEscape(image_file) << "\",\n  \"index\": " << index
      << ",\n  \"projection\": \"orthographic\",\n  \"position\": ";
  writeVec(out, camera.position);
  out << ",\n  \"yaw_deg\": " << camera.yaw_deg << ",\n  \"pitch_deg\": " << camera.pitch_deg
      << ",\n  \"rotation\": [";
  for (int r = 0; r < 3; ++r) {
    out << (r ? ", " : "");
    writeVec(out, camera.rotation.row(r).transpose());
  }
  out << "],\n  \"width_px\": " << camera.width_px << ",\n  \"height_px\": " << camera.height_px
      << ",\n  \"metres_per_pixel\": " << camera.metres_per_pixel
      << ",\n  \"max_depth_m\": " << camera.max_depth_m
      << ",\n  \"pixel_to_cloud\": \"p = position + rotation^T * [(x + 0.5 - width_px / 2) * "
         "metres_per_pixel, (y + 0.5 - height_px / 2) * metres_per_pixel, depth]\"\n}\n";
  return finish(out, path, error);
}

}  // namespace core
}  // namespace urban_detection
