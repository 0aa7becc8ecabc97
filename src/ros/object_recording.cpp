#include "urban_detection/ros/object_recording.h"

#include <cmath>
#include <cstdio>

namespace urban_detection {
namespace ros_conv {

namespace {

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

const char* kittiType(const std::string& class_label) {
  if (class_label == "vehicle") return "Car";
  if (class_label == "pedestrian") return "Pedestrian";
  if (class_label == "cyclist") return "Cyclist";
  if (class_label == "other_object" || class_label == "non_object") return "Misc";
  return "DontCare";
}

}  // namespace

bool instanceLabels(const DetectedObjectArray& objects, std::size_t cloud_size,
                    std::vector<std::uint32_t>* labels) {
  labels->assign(cloud_size, 0u);
  for (std::size_t k = 0; k < objects.objects.size(); ++k) {
    for (const std::uint32_t i : objects.objects[k].indices) {
      if (i >= cloud_size) return false;
      (*labels)[i] = static_cast<std::uint32_t>(k + 1);
    }
  }
  return true;
}

std::string kittiLabelLine(const DetectedObject& o) {
  const auto& c = o.obb_pose.position;
  const auto& d = o.obb_dimensions;  // x length, y width, z height
  const double yaw = yawOf(o.obb_pose.orientation);
  double ry = -yaw - M_PI / 2.0;
  ry = std::atan2(std::sin(ry), std::cos(ry));
  char buf[256];
  // Location: the bottom-face centre, in the camera axes (y down).
  std::snprintf(buf, sizeof buf,
                "%s 0.00 0 -10.00 0.00 0.00 0.00 0.00 %.2f %.2f %.2f %.2f %.2f %.2f %.2f %.4f",
                kittiType(o.class_label), d.z, d.y, d.x, -c.y, -(c.z - 0.5 * d.z), c.x, ry,
                static_cast<double>(o.class_confidence));
  return buf;
}

std::string csvHeader() {
  return "revolution,stamp_s,frame_id,id,class,confidence,points,x,y,z,length,width,height,"
         "yaw_rad";
}

std::string csvLine(std::uint64_t revolution, const std_msgs::Header& header,
                    const DetectedObject& o) {
  char buf[512];
  const auto& c = o.obb_pose.position;
  const auto& d = o.obb_dimensions;
  std::snprintf(buf, sizeof buf, "%llu,%.6f,%s,%u,%s,%.4f,%u,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f",
                static_cast<unsigned long long>(revolution), header.stamp.toSec(),
                header.frame_id.c_str(), o.id, o.class_label.c_str(),
                static_cast<double>(o.class_confidence), o.point_count, c.x, c.y, c.z, d.x, d.y,
                d.z, yawOf(o.obb_pose.orientation));
  return buf;
}

}  // namespace ros_conv
}  // namespace urban_detection
