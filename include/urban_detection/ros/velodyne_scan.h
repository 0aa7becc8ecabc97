/// \file velodyne_scan.h
/// urban_detection/VelodyneScan <-> packets and calibrated clouds.
///
/// ScanAssembler groups raw packets into one VelodyneScan per revolution (PacketSource);
/// decodeScan() turns a VelodyneScan into a CloudXYZIRT, optionally transforming each packet at
/// its own timestamp (PacketToCloud's per-packet motion compensation).
#pragma once

#include <ros/time.h>
#include <urban_detection/VelodyneScan.h>

#include <boost/shared_ptr.hpp>

#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <string>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace ros_conv {

/// Copies one raw packet and its stamp into a message packet.
void toMessage(const core::RawPacket& packet, const ros::Time& stamp, VelodynePacket* msg);

/// Which packet's stamp a revolution's header.stamp is, as velodyne_driver does: the last
/// packet's by default (parameter `timestamp_first_packet: false`), the first packet's when
/// `timestamp_first_packet` is true. The points' `time` field is always relative to the first
/// packet of the revolution.
enum class ScanStamp { kLastPacket, kFirstPacket };

/// Groups a stream of packets into whole revolutions cut at a fixed azimuth
/// (core::RevolutionBoundary). Only revolutions bounded by two observed cuts are returned: the
/// partial one at the start of a stream (and whatever is open when the stream ends) is dropped
/// and counted. Each returned revolution is a fresh message, so it can be published without copy.
class ScanAssembler {
 public:
  /// Safety limit when the azimuth never crosses the cut angle (sensor not spinning, garbage
  /// azimuths): the packets gathered so far are dropped and counted in forcedCuts().
  static constexpr std::size_t kMaxPacketsPerScan =
      core::RevolutionBoundary::kMaxPacketsPerRevolution;

  /// `cut_angle_deg` [deg, 0..360]; `frame_id` goes into every scan's header;
  /// `expected_packets` (0: unknown) sizes the first revolution's buffer (later ones take the
  /// size of the previous revolution) and is what lastSizeProblem() checks against; the cut
  /// stays by azimuth whatever the expectation.
  ScanAssembler(double cut_angle_deg, const std::string& frame_id, std::size_t expected_packets = 0,
                ScanStamp stamp = ScanStamp::kLastPacket);

  /// Adds a packet received at `stamp`. Returns the finished revolution when this packet
  /// starts a new one (the packet then opens the next scan), otherwise null. The scan's
  /// header.stamp follows the ScanStamp convention; header.seq counts the returned revolutions
  /// from 1, so a consumer can count revolutions it never received.
  VelodyneScan::Ptr add(const core::RawPacket& packet, const ros::Time& stamp);

  /// Drops the revolution in progress and restarts cut detection (a gap in the stream).
  void reset();
  /// A file's stream (re)starts: a first revolution that begins at the cut angle is whole
  /// (core::RevolutionBoundary::startFile, PcapRevolutionReader's rule).
  void startFile(double tolerance_deg);
  /// The file's stream ends: returns the open revolution when it is whole by
  /// PcapRevolutionReader's end rule, else null (dropped, counted as partial).
  VelodyneScan::Ptr finishFile();
  /// Adds `s` seconds to the stamps of the open revolution (a replay resumed after a pause).
  void shiftOpen(double s);

  /// Partial revolutions dropped (stream start, reset()).
  std::size_t partialDropped() const { return boundary_.partialDropped(); }
  /// Packet runs dropped at kMaxPacketsPerScan without any cut.
  std::size_t forcedCuts() const { return boundary_.forcedCuts(); }
  /// The revolution boundary: its counters of invalid, stray and reordered packets, and why
  /// the last skipped packet was invalid.
  const core::RevolutionBoundary& boundary() const { return boundary_; }
  /// Packets of the revolution returned last, and core::revolutionSizeProblem() of it against
  /// the expected count given at construction.
  std::size_t lastPackets() const { return last_packets_; }
  const char* lastSizeProblem() const {
    return core::revolutionSizeProblem(last_packets_, nominal_packets_);
  }

 private:
  core::RevolutionBoundary boundary_;
  std::string frame_id_;
  ScanStamp stamp_;
  VelodyneScan::Ptr current_;
  std::size_t expected_packets_ = 700;  // capacity hint: size of the previous revolution
  std::size_t nominal_packets_ = 0;     // the expected count (rate check; 0 = unknown)
  std::size_t last_packets_ = 0;
  std::uint32_t revolutions_ = 0;  // returned so far (header.seq)
  VelodyneScan::Ptr close();       // the open revolution, numbered and stamped
};

