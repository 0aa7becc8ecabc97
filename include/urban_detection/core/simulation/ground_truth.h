/// \file ground_truth.h
/// Per-point ground truth of simulated revolutions and its file format (ROS-free).
///
/// File format (little-endian, version 1), written by urban_detection_simulate:
/// ```
///   file   := "UDGT" u32 version(=1) frame*
///   frame  := "GTFR" u64 revolution f64 stamp_s u32 num_packets
///             f64 sensor_pose[7]            (x y z [m], qx qy qz qw: world_T_velodyne at stamp)
///             u32 n  u32 instance_id[n]  u8 class[n]
///             u32 m  object[m]
///   object := u32 instance_id u8 class u8 pad[3] f32 center[3] f32 size[3] f32 yaw
///             f32 velocity[3] u32 num_points  (52 bytes)
/// ```
/// `instance_id[i]`/`class[i]` label the i-th point of the decoded revolution (PacketDecoder
/// order: packet by packet, block by block, laser by laser, no-return and out-of-range skipped);
/// classes are ObjectClass values; instance 0 is background. Objects are given in the world
/// frame at the revolution stamp (box centre, length/width/height, yaw about z).
#pragma once

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/common/object_class.h"

namespace urban_detection {
namespace core {

class LidarSimulator;
struct SimRevolution;

/// One ground-truth object of a revolution.
struct GroundTruthObject {
  std::uint32_t instance_id = 0;
  ObjectClass object_class = ObjectClass::kUnlabeled;
  Eigen::Vector3f center = Eigen::Vector3f::Zero();    // [m] world, box centre
  Eigen::Vector3f size = Eigen::Vector3f::Zero();      // [m] length, width, height
  float yaw_rad = 0.0f;                                // [rad]
  Eigen::Vector3f velocity = Eigen::Vector3f::Zero();  // [m/s]
  std::uint32_t num_points = 0;                        // returns on it in this revolution
};

/// Ground truth of one revolution.
struct GroundTruthFrame {
  std::uint64_t revolution = 0;
  double stamp_s = 0.0;  // [s] epoch, = the VelodyneScan header stamp of the revolution
  std::uint32_t num_packets = 0;
  Eigen::Isometry3d sensor_pose = Eigen::Isometry3d::Identity();  // world_T_velodyne at stamp
  std::vector<std::uint32_t> instance_ids;                        // per decoded point
  std::vector<std::uint8_t> classes;       // per decoded point, ObjectClass values
  std::vector<GroundTruthObject> objects;  // every scene object, with its point count
};

/// Index of the frame whose stamp is within `tolerance_s` of `stamp_s` (a VelodyneScan header
/// stamp), or -1. Match frames by stamp, not by position: PacketSource/ScanAssembler drop the
/// first revolution of a stream (no cut observed before it) and pcap stores stamps to 1 us, so
/// the first scan replayed from a pcap is the simulator's revolution 1, stamped to +-0.5 us.
/// `frames` must be sorted by stamp (as written).
std::ptrdiff_t findGroundTruthFrame(const std::vector<GroundTruthFrame>& frames, double stamp_s,
                                    double tolerance_s = 5e-5);

/// Fills `frame` from a simulated revolution (objects of the simulator's scene).
void makeGroundTruthFrame(const LidarSimulator& sim, const SimRevolution& rev,
                          GroundTruthFrame* frame);

/// Raised on I/O errors and malformed files; the message names the file and the problem.
class GroundTruthError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes the format above.
class GroundTruthWriter {
 public:
  explicit GroundTruthWriter(const std::string& path);  // throws GroundTruthError
  void write(const GroundTruthFrame& frame);            // throws GroundTruthError
  void close();

 private:
  std::string path_;
  std::ofstream out_;
};

/// Reads the format above.
class GroundTruthReader {
 public:
  explicit GroundTruthReader(const std::string& path);  // throws GroundTruthError
  enum class Result { kFrame, kEnd, kCorrupt };
  /// kCorrupt: truncated or inconsistent frame (error() tells why); reading stops there.
  Result next(GroundTruthFrame* frame);
  const std::string& error() const { return error_; }
  /// Reads every frame; throws GroundTruthError on a corrupt file.
  static std::vector<GroundTruthFrame> readAll(const std::string& path);

 private:
  std::string path_;
  std::ifstream in_;
  std::string error_;
};

}  // namespace core
}  // namespace urban_detection
