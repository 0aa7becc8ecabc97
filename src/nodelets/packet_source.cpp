// urban_detection/PacketSource: HDL-64E packets from a live UDP socket or a pcap replay,
// published as one urban_detection/VelodyneScan per whole revolution on `velodyne_packets`
// (the partial revolutions at the start and the end of a stream are dropped).
//
// Laziness: the live socket is read all the time, subscribers or not. A sensor does not stop
// sending; an unread socket fills its buffer with stale packets that a late subscriber would
// get first, and draining it costs little. Publishing to no subscriber costs nothing in roscpp.
// A pcap replay, however, pauses while nobody subscribes, so no recorded revolution is lost.
#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>

#include "urban_detection/core/pcap_io.h"
#include "urban_detection/core/udp_receiver.h"
#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {

class PacketSource : public nodelet::Nodelet {
 public:
  ~PacketSource() override {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }

 private:
  void onInit() override {
    try {
      params_ = loadPacketSourceParams(getPrivateNodeHandle());
      if (params_.pcap.empty()) {
        receiver_ = std::make_unique<core::UdpReceiver>(core::UdpReceiverParams{
            params_.port, params_.device_ip, params_.rcvbuf_bytes});
      } else {
        pcap_ = std::make_unique<core::PcapReader>(params_.pcap, params_.port);
      }
    } catch (const std::exception& e) {  // ParamError, socket or file errors
      NODELET_FATAL("PacketSource inactive: %s", e.what());
      return;
    }
    assembler_ = std::make_unique<ScanAssembler>(params_.cut_angle_deg, params_.frame_id);
    pub_ = getNodeHandle().advertise<VelodyneScan>("velodyne_packets", params_.queue_size);
    updater_ = std::make_unique<diagnostic_updater::Updater>(getNodeHandle(),
                                                             getPrivateNodeHandle(), getName());
    updater_->setHardwareID(params_.pcap.empty() ? "HDL-64E udp:" + std::to_string(params_.port)
                                                 : "pcap:" + params_.pcap);
    updater_->add("packets", this, &PacketSource::diagnose);
    diag_timer_ = getNodeHandle().createWallTimer(ros::WallDuration(0.5),
                                                  [this](const ros::WallTimerEvent&) {
                                                    updater_->update();
                                                  });
    if (receiver_ && receiver_->rcvbufBytes() / 2 < params_.rcvbuf_bytes) {
      NODELET_WARN("UDP receive buffer limited to %d bytes instead of rcvbuf_bytes = %d: raise "
                   "net.core.rmem_max (sysctl) or run with CAP_NET_ADMIN, or bursts may be lost",
                   receiver_->rcvbufBytes() / 2, params_.rcvbuf_bytes);
    }
    if (receiver_) {
      NODELET_INFO("PacketSource: UDP port %d%s%s, receive buffer %d bytes", receiver_->port(),
                   params_.device_ip.empty() ? "" : " from ", params_.device_ip.c_str(),
                   receiver_->rcvbufBytes());
    }
    running_ = true;
    thread_ = std::thread([this] { receiver_ ? udpLoop() : pcapLoop(); });
  }

  void udpLoop() {
    core::RawPacket raw;
    std::size_t size = 0;
    while (running_ && ros::ok()) {
      switch (receiver_->receive(&raw, 100, &size)) {
        case core::UdpReceiver::Result::kPacket:
          addPacket(raw, ros::Time::now());
          break;
        case core::UdpReceiver::Result::kWrongSize:
          ++bad_size_;
          NODELET_WARN_THROTTLE(5, "dropped a %zu-byte datagram (HDL-64E packets are %zu bytes); "
                                   "%lu dropped so far", size, core::kPacketSize,
                                static_cast<unsigned long>(bad_size_));
          break;
        case core::UdpReceiver::Result::kOtherSender:
          ++other_sender_;
          NODELET_WARN_THROTTLE(5, "ignoring datagrams not from device_ip %s (%lu so far)",
                                params_.device_ip.c_str(),
                                static_cast<unsigned long>(other_sender_));
          break;
        case core::UdpReceiver::Result::kError:
          NODELET_ERROR_THROTTLE(5, "UDP receive failed: %s", receiver_->lastError().c_str());
          std::this_thread::sleep_for(std::chrono::milliseconds(100));
          break;
        case core::UdpReceiver::Result::kTimeout:
          break;
      }
    }
  }