/// Counters of decodeScan().
struct ScanDecodeStats {
  core::DecodeStats decode;     // accumulated over the packets of the scan
  std::size_t tf_failures = 0;  // packets dropped because their transform was unavailable
  core::PacketStatus last_bad_status = core::PacketStatus::kOk;  // why the last bad packet failed
};

/// "" unless a revolution with decodable packets gave (almost) no point: then the cause,
/// for a WARN: every return beyond the decoder's range (at least 99 % of them out of
/// [min_range_m, max_range_m]: a blinded or covered sensor, or the range misconfigured), or no
/// return at all (raw distance 0 in every firing).
std::string emptyRevolutionCause(const core::DecodeStats& stats, const core::DecoderParams& params);

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

/// Decodes one packet stamped `stamp` of a revolution whose first packet is stamped `start`
/// and appends its points to `cloud` (transformed by `transform` unless it is null): the step
/// decodeScan() repeats over a scan and StreamingScanDecoder runs as each packet arrives.
void decodePacket(const core::PacketDecoder& decoder, const std::uint8_t* data, std::size_t size,
                  const ros::Time& stamp, const ros::Time& start, const Eigen::Affine3f* transform,
                  CloudXYZIRT* cloud, ScanDecodeStats* stats);

/// PacketSource's streaming path: decodes each packet as it arrives into the cloud of the open
/// revolution, cut exactly as ScanAssembler cuts (the same core::RevolutionBoundary), so that
/// when a revolution closes only its last packet is left to decode. The revolutions equal
/// ScanAssembler + decodeScan() point for point (a test checks it bit for bit); header.stamp
/// follows the ScanStamp convention, header.seq counts the returned revolutions from 1.
/// Points stay in the sensor frame (motion compensation is PacketToCloud's).
class StreamingScanDecoder {
 public:
  /// `decoder` must outlive this object.
  StreamingScanDecoder(const core::PacketDecoder* decoder, double cut_angle_deg,
                       const std::string& frame_id, std::size_t expected_packets = 0,
                       ScanStamp stamp = ScanStamp::kLastPacket);

  /// Decodes a packet received at `stamp`. Returns the finished revolution's cloud (fresh, for
  /// a zero-copy publish) when this packet starts a new revolution, otherwise null. `stats`
  /// of the returned revolution are in lastStats().
  boost::shared_ptr<CloudXYZIRT> add(const core::RawPacket& packet, const ros::Time& stamp);
  /// Drops the revolution in progress and restarts cut detection (a gap in the stream).
  void reset();
  /// As ScanAssembler::startFile / finishFile / shiftOpen.
  void startFile(double tolerance_deg);
  boost::shared_ptr<CloudXYZIRT> finishFile();
  void shiftOpen(double s);

  /// The cloud of the open revolution (its points so far; null before the first packet), the
  /// header.seq it will carry, and a count of the revolutions opened (changes whenever a new
  /// cloud starts, also after a dropped partial one): the sectors of PacketSource.
  const CloudXYZIRT* openCloud() const { return current_.get(); }
  std::uint32_t openSeq() const { return revolutions_ + 1; }
  std::uint64_t openedCount() const { return opened_; }

  /// Decode counters of the revolution returned last.
  const ScanDecodeStats& lastStats() const { return last_stats_; }
  /// Packets of the revolution returned last.
  std::size_t lastPackets() const { return last_packets_; }
  std::size_t partialDropped() const { return boundary_.partialDropped(); }
  std::size_t forcedCuts() const { return boundary_.forcedCuts(); }

 private:
  void open(const ros::Time& stamp);

  const core::PacketDecoder* decoder_;
  core::RevolutionBoundary boundary_;
  std::string frame_id_;
  ScanStamp stamp_;
  boost::shared_ptr<CloudXYZIRT> current_;
  ros::Time first_stamp_, last_stamp_;  // of the open revolution
  ScanDecodeStats stats_, last_stats_;
  std::size_t expected_packets_ = 700;
  std::size_t last_packets_ = 0;
  std::size_t nominal_packets_ = 0;
  std::uint32_t revolutions_ = 0;
  std::uint64_t opened_ = 0;
  boost::shared_ptr<CloudXYZIRT> close();
};

}  // namespace ros_conv
}  // namespace urban_detection
