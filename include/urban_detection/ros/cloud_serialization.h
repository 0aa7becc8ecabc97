/// \file cloud_serialization.h
/// The pipeline's PCL clouds (CloudXYZIRT, LabeledCloud) as ROS messages, deserialised with
/// every size checked. Include this header instead of <pcl_ros/point_cloud.h> wherever one of
/// these clouds is published or subscribed.
///
/// A typed subscription (`subscribe<CloudXYZIRT>`) gets a publisher of its own process as a
/// pointer (zero copy) and any other publisher's sensor_msgs/PointCloud2 (the same MD5) through
/// ros::serialization. pcl_ros's deserialiser trusts the message: it copies `data` into a
/// vector of width x height points whatever the data's size (a heap overflow when the data is
/// longer), reads rows of row_step bytes past a short buffer, takes point_step 0, duplicate or
/// out-of-point fields and big-endian data as they come, and builds its field mapping once from
/// the first message it sees. The serialiser below replaces it for the pipeline's point types:
/// it checks the layout (checkCloudLayout) and maps fields by name per message; a message that
/// fails is not converted but arrives as an empty cloud that carries the reason
/// (cloudRefusal()), so the subscriber logs it, counts it and goes on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <pcl/common/io.h>
#include <pcl_ros/point_cloud.h>
#include <sensor_msgs/PointField.h>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace ros_conv {

/// The most points a cloud on a pipeline topic may hold: three HDL-64E revolutions at 300 rpm
/// (3 x 695 packets of 384 returns), as CloudInput's default max_points.
constexpr std::size_t kMaxCloudPoints = 3 * 695 * 384;

/// What a serialised PointCloud2 declares before its data.
struct CloudLayout {
  std::uint32_t height = 0, width = 0;
  std::vector<sensor_msgs::PointField> fields;
  bool big_endian = false;
  std::uint32_t point_step = 0, row_step = 0;
  std::uint64_t data_size = 0;  // bytes of `data` actually present
};

/// One field copied from a serialised point into the point struct.
struct FieldCopy {
  std::uint32_t from = 0, to = 0, size = 0;  // [bytes] offset in the message point, the struct
};

/// "" when `layout` describes a sound cloud, else what is wrong, starting with a short kind
/// ("data size: ..."): data size other than row_step x height, row_step below width x
/// point_step, point_step 0 with points, more than `max_points` points, big-endian data, a
/// field named twice, a field beyond point_step or of an unknown datatype.
std::string checkCloudLayout(const CloudLayout& layout, std::size_t max_points = kMaxCloudPoints);

/// "" when `stamp` is a normalised time (nsec below 10^9), else what is wrong: PCL keeps
/// stamps in microseconds, and converting an unnormalised one back for publishing throws.
std::string checkCloudStamp(const ros::Time& stamp);

/// Maps the fields of `layout` onto the point struct's `wanted` fields by name: x, y and z
/// must be present, the others are zero when absent; a present field must have the struct's
/// datatype and count. Fills `copies` (adjacent fields merged); returns "" or what is wrong.
std::string mapCloudFields(const CloudLayout& layout, const std::vector<pcl::PCLPointField>& wanted,
                           std::vector<FieldCopy>* copies);

/// Prefix of the frame_id of a cloud the deserialiser refused (the reason follows).
constexpr const char* kRefusedFramePrefix = "urban_detection/refused: ";

/// "" when `cloud` may be processed, else why not: the reason the deserialiser refused it, a
/// point count other than width x height, or more than `max_points` points (a cloud from a
/// publisher in this process arrives unchecked).
template <typename PointT>
std::string cloudRefusal(const pcl::PointCloud<PointT>& cloud,
                         std::size_t max_points = kMaxCloudPoints) {
  const std::string& frame = cloud.header.frame_id;
  const std::size_t prefix = std::strlen(kRefusedFramePrefix);
  if (cloud.points.empty() && frame.compare(0, prefix, kRefusedFramePrefix) == 0) {
    return frame.substr(prefix);
  }
  const std::uint64_t declared = static_cast<std::uint64_t>(cloud.width) * cloud.height;
  if (declared != cloud.points.size()) {
    return "point count: " + std::to_string(cloud.points.size()) + " points, width x height " +
           std::to_string(declared);
  }
  if (cloud.points.size() > max_points) {
    return "too many points: " + std::to_string(cloud.points.size()) + " points, at most " +
           std::to_string(max_points);
  }
  return "";
}