  // Replays at `rate` times the recorded speed (0: as fast as possible). Stamps are the capture
  // times shifted so that the first packet is stamped "now" (use_pcap_time: unshifted), and keep
  // increasing across loops; intra-revolution time differences stay those of the sensor.
  void pcapLoop() {
    using Clock = std::chrono::steady_clock;
    core::PcapPacket packet;
    bool anchored = false, first = true;
    Clock::time_point wall_anchor;
    double replay_anchor_s = 0, stamp_offset_s = 0, loop_shift_s = 0;
    double first_s = 0, last_s = 0;
    std::size_t in_pass = 0;
    while (running_ && ros::ok()) {
      if (pub_.getNumSubscribers() == 0) {  // lazy: pause, and resume without a burst
        anchored = false;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        continue;
      }
      const core::PcapReader::Result result = pcap_->next(&packet);
      if (result == core::PcapReader::Result::kTruncated) {
        NODELET_ERROR("pcap '%s' is truncated after %lu packets; replay stops",
                      params_.pcap.c_str(), static_cast<unsigned long>(packets_));
        break;
      }
      if (result == core::PcapReader::Result::kEnd) {
        if (in_pass == 0) {
          NODELET_ERROR("pcap '%s' has no HDL-64E packet for UDP port %d", params_.pcap.c_str(),
                        params_.port);
          break;
        }
        if (!params_.loop) break;
        const double span_s = last_s - first_s;
        loop_shift_s += span_s + (in_pass > 1 ? span_s / static_cast<double>(in_pass - 1) : 0.1);
        pcap_->rewind();
        assembler_->reset();  // never splice the end of the file to its start in one scan
        in_pass = 0;
        continue;
      }
      if (in_pass++ == 0) first_s = packet.stamp_s;
      last_s = packet.stamp_s;
      const double replay_s = packet.stamp_s + loop_shift_s;
      if (first) {
        stamp_offset_s = params_.use_pcap_time ? 0.0 : ros::Time::now().toSec() - replay_s;
        first = false;
      }
      if (!anchored) {
        wall_anchor = Clock::now();
        replay_anchor_s = replay_s;
        anchored = true;
      }
      if (params_.rate > 0) {
        const auto due = wall_anchor + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(
                                               (replay_s - replay_anchor_s) / params_.rate));
        while (running_ && Clock::now() < due) {  // interruptible sleep
          std::this_thread::sleep_for(std::min<Clock::duration>(due - Clock::now(),
                                                                std::chrono::milliseconds(50)));
        }
      }
      addPacket(packet.data, ros::Time(std::max(0.0, replay_s + stamp_offset_s)));
    }
    assembler_->reset();  // the revolution open at the end of the file is partial
    partial_dropped_ = assembler_->partialDropped();
    if (pcap_->skipped() > 0) {
      NODELET_WARN("pcap '%s': skipped %lu records that are not HDL-64E data packets",
                   params_.pcap.c_str(), static_cast<unsigned long>(pcap_->skipped()));
    }
    NODELET_INFO("pcap replay finished: %lu packets, %lu revolutions",
                 static_cast<unsigned long>(packets_), static_cast<unsigned long>(scans_));
    running_ = false;
  }

  void addPacket(const core::RawPacket& packet, const ros::Time& stamp) {
    ++packets_;
    VelodyneScan::Ptr scan = assembler_->add(packet, stamp);
    partial_dropped_ = assembler_->partialDropped();
    if (assembler_->forcedCuts() != forced_cuts_) {
      forced_cuts_ = assembler_->forcedCuts();
      NODELET_WARN_THROTTLE(5, "no revolution boundary at cut_angle %.2f deg within %zu packets: "
                               "dropped them (is the sensor spinning?)",
                            params_.cut_angle_deg, ScanAssembler::kMaxPacketsPerScan);
    }
    if (!scan) return;
    ++scans_;
    pub_.publish(scan);  // a fresh message, never touched again: zero copy inside a manager
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    const std::uint64_t bad = bad_size_ + other_sender_;
    if (bad > reported_bad_) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "dropping bad or foreign packets");
    } else if (pcap_ && running_ && pub_.getNumSubscribers() == 0) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "replay paused: no subscriber");
    } else if (packets_ == reported_packets_ && running_) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no packets");
    } else {
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, running_ ? "receiving" : "stopped");
    }
    reported_bad_ = bad;
    reported_packets_ = packets_;
    stat.add("packets", packets_.load());
    stat.add("revolutions", scans_.load());
    stat.add("bad_size_packets", bad_size_.load());
    stat.add("other_sender_packets", other_sender_.load());
    stat.add("partial_revolutions_dropped", partial_dropped_.load());
    stat.add("forced_cuts", forced_cuts_.load());
  }

  PacketSourceParams params_;
  std::unique_ptr<core::UdpReceiver> receiver_;
  std::unique_ptr<core::PcapReader> pcap_;
  std::unique_ptr<ScanAssembler> assembler_;  // used by the reading thread only
  ros::Publisher pub_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer diag_timer_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> packets_{0}, scans_{0}, bad_size_{0}, other_sender_{0};
  std::atomic<std::uint64_t> partial_dropped_{0}, forced_cuts_{0};
  std::uint64_t reported_bad_ = 0, reported_packets_ = 0;  // diagnostics thread only
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::PacketSource, nodelet::Nodelet)
