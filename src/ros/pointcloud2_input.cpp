#include "urban_detection/ros/pointcloud2_input.h"

#include "urban_detection/ros/cloud_serialization.h"

#include <cmath>
#include <cstring>
#include <limits>

#include <pcl_conversions/pcl_conversions.h>

namespace urban_detection {
namespace ros_conv {

namespace {

// A located field: byte offset in the point and PointField datatype (0 = absent).
struct Field {
  std::uint32_t offset = 0;
  std::uint8_t type = 0;
};

Field findField(const sensor_msgs::PointCloud2& msg, const char* name) {
  Field f;
  for (const sensor_msgs::PointField& pf : msg.fields) {
    if (pf.name == name && pf.count >= 1) {
      f.offset = pf.offset;
      f.type = pf.datatype;
    }
  }
  return f;
}

template <typename T>
T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

double read(const std::uint8_t* point, const Field& f) {
  using PF = sensor_msgs::PointField;
  const std::uint8_t* p = point + f.offset;
  switch (f.type) {
    case PF::INT8:
      return load<std::int8_t>(p);
    case PF::UINT8:
      return load<std::uint8_t>(p);
    case PF::INT16:
      return load<std::int16_t>(p);
    case PF::UINT16:
      return load<std::uint16_t>(p);
    case PF::INT32:
      return load<std::int32_t>(p);
    case PF::UINT32:
      return load<std::uint32_t>(p);
    case PF::FLOAT32:
      return load<float>(p);
    case PF::FLOAT64:
      return load<double>(p);
    default:
      return 0.0;
  }
}

}  // namespace

bool fromPointCloud2(const sensor_msgs::PointCloud2& msg, CloudXYZIRT* cloud,
                     PointCloud2InputInfo* info, std::string* error) {
  cloud->clear();
  *info = PointCloud2InputInfo();
  const Field fx = findField(msg, "x"), fy = findField(msg, "y"), fz = findField(msg, "z");
  if (fx.type == 0 || fy.type == 0 || fz.type == 0) {
    std::string present;
    for (const auto& f : msg.fields) present += (present.empty() ? "" : ", ") + f.name;
    *error = "PointCloud2 without x, y and z fields (fields: " +
             (present.empty() ? std::string("none") : present) + ")";
    return false;
  }
  CloudLayout layout;  // the checks of the typed subscriptions (cloud_serialization.h)
  layout.height = msg.height;
  layout.width = msg.width;
  layout.fields = msg.fields;
  layout.big_endian = msg.is_bigendian != 0;
  layout.point_step = msg.point_step;
  layout.row_step = msg.row_step;
  layout.data_size = msg.data.size();
  *error = checkCloudStamp(msg.header.stamp);
  if (error->empty()) *error = checkCloudLayout(layout, std::numeric_limits<std::size_t>::max());
  if (!error->empty()) return false;
  const Field fi = findField(msg, "intensity"), fr = findField(msg, "ring"),
              ft = findField(msg, "time");
  const std::size_t w = msg.width, h = msg.height;
  info->has_intensity = fi.type != 0;
  info->has_ring = fr.type != 0;
  info->has_time = ft.type != 0;

  cloud->resize(w * h);
  std::size_t k = 0;
  for (std::size_t r = 0; r < h; ++r) {
    const std::uint8_t* row = msg.data.data() + r * msg.row_step;
    for (std::size_t c = 0; c < w; ++c, ++k) {
      const std::uint8_t* pt = row + c * msg.point_step;
      PointXYZIRT& p = (*cloud)[k];
      p.x = static_cast<float>(read(pt, fx));
      p.y = static_cast<float>(read(pt, fy));
      p.z = static_cast<float>(read(pt, fz));
      p.intensity = fi.type ? static_cast<float>(read(pt, fi)) : 0.0f;
      p.ring = fr.type ? static_cast<std::uint16_t>(read(pt, fr)) : 0;
      p.time = ft.type ? static_cast<float>(read(pt, ft)) : 0.0f;
      info->non_finite += !isFinitePoint(p);
    }
  }
  cloud->width = static_cast<std::uint32_t>(w);
  cloud->height = static_cast<std::uint32_t>(h);
  cloud->is_dense = msg.is_dense;
  pcl_conversions::toPCL(msg.header, cloud->header);
  return true;
}

}  // namespace ros_conv
}  // namespace urban_detection
