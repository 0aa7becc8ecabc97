#include "urban_detection/ros/object_conversions.h"

#include <cmath>

namespace urban_detection {
namespace ros_conv {

void toMsg(const core::DetectedObject& o, DetectedObject* m) {
  m->id = o.id;
  m->point_count = static_cast<std::uint32_t>(o.indices.size());
  m->centroid.x = o.centroid.x();
  m->centroid.y = o.centroid.y();
  m->centroid.z = o.centroid.z();
  const Eigen::Vector3f c = 0.5f * (o.min_pt + o.max_pt), d = o.max_pt - o.min_pt;
  m->aabb_pose = yawPose(c, 0.0);
  m->aabb_dimensions = toVector3(d);
  m->obb_pose = yawPose(o.obb_center, o.obb_yaw_rad);
  m->obb_dimensions = toVector3(o.obb_size);
  m->indices.assign(o.indices.begin(), o.indices.end());
  if (o.category == core::ObjectCategory::kUnknown) {
    m->class_label = kUnknownClass;
    m->class_confidence = 0.0f;
  } else {
    m->class_label = core::toString(o.category);
    m->class_confidence = o.class_confidence;
  }
}

void toMsg(const std::vector<core::DetectedObject>& objects, const std::string& detector,
           const std_msgs::Header& header, DetectedObjectArray* msg) {
  msg->header = header;
  msg->detector = detector;
  msg->objects.resize(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) toMsg(objects[i], &msg->objects[i]);
}

void buildObjectPoints(const LabeledCloud& foreground,
                       const std::vector<core::DetectedObject>& objects, LabeledCloud* out,
                       std::unordered_map<std::uint32_t, std::uint32_t>* id_of_index) {
  out->header = foreground.header;
  out->points.clear();
  id_of_index->clear();
  std::size_t n = 0;
  for (const core::DetectedObject& o : objects) n += o.indices.size();
  id_of_index->reserve(n);
  for (const core::DetectedObject& o : objects) {
    for (const std::uint32_t i : o.indices) (*id_of_index)[i] = o.id;
  }
  out->points.reserve(n);
  for (const LabeledPoint& p : foreground.points) {
    const auto it = id_of_index->find(p.index);
    if (it == id_of_index->end()) continue;
    LabeledPoint q = p;
    q.label = it->second;
    out->points.push_back(q);
  }
  out->width = static_cast<std::uint32_t>(out->points.size());
  out->height = 1;
  out->is_dense = foreground.is_dense;
}

}  // namespace ros_conv
}  // namespace urban_detection
