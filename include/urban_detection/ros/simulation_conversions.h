/// \file simulation_conversions.h
/// ROS messages of the simulated HDL-64E drive: VelodyneScan, GroundTruth and tf transforms
/// built from core::SimRevolution, and a rosbag writer used by urban_detection_simulate.
#pragma once

#include <memory>
#include <string>

#include "urban_detection/ros/velodyne_scan.h"

#include <geometry_msgs/TransformStamped.h>
#include <urban_detection/GroundTruth.h>
#include <urban_detection/VelodyneScan.h>

#include "urban_detection/core/simulation/lidar_simulator.h"

namespace rosbag {
class Bag;
}
namespace topic_tools {
class ShapeShifter;
}

namespace urban_detection {
namespace ros_conv {

/// Frame names of the simulated platform.
struct SimulationFrames {
  std::string odom = "odom";            // world frame of the scene
  std::string base_link = "base_link";  // platform, on the ground under the sensor
  std::string sensor = "velodyne";      // sensor frame (frame_id of scans and ground truth)
};

/// The header stamp of a simulated revolution under the ScanStamp convention: its last
/// packet's stamp (velodyne_driver's default) or its first packet's.
double revolutionStamp(const core::SimRevolution& rev, ScanStamp stamp);
/// Scan of one revolution: header stamp by `stamp` (revolutionStamp), one packet per RawPacket.
void toScanMsg(const core::SimRevolution& rev, const std::string& frame_id,
               urban_detection::VelodyneScan* msg, ScanStamp stamp = ScanStamp::kLastPacket);
/// Ground truth of one revolution (the same header stamp as toScanMsg with the same `stamp`).
void toGroundTruthMsg(const core::SimRevolution& rev, const std::string& frame_id,
                      urban_detection::GroundTruth* msg, ScanStamp stamp = ScanStamp::kLastPacket);
/// odom -> base_link at drive time `t_s` (stamped `stamp_s`), and base_link -> sensor.
void toTransforms(const core::LidarSimulator& sim, double t_s, double stamp_s,
                  const SimulationFrames& frames, geometry_msgs::TransformStamped* odom_base,
                  geometry_msgs::TransformStamped* base_sensor);

/// The connection type of scans in a velodyne driver's bag; urban_detection/VelodyneScan has the
/// same MD5 sum and layout, so either type name reads the other's messages.
constexpr const char* kVelodyneMsgsScanType = "velodyne_msgs/VelodyneScan";

/// `scan` serialised under the type name kVelodyneMsgsScanType (same MD5 sum, the message
/// definition with velodyne_msgs/ type names), for writing into a bag as a driver would.
topic_tools::ShapeShifter asVelodyneMsgsScan(const urban_detection::VelodyneScan& scan);

/// Writes a simulated drive into a bag: `/velodyne_packets` (velodyne_msgs/VelodyneScan, as
/// velodyne drivers record it; instantiates as urban_detection::VelodyneScan too),
/// `/ground_truth` (GroundTruth), `/tf` (odom -> base_link at every revolution start and at
/// the end of the last one; tf interpolates in between) and `/tf_static` (base_link -> velodyne).
class SimulationBagWriter {
 public:
  /// Throws rosbag::BagException if the file cannot be created.
  SimulationBagWriter(const std::string& path, const SimulationFrames& frames = {});
  ~SimulationBagWriter();
  void write(const core::LidarSimulator& sim, const core::SimRevolution& rev);
  void close();

 private:
  std::unique_ptr<rosbag::Bag> bag_;
  SimulationFrames frames_;
  bool static_written_ = false;
  bool have_end_pose_ = false;
  geometry_msgs::TransformStamped end_pose_;  // odom -> base_link at the last revolution's end
};

}  // namespace ros_conv
}  // namespace urban_detection
