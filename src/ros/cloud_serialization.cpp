#include "urban_detection/ros/cloud_serialization.h"

#include <algorithm>
#include <set>

namespace urban_detection {
namespace ros_conv {

namespace {

std::uint32_t datatypeSize(std::uint8_t datatype) {
  switch (datatype) {
    case sensor_msgs::PointField::INT8:
    case sensor_msgs::PointField::UINT8:
      return 1;
    case sensor_msgs::PointField::INT16:
    case sensor_msgs::PointField::UINT16:
      return 2;
    case sensor_msgs::PointField::INT32:
    case sensor_msgs::PointField::UINT32:
    case sensor_msgs::PointField::FLOAT32:
      return 4;
    case sensor_msgs::PointField::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

const char* datatypeName(std::uint8_t datatype) {
  static const char* const kNames[] = {"?",     "INT8",   "UINT8",   "INT16",  "UINT16",
                                       "INT32", "UINT32", "FLOAT32", "FLOAT64"};
  return datatype <= 8 ? kNames[datatype] : "?";
}

std::string u64(std::uint64_t v) {
  return std::to_string(v);
}

}  // namespace

std::string checkCloudStamp(const ros::Time& stamp) {
  if (stamp.nsec < 1000000000u) return "";
  return "bad stamp: nsec " + u64(stamp.nsec) + " not below 10^9";
}

std::string checkCloudLayout(const CloudLayout& l, std::size_t max_points) {
  const std::uint64_t points = static_cast<std::uint64_t>(l.width) * l.height;
  if (points > max_points) {
    return "too many points: width x height = " + u64(points) + ", at most " + u64(max_points);
  }
  if (l.big_endian) return "big-endian data: only little-endian clouds are read";
  if (points > 0 && l.point_step == 0) return "point_step 0 with " + u64(points) + " points";
  const std::uint64_t min_row = static_cast<std::uint64_t>(l.width) * l.point_step;
  if (points > 0 && l.row_step < min_row) {
    return "row_step too small: " + u64(l.row_step) +
           " bytes for width x point_step = " + u64(min_row);
  }
  const std::uint64_t declared = static_cast<std::uint64_t>(l.row_step) * l.height;
  if (l.data_size > declared) {
    return "data longer than row_step x height: " + u64(l.data_size) + " bytes for " +
           u64(declared);
  }
  if (l.data_size < declared) {
    return "data shorter than row_step x height: " + u64(l.data_size) + " bytes for " +
           u64(declared);
  }
  std::set<std::string> names;
  for (const sensor_msgs::PointField& f : l.fields) {
    if (!names.insert(f.name).second) return "duplicate field: '" + f.name + "' defined twice";
    const std::uint32_t size = datatypeSize(f.datatype);
    if (size == 0) {
      return "unknown field datatype: '" + f.name + "' has datatype " + u64(f.datatype);
    }
    const std::uint64_t end = static_cast<std::uint64_t>(f.offset) + std::uint64_t{size} * f.count;
    if (end > l.point_step) {
      return "field beyond point_step: '" + f.name + "' ends at byte " + u64(end) + " of a " +
             u64(l.point_step) + "-byte point";
    }
  }
  return "";
}

std::string mapCloudFields(const CloudLayout& layout, const std::vector<pcl::PCLPointField>& wanted,
                           std::vector<FieldCopy>* copies) {
  copies->clear();
  for (const pcl::PCLPointField& w : wanted) {
    if (w.name == "_") continue;  // PCL's padding
    const auto f = std::find_if(layout.fields.begin(), layout.fields.end(),
                                [&](const sensor_msgs::PointField& m) { return m.name == w.name; });
    if (f == layout.fields.end()) {
      if (w.name == "x" || w.name == "y" || w.name == "z") {
        std::string present;
        for (const auto& m : layout.fields) present += (present.empty() ? "" : " ") + m.name;
        return "missing field: no '" + w.name +
               "' (fields: " + (present.empty() ? std::string("none") : present) + ")";
      }
      continue;  // left zero
    }
    const std::uint32_t count = std::max<std::uint32_t>(w.count, 1);
    if (f->datatype != w.datatype || std::max<std::uint32_t>(f->count, 1) != count) {
      return "field type: '" + w.name + "' is " + datatypeName(f->datatype) + " x" + u64(f->count) +
             ", this topic needs " + datatypeName(w.datatype) + " x" + u64(count) +
             " (CloudInput on points_in converts any numeric type)";
    }
    copies->push_back({f->offset, w.offset, datatypeSize(w.datatype) * count});
  }
  // Fields adjacent in both layouts are copied in one go.
  std::sort(copies->begin(), copies->end(),
            [](const FieldCopy& a, const FieldCopy& b) { return a.to < b.to; });
  std::vector<FieldCopy> merged;
  for (const FieldCopy& c : *copies) {
    if (!merged.empty() && merged.back().from + merged.back().size == c.from &&
        merged.back().to + merged.back().size == c.to) {
      merged.back().size += c.size;
    } else {
      merged.push_back(c);
    }
  }
  copies->swap(merged);
  return "";
}

}  // namespace ros_conv
}  // namespace urban_detection
