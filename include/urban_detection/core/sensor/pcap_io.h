/// \file pcap_io.h
/// Reading and writing HDL-64E packets in pcap files (libpcap), ROS-free.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace core {

/// One Velodyne data packet read from a capture.
struct PcapPacket {
  double stamp_s = 0.0;  // [s] capture time (epoch)
  RawPacket data{};
};

/// Reads UDP payloads of 1206 bytes to a given port from a pcap file (Ethernet/IPv4/UDP or
/// Linux cooked captures). Other packets are skipped and counted.
class PcapReader {
 public:
  /// Throws std::runtime_error naming the file if it cannot be opened or is not a capture.
  explicit PcapReader(const std::string& path, int udp_port = 2368);
  ~PcapReader();

  enum class Result { kPacket, kEnd, kTruncated };
  /// Reads the next Velodyne data packet (a UDP payload of exactly 1206 bytes to the port;
  /// anything else, including IP fragments and records shorter than their headers claim, is
  /// skipped and counted). kEnd: clean end of file. kTruncated: the file ends inside a record or
  /// a record header is corrupt; nothing more can be read (rewind() to start over).
  Result next(PcapPacket* packet);
  void rewind();
  std::size_t skipped() const { return skipped_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t skipped_ = 0;
};

/// Whole revolutions of a capture, assembled by RevolutionBoundary exactly as the nodelets
/// assemble a live stream (invalid and stray packets skipped and counted, reordered ones kept),
/// the one way the bench, the evaluation and the tools cut a file. Two rules only a file
/// allows: its first revolution is whole when the first valid packet lies within
/// kStartToleranceDeg after the cut angle (a capture that starts at the cut, as the simulator
/// writes them), and at the end of the file the open revolution is returned when it began at a
/// cut and holds at least 90 % of the previous revolution's packets (of kNominalPackets when there
/// was none): a capture that stops mid-revolution loses only its tail.
class PcapRevolutionReader {
 public:
  static constexpr double kStartToleranceDeg = 2.0;    // one packet at 1200 rpm
  static constexpr std::size_t kNominalPackets = 347;  // one revolution at 600 rpm
  enum class Result { kRevolution, kEnd, kTruncated };

  /// Throws std::runtime_error naming the file (PcapReader).
  explicit PcapRevolutionReader(const std::string& path, double cut_angle_deg = 0.0);

  /// The next whole revolution's packets, in arrival order, into `packets` (its capacity is
  /// reused). kEnd / kTruncated: nothing more (PcapReader's meaning).
  Result next(std::vector<PcapPacket>* packets);
  /// Starts over from the first packet (a new stream: the first-revolution rule applies again).
  void rewind();

  const RevolutionBoundary& boundary() const { return boundary_; }
  std::size_t revolutions() const { return revolutions_; }  ///< returned so far

 private:
  PcapReader reader_;
  RevolutionBoundary boundary_;
  PcapPacket pending_;  // opens the next revolution
  bool has_pending_ = false;
  bool first_ = true;         // no revolution opened yet
  bool first_whole_ = false;  // the open revolution is the file's first and began at the cut
  bool done_ = false;
  PcapReader::Result end_ = PcapReader::Result::kEnd;
  std::size_t previous_packets_ = 0;
  std::size_t revolutions_ = 0;
};

/// The timeline of a capture's replay [s]: it follows the packets' capture times while they
/// advance sanely, and advances by the nominal packet period where they go back, stand still
/// or jump forward by more than `max_gap_s` (a clock stepped during the capture, a file with
/// zero times, a splice), so a replay paced on it keeps the sensor's rate through any of them.
/// Starts at the first packet's capture time.
class ReplayTimeline {
 public:
  enum class Anomaly { kNone, kBackwards, kStill, kJump };

  /// `nominal_gap_s`: one packet period (HDL-64E: 1/3472 s); `max_gap_s`: the largest gap
  /// between two packets taken as it was recorded.
  explicit ReplayTimeline(double nominal_gap_s = 1.0 / 3472.0, double max_gap_s = 1.0);

  /// Timeline time of the next packet, captured at `capture_s`; `anomaly` (optional) says how
  /// its capture time was off.
  double next(double capture_s, Anomaly* anomaly = nullptr);
  /// A new pass over the file (loop): the next packet comes one mean packet gap of the file
  /// (its sane gaps so far; the nominal period if none) after the last.
  void restart() { restarted_ = true; }

 private:
  double nominal_gap_s_, max_gap_s_;
  bool started_ = false, restarted_ = false;
  double last_capture_s_ = 0.0, now_s_ = 0.0;
  double sane_sum_s_ = 0.0;  // sum of the sane gaps (the file's own pace)
  std::size_t sane_gaps_ = 0;
};
const char* toString(ReplayTimeline::Anomaly anomaly);

/// Writes packets as Ethernet/IPv4/UDP frames from 192.168.3.43:2368 (sensor default) to
/// port 2368.
class PcapWriter {
 public:
  explicit PcapWriter(const std::string& path);
  ~PcapWriter();
  void write(const RawPacket& packet, double stamp_s);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace core
}  // namespace urban_detection
