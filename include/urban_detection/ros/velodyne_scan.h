/// \file velodyne_scan.h
/// urban_detection/VelodyneScan <-> packets and calibrated clouds.
///
/// ScanAssembler groups raw packets into one VelodyneScan per revolution (PacketSource);
/// decodeScan() turns a VelodyneScan into a CloudXYZIRT, optionally transforming each packet at
/// its own timestamp (PacketToCloud's per-packet motion compensation).
#pragma once

#include <ros/time.h>
#include <urban_detection/VelodyneScan.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <string>

#include "urban_detection/core/hdl64e_packet.h"
#include "urban_detection/core/point_types.h"

namespace urban_detection {

/// Copies one raw packet and its stamp into a message packet.
void toMessage(const core::RawPacket& packet, const ros::Time& stamp, VelodynePacket* msg);

/// Groups a stream of packets into whole revolutions cut at a fixed azimuth
/// (core::RevolutionCutter). Only revolutions bounded by two observed cuts are returned: the
/// partial one at the start of a stream (and whatever is open when the stream ends) is dropped
/// and counted. Each returned revolution is a fresh message, so it can be published without copy.
class ScanAssembler {
 public:
  /// Safety limit when the azimuth never crosses the cut angle (sensor not spinning, garbage
  /// azimuths): three revolutions at 300 rpm, the slowest HDL-64E setting. The packets
  /// gathered so far are dropped and counted in forcedCuts().
  static constexpr std::size_t kMaxPacketsPerScan = 3 * 695;

  /// `cut_angle_deg` [deg, 0..360]; `frame_id` goes into every scan's header;
  /// `expected_packets` sizes the first revolution's buffer (later ones take the size of the
  /// previous revolution); the cut stays by azimuth whatever the expectation.
  ScanAssembler(double cut_angle_deg, const std::string& frame_id,
                std::size_t expected_packets = 700);

  /// Adds a packet received at `stamp`. Returns the finished revolution when this packet
  /// starts a new one (the packet then opens the next scan), otherwise null. The scan's
  /// header.stamp is the stamp of its first packet; header.seq counts the returned revolutions
  /// from 1, so a consumer can count revolutions it never received.
  VelodyneScan::Ptr add(const core::RawPacket& packet, const ros::Time& stamp);

  /// Drops the revolution in progress and restarts cut detection (a gap in the stream).
  void reset();

  /// Partial revolutions dropped (stream start, reset()).
  std::size_t partialDropped() const { return partial_dropped_; }
  /// Packet runs dropped at kMaxPacketsPerScan without any cut.
  std::size_t forcedCuts() const { return forced_cuts_; }

 private:
  core::RevolutionCutter cutter_;
  std::string frame_id_;
  VelodyneScan::Ptr current_;
  bool current_is_whole_ = false;       // current_ was opened by an observed cut
  std::size_t expected_packets_ = 700;  // capacity hint: size of the previous revolution
  std::uint32_t revolutions_ = 0;       // returned so far (header.seq)
  std::size_t partial_dropped_ = 0;
  std::size_t forced_cuts_ = 0;
};

/// Counters of decodeScan().
struct ScanDecodeStats {
  core::DecodeStats decode;          // accumulated over the packets of the scan
  std::size_t tf_failures = 0;       // packets dropped because their transform was unavailable
  core::PacketStatus last_bad_status = core::PacketStatus::kOk;  // why the last bad packet failed
};

/// Transform to apply to the points of a packet stamped `packet_stamp`; returns false when it
/// is not available (the packet is then dropped and counted in tf_failures).
using PacketTransformFn =
    std::function<bool(const ros::Time& packet_stamp, Eigen::Affine3f* transform)>;

/// Decodes every packet of `scan` and appends the points to `cloud` (width/height/is_dense are
/// set, the header is left to the caller). A point's time [s] is its packet's stamp minus the
/// first packet's stamp plus the firing offset within the packet. Rejected packets contribute
/// nothing. `transform` may be empty (points stay in the sensor frame).
void decodeScan(const core::PacketDecoder& decoder, const VelodyneScan& scan,
                const PacketTransformFn& transform, CloudXYZIRT* cloud, ScanDecodeStats* stats);

}  // namespace urban_detection
