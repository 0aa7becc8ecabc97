#include "urban_detection/ros/velodyne_scan.h"

#include <boost/make_shared.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace urban_detection {

void toMessage(const core::RawPacket& packet, const ros::Time& stamp, VelodynePacket* msg) {
  static_assert(sizeof(msg->data) == core::kPacketSize, "VelodynePacket.data must be 1206 bytes");
  msg->stamp = stamp;
  std::memcpy(msg->data.data(), packet.data(), core::kPacketSize);
}

ScanAssembler::ScanAssembler(double cut_angle_deg, const std::string& frame_id,
                             std::size_t expected_packets)
    : cutter_(cut_angle_deg), frame_id_(frame_id), expected_packets_(expected_packets) {}

VelodyneScan::Ptr ScanAssembler::add(const core::RawPacket& packet, const ros::Time& stamp) {
  VelodyneScan::Ptr finished;
  if (cutter_.startsNewRevolution(core::blockAzimuth(packet.data(), 0))) {
    if (current_ && current_is_whole_) {
      expected_packets_ = current_->packets.size();
      current_->header.seq = ++revolutions_;
      finished.swap(current_);
    } else if (current_) {
      ++partial_dropped_;
    }
    current_.reset();
    current_is_whole_ = true;
  } else if (current_ && current_->packets.size() >= kMaxPacketsPerScan) {
    ++forced_cuts_;
    current_.reset();
    current_is_whole_ = false;
  }
  if (!current_) {
    current_ = boost::make_shared<VelodyneScan>();
    current_->header.frame_id = frame_id_;
    current_->header.stamp = stamp;
    current_->packets.reserve(expected_packets_ + expected_packets_ / 8);
  }
  current_->packets.emplace_back();
  toMessage(packet, stamp, &current_->packets.back());
  return finished;
}

void ScanAssembler::reset() {
  if (current_) ++partial_dropped_;
  current_.reset();
  current_is_whole_ = false;
  cutter_.reset();
}

namespace {
void accumulate(const core::DecodeStats& in, core::DecodeStats* sum) {
  sum->packets += in.packets;
  sum->bad_packets += in.bad_packets;
  sum->points += in.points;
  sum->no_return += in.no_return;
  sum->out_of_range += in.out_of_range;
}
}  // namespace

void decodeScan(const core::PacketDecoder& decoder, const VelodyneScan& scan,
                const PacketTransformFn& transform, CloudXYZIRT* cloud, ScanDecodeStats* stats) {
  constexpr std::size_t kReturnsPerPacket = core::kBlocksPerPacket * core::kLasersPerBlock;
  cloud->points.reserve(cloud->points.size() + scan.packets.size() * kReturnsPerPacket);
  const ros::Time start = scan.packets.empty() ? ros::Time() : scan.packets.front().stamp;
  Eigen::Affine3f packet_transform = Eigen::Affine3f::Identity();
  for (const VelodynePacket& packet : scan.packets) {
    if (transform && !transform(packet.stamp, &packet_transform)) {
      ++stats->tf_failures;
      continue;
    }
    const std::size_t begin = cloud->points.size();
    // In nanoseconds, not ros::Time - ros::Time: that Duration throws std::runtime_error when
    // two stamps of one scan are more than 68 years apart (a corrupt or hostile message), and
    // the exception would escape the subscriber callback and take the nodelet manager down.
    const std::uint64_t t = packet.stamp.toNSec(), t0 = start.toNSec();
    const double packet_time_s = t >= t0 ? static_cast<double>(t - t0) * 1e-9
                                         : -static_cast<double>(t0 - t) * 1e-9;
    // A fresh counter per packet: correct whether decode() adds to or overwrites its stats.
    core::DecodeStats packet_stats;
    const core::PacketStatus status = decoder.decode(packet.data.data(), packet.data.size(),
                                                     packet_time_s, cloud, &packet_stats);
    accumulate(packet_stats, &stats->decode);
    if (status != core::PacketStatus::kOk) {
      stats->last_bad_status = status;
      continue;
    }
    if (transform) {
      for (std::size_t i = begin; i < cloud->points.size(); ++i) {
        PointXYZIRT& p = cloud->points[i];
        p.getVector3fMap() = packet_transform * p.getVector3fMap();
      }
    }
  }
  cloud->width = static_cast<std::uint32_t>(cloud->points.size());
  cloud->height = 1;
  cloud->is_dense = true;
}

}  // namespace urban_detection
