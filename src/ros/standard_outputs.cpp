#include "urban_detection/ros/standard_outputs.h"

#include "urban_detection/core/detection/object_detector.h"

namespace urban_detection {
namespace ros_conv {

std::int64_t classId(const std::string& class_label) {
  for (int c = 0; c <= 4; ++c) {
    if (class_label == core::toString(static_cast<core::ObjectCategory>(c))) return c;
  }
  return static_cast<std::int64_t>(core::ObjectCategory::kUnknown);
}

void toDetection3DArray(const DetectedObjectArray& objects, Detection3DArray* out) {
  out->header = objects.header;
  out->detections.resize(objects.objects.size());
  for (std::size_t k = 0; k < objects.objects.size(); ++k) {
    const DetectedObject& o = objects.objects[k];
    Detection3D& d = out->detections[k];
    d.header = objects.header;
    d.results.resize(1);
    d.results[0].id = classId(o.class_label);
    d.results[0].score = o.class_confidence;
    d.results[0].pose.pose = o.obb_pose;
    d.results[0].pose.covariance.fill(0.0);
    d.bbox.center = o.obb_pose;
    d.bbox.size = o.obb_dimensions;
    d.source_cloud = sensor_msgs::PointCloud2();
  }
}

}  // namespace ros_conv
}  // namespace urban_detection
