#include "urban_detection/ros/simulation_conversions.h"

#include <algorithm>

#include <rosbag/bag.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <topic_tools/shape_shifter.h>

#include "urban_detection/core/common/object_class.h"

namespace urban_detection {
namespace ros_conv {

// The message constants document the core enum; keep them in step.
static_assert(GroundTruth::BENCH == static_cast<std::uint8_t>(core::ObjectClass::kBench) &&
                  GroundTruth::CAR == static_cast<std::uint8_t>(core::ObjectClass::kCar) &&
                  GroundTruth::GROUND == static_cast<std::uint8_t>(core::ObjectClass::kGround) &&
                  GroundTruth::PEDESTRIAN ==
                      static_cast<std::uint8_t>(core::ObjectClass::kPedestrian) &&
                  GroundTruth::VEGETATION ==
                      static_cast<std::uint8_t>(core::ObjectClass::kVegetation) &&
                  GroundTruth::TERRAIN == static_cast<std::uint8_t>(core::ObjectClass::kTerrain) &&
                  core::kNumObjectClasses == 14,
              "GroundTruth.msg constants and core::ObjectClass differ");

double revolutionStamp(const core::SimRevolution& rev, ScanStamp stamp) {
  if (stamp == ScanStamp::kFirstPacket || rev.packet_stamps_s.empty()) return rev.stamp_s;
  return rev.packet_stamps_s.back();
}

void toScanMsg(const core::SimRevolution& rev, const std::string& frame_id,
               urban_detection::VelodyneScan* msg, ScanStamp stamp) {
  msg->header.stamp.fromSec(revolutionStamp(rev, stamp));
  msg->header.frame_id = frame_id;
  msg->packets.resize(rev.packets.size());
  for (std::size_t i = 0; i < rev.packets.size(); ++i) {
    msg->packets[i].stamp.fromSec(rev.packet_stamps_s[i]);
    std::copy(rev.packets[i].begin(), rev.packets[i].end(), msg->packets[i].data.begin());
  }
}

void toGroundTruthMsg(const core::SimRevolution& rev, const std::string& frame_id,
                      urban_detection::GroundTruth* msg, ScanStamp stamp) {
  msg->header.stamp.fromSec(revolutionStamp(rev, stamp));
  msg->header.frame_id = frame_id;
  msg->revolution = static_cast<std::uint32_t>(rev.index);
  msg->instance_ids = rev.instance_ids;
  msg->classes = rev.classes;
}

void toTransforms(const core::LidarSimulator& sim, double t_s, double stamp_s,
                  const SimulationFrames& frames, geometry_msgs::TransformStamped* odom_base,
                  geometry_msgs::TransformStamped* base_sensor) {
  *odom_base = tf2::eigenToTransform(sim.basePose(t_s));
  odom_base->header.stamp.fromSec(stamp_s);
  odom_base->header.frame_id = frames.odom;
  odom_base->child_frame_id = frames.base_link;
  *base_sensor = tf2::eigenToTransform(sim.baseToSensor());
  base_sensor->header.stamp.fromSec(stamp_s);
  base_sensor->header.frame_id = frames.base_link;
  base_sensor->child_frame_id = frames.sensor;
}

namespace {

// The message definition a velodyne driver's bag carries: ours with the package of the scan
// and packet types renamed (the MD5 sum does not depend on the package name).
std::string velodyneMsgsDefinition() {
  std::string def = ros::message_traits::Definition<urban_detection::VelodyneScan>::value();
  const std::string from = "urban_detection/VelodynePacket", to = "velodyne_msgs/VelodynePacket";
  for (std::size_t at = def.find(from); at != std::string::npos; at = def.find(from, at)) {
    def.replace(at, from.size(), to);
    at += to.size();
  }
  return def;
}

}  // namespace

topic_tools::ShapeShifter asVelodyneMsgsScan(const urban_detection::VelodyneScan& scan) {
  static const std::string definition = velodyneMsgsDefinition();
  std::vector<std::uint8_t> buffer(ros::serialization::serializationLength(scan));
  ros::serialization::OStream out(buffer.data(), static_cast<std::uint32_t>(buffer.size()));
  ros::serialization::serialize(out, scan);
  topic_tools::ShapeShifter shifter;
  shifter.morph(ros::message_traits::MD5Sum<urban_detection::VelodyneScan>::value(),
                kVelodyneMsgsScanType, definition, "false");
  ros::serialization::IStream in(buffer.data(), static_cast<std::uint32_t>(buffer.size()));
  shifter.read(in);
  return shifter;
}

SimulationBagWriter::SimulationBagWriter(const std::string& path, const SimulationFrames& frames)
    : bag_(std::make_unique<rosbag::Bag>(path, rosbag::bagmode::Write)), frames_(frames) {}

SimulationBagWriter::~SimulationBagWriter() {
  close();
}

void SimulationBagWriter::write(const core::LidarSimulator& sim, const core::SimRevolution& rev) {
  if (!bag_ || rev.packets.empty()) return;
  const ros::Time stamp = ros::Time().fromSec(rev.stamp_s);
  geometry_msgs::TransformStamped odom_base, base_sensor;
  toTransforms(sim, rev.start_time_s, rev.stamp_s, frames_, &odom_base, &base_sensor);
  if (!static_written_) {
    tf2_msgs::TFMessage tf_static;
    tf_static.transforms.push_back(base_sensor);
    bag_->write("/tf_static", stamp, tf_static);
    static_written_ = true;
  }
  // The platform pose at the start of every revolution; the pose at the end of the last one
  // is added by close(), so every packet stamp lies between two samples (tf interpolates).
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(odom_base);
  bag_->write("/tf", stamp, tf);
  const double rev_s = 60.0 / sim.sensorParams().rpm;
  toTransforms(sim, rev.start_time_s + rev_s, rev.stamp_s + rev_s, frames_, &end_pose_,
               &base_sensor);
  urban_detection::VelodyneScan scan;
  toScanMsg(rev, frames_.sensor, &scan);
  // Recorded like a driver: the scan arrives with its last packet, as velodyne_msgs/VelodyneScan.
  const ros::Time arrival = ros::Time().fromSec(rev.packet_stamps_s.back());
  bag_->write("/velodyne_packets", arrival, asVelodyneMsgsScan(scan));
  urban_detection::GroundTruth gt;
  toGroundTruthMsg(rev, frames_.sensor, &gt);
  bag_->write("/ground_truth", arrival, gt);
  have_end_pose_ = true;
}

void SimulationBagWriter::close() {
  if (bag_) {
    if (have_end_pose_) {
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(end_pose_);
      bag_->write("/tf", end_pose_.header.stamp, tf);
    }
    bag_->close();
    bag_.reset();
  }
}

}  // namespace ros_conv
}  // namespace urban_detection
