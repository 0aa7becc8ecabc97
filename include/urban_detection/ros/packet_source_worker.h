/// \file packet_source_worker.h
/// The reading thread of the PacketSource nodelet: HDL-64E packets from a live UDP socket or a
/// paced pcap replay, grouped into one VelodyneScan per whole revolution (ScanAssembler) and
/// handed to a publish function; with `decode`, also decoded packet by packet as they arrive
/// (StreamingScanDecoder) into one cloud per revolution, handed over one packet after the
/// revolution's last. Counts everything that goes wrong on StageDiagnostics and logs
/// it throttled; never throws once started.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include <ros/time.h>

#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/core/sensor/udp_receiver.h"
#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {
namespace ros_conv {

class PacketSourceWorker {
 public:
  using PublishFn = std::function<void(const VelodyneScan::Ptr& scan)>;
  using PublishCloudFn = std::function<void(const boost::shared_ptr<CloudXYZIRT>& cloud)>;
  using ListenedFn = std::function<bool()>;  // whether an output has a subscriber

  /// Opens the socket or the capture; throws std::runtime_error / std::invalid_argument with
  /// the system's reason (port in use, missing file). `diagnostics` must outlive the worker.
  /// `scans_listened`: whether the scans have a subscriber; `publish_cloud` and
  /// `clouds_listened` are used with params.decode (the calibration is loaded then: throws
  /// core::CalibrationError naming the file).
  PacketSourceWorker(const PacketSourceParams& params, ros_conv::StageDiagnostics* diagnostics,
                     PublishFn publish, ListenedFn scans_listened,
                     PublishCloudFn publish_cloud = PublishCloudFn(),
                     ListenedFn clouds_listened = ListenedFn());
  ~PacketSourceWorker();  // stops and joins the thread

  /// With params.decode and params.sector_packets > 0: every sector_packets packets, the points
  /// of the open revolution decoded since the last sector are handed to `publish_sector` (a
  /// fresh cloud, header.seq = the seq the revolution's cloud will carry, header.stamp = the
  /// newest packet's) while `sectors_listened`. Call before start().
  void setSectorOutput(PublishCloudFn publish_sector, ListenedFn sectors_listened);
  /// Starts the reading thread. Live: the socket is read all the time, subscribers or not (an
  /// unread socket fills with stale packets a late subscriber would get first). Replay: pauses
  /// while nobody listens, so no recorded revolution is lost.
  void start();
  /// Whether the thread still runs (a replay stops at the end of the file or on a truncation).
  bool running() const { return running_; }
  /// The streaming decoder's calibration (params.decode), else null.
  const core::PacketDecoder* decoder() const { return decoder_.get(); }
  /// Human-readable description of the input ("UDP port 2368 ..." or "pcap file").
  std::string describe() const;
  /// A configuration problem worth a warning at start ("" if none): a receive buffer smaller
  /// than requested because of net.core.rmem_max.
  std::string warning() const;

 private:
  void udpLoop();
  void pcapLoop();
  void addPacket(const core::RawPacket& packet, const ros::Time& stamp);
  void emitScan(const VelodyneScan::Ptr& scan);  // a whole revolution: counted, published
  void finishPass();                             // end of a pass: its last revolution if whole

  PacketSourceParams params_;
  ros_conv::StageDiagnostics* diagnostics_;
  bool listened() const;

  PublishFn publish_;
  ListenedFn scans_listened_;
  PublishCloudFn publish_cloud_;
  ListenedFn clouds_listened_;
  std::unique_ptr<core::PacketDecoder> decoder_;
  std::unique_ptr<StreamingScanDecoder> streamer_;  // reading thread only
  bool streaming_ = false;  // streamer_ fed since its last reset (clouds listened)
  void publishSector(const ros::Time& stamp);
  PublishCloudFn publish_sector_;
  ListenedFn sectors_listened_;
  std::uint64_t sector_revolution_ = 0;  // streamer_->openedCount() of the sectors' revolution
  std::size_t sector_begin_ = 0;         // first point of the next sector in the open cloud
  std::size_t sector_packets_ = 0;       // packets since the last sector
  std::unique_ptr<core::UdpReceiver> receiver_;
  std::unique_ptr<core::PcapReader> pcap_;
  ScanAssembler assembler_;  // reading thread only
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::uint64_t packets_ = 0, scans_ = 0;
  double revolution_s_ = 0.0;  // [s] time spent on the packets of the open revolution
};

}  // namespace ros_conv
}  // namespace urban_detection
