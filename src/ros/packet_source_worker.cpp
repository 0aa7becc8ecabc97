#include "urban_detection/ros/packet_source_worker.h"

#include <ros/console.h>
#include <ros/init.h>

#include <algorithm>
#include <chrono>

#include <pcl_conversions/pcl_conversions.h>
#include <boost/make_shared.hpp>

namespace urban_detection {
namespace ros_conv {

PacketSourceWorker::PacketSourceWorker(const PacketSourceParams& params,
                                       ros_conv::StageDiagnostics* diagnostics, PublishFn publish,
                                       ListenedFn scans_listened, PublishCloudFn publish_cloud,
                                       ListenedFn clouds_listened)
    : params_(params),
      diagnostics_(diagnostics),
      publish_(std::move(publish)),
      scans_listened_(std::move(scans_listened)),
      publish_cloud_(std::move(publish_cloud)),
      clouds_listened_(std::move(clouds_listened)),
      assembler_(params.cut_angle_deg, params.frame_id, params.expectedPacketsPerRevolution(),
                 params.timestamp_first_packet ? ScanStamp::kFirstPacket : ScanStamp::kLastPacket) {
  if (params_.decode) {
    if (!publish_cloud_ || !clouds_listened_) {
      throw std::invalid_argument("PacketSourceWorker: decode needs a cloud publish function");
    }
    decoder_ = std::make_unique<core::PacketDecoder>(core::loadCalibration(params_.calibration),
                                                     params_.decoder);
    streamer_ = std::make_unique<StreamingScanDecoder>(
        decoder_.get(), params_.cut_angle_deg, params_.frame_id,
        params_.expectedPacketsPerRevolution(),
        params_.timestamp_first_packet ? ScanStamp::kFirstPacket : ScanStamp::kLastPacket);
  }
  if (params_.pcap.empty()) {
    receiver_ = std::make_unique<core::UdpReceiver>(
        core::UdpReceiverParams{params_.port, params_.device_ip, params_.rcvbuf_bytes});
  } else {
    pcap_ = std::make_unique<core::PcapReader>(params_.pcap, params_.port);
  }
}

bool PacketSourceWorker::listened() const {
  return scans_listened_() || (clouds_listened_ && clouds_listened_());
}

PacketSourceWorker::~PacketSourceWorker() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void PacketSourceWorker::start() {
  running_ = true;
  thread_ = std::thread([this] { receiver_ ? udpLoop() : pcapLoop(); });
}

std::string PacketSourceWorker::describe() const {
  if (pcap_) return "pcap " + params_.pcap;
  return "UDP port " + std::to_string(receiver_->port()) +
         (params_.device_ip.empty() ? "" : " from " + params_.device_ip) + ", receive buffer " +
         std::to_string(receiver_->rcvbufBytes()) + " bytes";
}

std::string PacketSourceWorker::warning() const {
  if (!receiver_ || receiver_->rcvbufBytes() / 2 >= params_.rcvbuf_bytes) return "";
  return "UDP receive buffer limited to " + std::to_string(receiver_->rcvbufBytes() / 2) +
         " bytes instead of rcvbuf_bytes = " + std::to_string(params_.rcvbuf_bytes) +
         ": raise net.core.rmem_max (sysctl) or run with CAP_NET_ADMIN, or bursts may be lost";
}

void PacketSourceWorker::udpLoop() {
  core::RawPacket raw;
  std::size_t size = 0;
  auto last_packet = std::chrono::steady_clock::now();
  diagnostics_->setInputTimeouts(kNoSensorDataWarnS, kNoSensorDataErrorS);
  while (running_ && ros::ok()) {
    const core::UdpReceiver::Result result = receiver_->receive(&raw, 100, &size);
    const auto now = std::chrono::steady_clock::now();
    if (result == core::UdpReceiver::Result::kPacket) last_packet = now;
    const double silent_s = std::chrono::duration<double>(now - last_packet).count();
    if (silent_s >= kNoSensorDataErrorS) {
      ROS_ERROR_THROTTLE(30,
                         "PacketSource: no HDL-64E packet on %s for %.0f s (sensor off, "
                         "unplugged, another port or device_ip?)",
                         describe().c_str(), silent_s);
    } else if (silent_s >= kNoSensorDataWarnS) {
      ROS_WARN_THROTTLE(30, "PacketSource: no HDL-64E packet on %s for %.1f s", describe().c_str(),
                        silent_s);
    }
    switch (result) {
      case core::UdpReceiver::Result::kPacket:
        diagnostics_->setTotal("kernel_dropped_packets", receiver_->kernelDrops());
        addPacket(raw, ros::Time::now());
        break;
      case core::UdpReceiver::Result::kWrongSize:
        diagnostics_->count("bad_size_packets");
        ROS_WARN_THROTTLE(5,
                          "PacketSource: dropped a %zu-byte datagram (HDL-64E packets are "
                          "%zu bytes)",
                          size, core::kPacketSize);
        break;
      case core::UdpReceiver::Result::kOtherSender:
        diagnostics_->count("other_sender_packets");
        ROS_WARN_THROTTLE(5, "PacketSource: ignoring datagrams not from device_ip %s",
                          params_.device_ip.c_str());
        break;
      case core::UdpReceiver::Result::kError:
        if (diagnostics_->error("socket_errors", "UDP receive failed: " + receiver_->lastError())) {
          ROS_ERROR("PacketSource: UDP receive failed: %s", receiver_->lastError().c_str());
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        break;
      case core::UdpReceiver::Result::kTimeout:
        break;
    }
  }
}

// Replays at `rate` times the recorded speed (0: as fast as possible) on the capture's replay
// timeline (core::ReplayTimeline: capture times where they are sane, the nominal packet period
// where they go back, stand still or jump). Stamps are that timeline shifted so that the packet
// after every (re)start of the pacing is stamped "now": the first one, and the first after a
// pause without subscribers, so idle time never puts the stamps behind the clock
// (use_pcap_time: unshifted). They keep increasing across loops; intra-revolution time
// differences stay those of the sensor (a revolution open at a pause is shifted with it).
// Invalid packets (what the revolution boundary refuses) are counted but never advance the
// timeline, so garbage datagrams cannot slow the replay. Each pass over the file keeps its first
// and last revolutions when they are whole (PcapRevolutionReader's rules), so a looped replay
// gives every revolution of the file, as the offline tools read it.
void PacketSourceWorker::pcapLoop() {
  using Clock = std::chrono::steady_clock;
  core::PcapPacket packet;
  core::ReplayTimeline timeline;
  bool anchored = false, first = true;
  Clock::time_point wall_anchor;
  double replay_anchor_s = 0, stamp_offset_s = 0, replay_s = 0;
  std::size_t in_pass = 0, valid_in_pass = 0, anomalies = 0;
  ros::Time last_stamp;
  const auto startPass = [&] {
    assembler_.startFile(core::PcapRevolutionReader::kStartToleranceDeg);
    if (streamer_) streamer_->startFile(core::PcapRevolutionReader::kStartToleranceDeg);
    in_pass = valid_in_pass = 0;
  };
  startPass();
  while (running_ && ros::ok()) {
    if (!listened()) {  // lazy: pause, and resume without a burst
      anchored = false;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const core::PcapReader::Result result = pcap_->next(&packet);
    if (result != core::PcapReader::Result::kPacket) {
      finishPass();  // the open revolution, when whole
      if (result == core::PcapReader::Result::kTruncated) {
        diagnostics_->count("truncated_captures");
        const std::string text = "pcap '" + params_.pcap + "' is truncated after " +
                                 std::to_string(packets_) + " packets; replay stops";
        diagnostics_->setError(text);
        ROS_ERROR("PacketSource: %s", text.c_str());
        break;
      }
      if (valid_in_pass == 0) {
        const std::string text = "pcap '" + params_.pcap + "' has no HDL-64E packet for UDP port " +
                                 std::to_string(params_.port);
        diagnostics_->setError(text);
        ROS_ERROR("PacketSource: %s", text.c_str());
        break;
      }
      if (!params_.loop) break;
      pcap_->rewind();
      timeline.restart();
      startPass();  // never splice the end of the file to its start in one scan
      continue;
    }
    ++in_pass;
    if (core::PacketDecoder::validate(packet.data.data(), packet.data.size()) !=
        core::PacketStatus::kOk) {
      // Refused by the boundary (counted and warned there); never a step of the timeline.
      addPacket(packet.data, last_stamp);
      continue;
    }
    ++valid_in_pass;
    core::ReplayTimeline::Anomaly anomaly;
    replay_s = timeline.next(packet.stamp_s, &anomaly);
    if (anomaly != core::ReplayTimeline::Anomaly::kNone) {
      diagnostics_->setTotal("pcap_time_anomalies", ++anomalies);
      ROS_WARN_THROTTLE(5,
                        "PacketSource: pcap '%s', packet %lu: capture time %s (%.6f s); "
                        "pacing at the nominal packet rate until the times are sane again",
                        params_.pcap.c_str(), static_cast<unsigned long>(in_pass),
                        core::toString(anomaly), packet.stamp_s);
    }
    if (!anchored) {
      wall_anchor = Clock::now();
      replay_anchor_s = replay_s;
      anchored = true;
      if (!params_.use_pcap_time) {
        // This packet is stamped now: after a pause the stamps move on by the idle time.
        const double offset_s = ros::Time::now().toSec() - replay_s;
        if (!first && offset_s > stamp_offset_s) {
          assembler_.shiftOpen(offset_s - stamp_offset_s);
          if (streamer_) streamer_->shiftOpen(offset_s - stamp_offset_s);
        }
        if (first || offset_s > stamp_offset_s) stamp_offset_s = offset_s;
      }
      first = false;
    }
    if (params_.rate > 0) {
      const auto due =
          wall_anchor + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                            (replay_s - replay_anchor_s) / params_.rate));
      while (running_ && Clock::now() < due) {  // interruptible sleep
        std::this_thread::sleep_for(
            std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(50)));
      }
    }
    last_stamp = ros::Time(std::max(0.0, replay_s + stamp_offset_s));
    addPacket(packet.data, last_stamp);
  }
  assembler_.reset();  // a revolution open when the replay stops is partial
  if (streamer_) streamer_->reset();
  diagnostics_->setTotal("partial_revolutions_dropped", assembler_.partialDropped(), false);
  if (pcap_->skipped() > 0) {
    diagnostics_->setTotal("skipped_pcap_records", pcap_->skipped(), false);
    ROS_WARN("PacketSource: pcap '%s': skipped %lu records that are not HDL-64E data packets",
             params_.pcap.c_str(), static_cast<unsigned long>(pcap_->skipped()));
  }
  ROS_INFO("PacketSource: pcap replay finished: %lu packets, %lu revolutions",
           static_cast<unsigned long>(packets_), static_cast<unsigned long>(scans_));
  running_ = false;
}

void PacketSourceWorker::finishPass() {
  if (streamer_ && streaming_ && clouds_listened_()) {
    boost::shared_ptr<CloudXYZIRT> cloud = streamer_->finishFile();
    if (cloud) publish_cloud_(cloud);
  }
  VelodyneScan::Ptr scan = assembler_.finishFile();
  diagnostics_->setTotal("partial_revolutions_dropped", assembler_.partialDropped(), false);
  if (scan) emitScan(scan);
}

void PacketSourceWorker::addPacket(const core::RawPacket& packet, const ros::Time& stamp) {
  const auto start = std::chrono::steady_clock::now();
  ++packets_;
  diagnostics_->input();
  // Streaming decoding first: the closing packet hands the finished cloud on at once.
  if (streamer_) {
    if (clouds_listened_()) {
      streaming_ = true;
      boost::shared_ptr<CloudXYZIRT> cloud = streamer_->add(packet, stamp);
      if (cloud) {
        const ScanDecodeStats& stats = streamer_->lastStats();
        diagnostics_->count("bad_packets", stats.decode.bad_packets);
        const std::string empty = emptyRevolutionCause(stats.decode, decoder_->params());
        if (!empty.empty()) {
          diagnostics_->count("revolutions without points");
          ROS_WARN_THROTTLE(10, "PacketSource: %s", empty.c_str());
        }
        if (stats.decode.bad_packets > 0) {
          ROS_WARN_THROTTLE(5,
                            "PacketSource: dropped %zu of %zu packets of a revolution "
                            "(last: %s)",
                            stats.decode.bad_packets, streamer_->lastPackets(),
                            core::toString(stats.last_bad_status));
        }
        publish_cloud_(cloud);  // fresh, never touched again: zero copy inside the manager
      }
      if (publish_sector_) publishSector(stamp);
    } else if (streaming_) {  // nobody listens: the open revolution would be partial
      streamer_->reset();
      streaming_ = false;
    }
  }
  const std::size_t forced_before = assembler_.forcedCuts();
  const core::RevolutionBoundary& boundary = assembler_.boundary();
  const std::size_t invalid_before = boundary.invalidPackets();
  const std::size_t strays_before = boundary.strayPackets();
  VelodyneScan::Ptr scan = assembler_.add(packet, stamp);
  diagnostics_->setTotal("partial_revolutions_dropped", assembler_.partialDropped(), false);
  if (boundary.invalidPackets() != invalid_before) {  // in no revolution, never decoded
    diagnostics_->setTotal("invalid_packets", boundary.invalidPackets());
    if (boundary.lastStatus() == core::PacketStatus::kOtherModel) {
      ROS_WARN_THROTTLE(10,
                        "PacketSource: refusing packets of a %s: this package decodes "
                        "HDL-64E packets only",
                        core::velodyneModelName(packet.data(), packet.size()).c_str());
    } else {
      ROS_WARN_THROTTLE(5, "PacketSource: refusing invalid packets (last: %s)",
                        core::toString(boundary.lastStatus()));
    }
  }
  if (boundary.strayPackets() != strays_before) {
    diagnostics_->setTotal("stray_packets", boundary.strayPackets());
    ROS_WARN_THROTTLE(5,
                      "PacketSource: ignoring packets whose azimuth does not follow the "
                      "stream (another sender's, or corrupt)%s",
                      params_.device_ip.empty() ? "; set device_ip to accept one sensor only" : "");
  }
  diagnostics_->setTotal("reordered_packets", boundary.reorderedPackets(), false);
  if (assembler_.forcedCuts() != forced_before) {
    diagnostics_->setTotal("forced_cuts", assembler_.forcedCuts());
    ROS_WARN_THROTTLE(5,
                      "PacketSource: no revolution boundary at cut_angle %.2f deg within %zu "
                      "packets: dropped them (is the sensor spinning?)",
                      params_.cut_angle_deg, ScanAssembler::kMaxPacketsPerScan);
  }
  revolution_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (scan) emitScan(scan);
}

void PacketSourceWorker::setSectorOutput(PublishCloudFn publish_sector,
                                         ListenedFn sectors_listened) {
  if (!streamer_ || params_.sector_packets <= 0) return;
  publish_sector_ = std::move(publish_sector);
  sectors_listened_ = std::move(sectors_listened);
}

void PacketSourceWorker::publishSector(const ros::Time& stamp) {
  const CloudXYZIRT* open = streamer_->openCloud();
  if (!open) return;
  if (streamer_->openedCount() != sector_revolution_) {  // a new revolution: sectors from 0
    sector_revolution_ = streamer_->openedCount();
    sector_begin_ = 0;
    sector_packets_ = 0;
  }
  if (++sector_packets_ < static_cast<std::size_t>(params_.sector_packets)) return;
  sector_packets_ = 0;
  const std::size_t end = open->points.size();
  if (end <= sector_begin_ || !sectors_listened_()) {
    sector_begin_ = end;  // nobody listens: the next sector starts here (the receiver checks)
    return;
  }
  auto sector = boost::make_shared<CloudXYZIRT>();
  sector->header.frame_id = open->header.frame_id;
  sector->header.seq = streamer_->openSeq();
  sector->header.stamp = pcl_conversions::toPCL(stamp);
  sector->points.assign(open->points.begin() + static_cast<std::ptrdiff_t>(sector_begin_),
                        open->points.end());
  sector->width = static_cast<std::uint32_t>(sector->points.size());
  sector->height = 1;
  sector->is_dense = open->is_dense;
  sector_begin_ = end;
  publish_sector_(sector);  // fresh, never touched again
}

void PacketSourceWorker::emitScan(const VelodyneScan::Ptr& scan) {
  ++scans_;
  if (*assembler_.lastSizeProblem()) {
    diagnostics_->count(std::string("revolutions with ") + assembler_.lastSizeProblem());
    ROS_WARN_THROTTLE(5,
                      "PacketSource: a revolution of %zu packets, %s for %.0f rpm "
                      "(expected about %zu)",
                      assembler_.lastPackets(), assembler_.lastSizeProblem(), params_.rpm,
                      params_.expectedPacketsPerRevolution());
  }
  diagnostics_->frame(revolution_s_);
  revolution_s_ = 0.0;
  if (scans_listened_()) publish_(scan);  // a fresh message, never touched again: zero copy
  diagnostics_->output();
}

}  // namespace ros_conv
}  // namespace urban_detection
