// libFuzzer target: a sensor_msgs/PointCloud2 arriving as bytes from another process on a
// topic the pipeline subscribes with its PCL type (velodyne_points, segmentation/foreground),
// deserialised by the typed path (cloud_serialization.h) as roscpp does for such a
// subscription, into CloudXYZIRT and LabeledCloud.
//
// Checked: deserialisation never throws and never reads or writes outside the message (ASan);
// a cloud is either refused (no point, the reason in cloudRefusal()) or sound (width x height
// points, at most kMaxCloudPoints); a sound cloud re-serialises and reads back to the same
// points, bit for bit.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <ros/serialization.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "urban_detection/ros/cloud_serialization.h"

namespace ud = urban_detection;
namespace rc = urban_detection::ros_conv;
namespace ser = ros::serialization;

namespace {

template <typename PointT>
void check(const std::uint8_t* data, std::size_t size) {
  // Never a null buffer (roscpp never hands one over; ros::serialization's pointer arithmetic
  // on it is undefined).
  std::vector<std::uint8_t> bytes(size + 1);
  if (size > 0) std::memcpy(bytes.data(), data, size);
  pcl::PointCloud<PointT> cloud;
  ser::IStream in(bytes.data(), static_cast<std::uint32_t>(size));
  ser::deserialize(in, cloud);  // an exception escapes: a finding
  const std::string refusal = rc::cloudRefusal(cloud);
  if (!refusal.empty()) {
    if (!cloud.points.empty()) std::abort();  // a refused cloud carries no point
    return;
  }
  if (static_cast<std::uint64_t>(cloud.width) * cloud.height != cloud.points.size()) std::abort();
  if (cloud.points.size() > rc::kMaxCloudPoints) std::abort();
  // Round trip: what the pipeline would publish to another process reads back the same.
  std::vector<std::uint8_t> out(ser::serializationLength(cloud));
  ser::OStream os(out.data(), static_cast<std::uint32_t>(out.size()));
  ser::serialize(os, cloud);
  pcl::PointCloud<PointT> again;
  ser::IStream is(out.data(), static_cast<std::uint32_t>(out.size()));
  ser::deserialize(is, again);
  if (!rc::cloudRefusal(again).empty() || again.points.size() != cloud.points.size()) {
    std::abort();
  }
  if (!cloud.points.empty() && std::memcmp(again.points.data(), cloud.points.data(),
                                           cloud.points.size() * sizeof(PointT)) != 0) {
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  check<ud::PointXYZIRT>(data, size);
  check<ud::LabeledPoint>(data, size);
  return 0;
}