namespace detail {

/// Reads the fields array without trusting its count: roscpp's vector reader resizes to the
/// count before it reads, so a count of 2^32-1 would allocate ~200 GB.
template <typename Stream>
void readFields(Stream& stream, std::vector<sensor_msgs::PointField>* fields) {
  std::uint32_t count = 0;
  stream.next(count);
  constexpr std::uint32_t kMinFieldBytes = 4 + 4 + 1 + 4;  // empty name, offset, type, count
  if (count > stream.getLength() / kMinFieldBytes) {
    throw ros::serialization::StreamOverrunException("PointField count beyond the message");
  }
  fields->resize(count);
  for (sensor_msgs::PointField& f : *fields) stream.next(f);
}

/// pcl_ros's Serializer<pcl::PointCloud<T>> with a checked read().
template <typename T>
struct CheckedCloudSerializer {
  template <typename Stream>
  static void write(Stream& stream, const pcl::PointCloud<T>& m) {
    stream.next(m.header);
    std::uint32_t height = m.height, width = m.width;
    // pcl_ros copies width x height points whatever points.size() holds.
    if (static_cast<std::uint64_t>(width) * height != m.points.size()) {
      width = static_cast<std::uint32_t>(m.points.size());
      height = 1;
    }
    stream.next(height);
    stream.next(width);
    using FieldList = typename pcl::traits::fieldList<T>::type;
    std::uint32_t fields_size = boost::mpl::size<FieldList>::value;
    stream.next(fields_size);
    pcl::for_each_type<FieldList>(pcl::detail::FieldStreamer<Stream, T>(stream));
    std::uint8_t is_bigendian = false;
    stream.next(is_bigendian);
    std::uint32_t point_step = sizeof(T);
    stream.next(point_step);
    std::uint32_t row_step = point_step * width;
    stream.next(row_step);
    std::uint32_t data_size = row_step * height;
    stream.next(data_size);
    std::uint8_t* out = stream.advance(data_size);
    if (data_size > 0) std::memcpy(out, m.points.data(), data_size);  // no point: data() is null
    std::uint8_t is_dense = m.is_dense;
    stream.next(is_dense);
  }

  template <typename Stream>
  static void read(Stream& stream, pcl::PointCloud<T>& m) {
    std_msgs::Header header;
    CloudLayout layout;
    std::string error;
    const std::uint8_t* data = nullptr;
    std::uint8_t is_dense = 0;
    try {
      stream.next(header);
      stream.next(layout.height);
      stream.next(layout.width);
      readFields(stream, &layout.fields);
      std::uint8_t big_endian = 0;
      stream.next(big_endian);
      layout.big_endian = big_endian != 0;
      stream.next(layout.point_step);
      stream.next(layout.row_step);
      std::uint32_t data_size = 0;
      stream.next(data_size);
      layout.data_size = data_size;
      data = stream.advance(data_size);  // throws when the message holds fewer bytes
      stream.next(is_dense);
    } catch (const ros::serialization::StreamOverrunException&) {
      error = "truncated message: shorter than its own sizes (data " +
              std::to_string(layout.data_size) + " bytes declared)";
    }
    std::vector<FieldCopy> copies;
    if (error.empty()) error = checkCloudStamp(header.stamp);
    if (error.empty()) error = checkCloudLayout(layout);
    if (error.empty()) error = mapCloudFields(layout, pcl::getFields<T>(), &copies);
    if (!error.empty()) header.stamp = ros::Time();  // possibly unnormalised: not converted
    pcl_conversions::toPCL(header, m.header);
    m.points.clear();
    if (!error.empty()) {
      m.width = m.height = 0;
      m.is_dense = false;
      m.header.frame_id = kRefusedFramePrefix + error;
      return;
    }
    m.height = layout.height;
    m.width = layout.width;
    m.is_dense = is_dense != 0;
    m.points.resize(static_cast<std::size_t>(layout.width) * layout.height);
    if (m.points.empty()) return;  // e.g. width 0 and a height of 10^9: no row to walk
    auto* out = reinterpret_cast<std::uint8_t*>(m.points.data());
    for (std::uint32_t row = 0; row < layout.height; ++row) {
      const std::uint8_t* in = data + static_cast<std::size_t>(row) * layout.row_step;
      for (std::uint32_t col = 0; col < layout.width; ++col, in += layout.point_step) {
        for (const FieldCopy& c : copies) std::memcpy(out + c.to, in + c.from, c.size);
        out += sizeof(T);
      }
    }
  }

  static std::uint32_t serializedLength(const pcl::PointCloud<T>& m) {
    std::uint32_t length = ros::serialization::serializationLength(m.header);
    length += 8;  // height, width
    pcl::detail::FieldsLength<T> fl;
    using FieldList = typename pcl::traits::fieldList<T>::type;
    pcl::for_each_type<FieldList>(boost::ref(fl));
    length += 4 + fl.length;  // fields
    length += 1 + 4 + 4 + 4;  // is_bigendian, point_step, row_step, size of data
    length += static_cast<std::uint32_t>(m.points.size() * sizeof(T));
    length += 1;  // is_dense
    return length;
  }
};

}  // namespace detail
}  // namespace ros_conv
}  // namespace urban_detection

namespace ros {
namespace serialization {
template <>
struct Serializer<pcl::PointCloud<urban_detection::PointXYZIRT>>
    : urban_detection::ros_conv::detail::CheckedCloudSerializer<urban_detection::PointXYZIRT> {};
template <>
struct Serializer<pcl::PointCloud<urban_detection::LabeledPoint>>
    : urban_detection::ros_conv::detail::CheckedCloudSerializer<urban_detection::LabeledPoint> {};
}  // namespace serialization
}  // namespace ros
