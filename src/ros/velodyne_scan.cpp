#include "urban_detection/ros/velodyne_scan.h"

#include "urban_detection/core/sensor/pcap_io.h"

#include <pcl_conversions/pcl_conversions.h>
#include <boost/make_shared.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace urban_detection {
namespace ros_conv {

void toMessage(const core::RawPacket& packet, const ros::Time& stamp, VelodynePacket* msg) {
  static_assert(sizeof(msg->data) == core::kPacketSize, "VelodynePacket.data must be 1206 bytes");
  msg->stamp = stamp;
  std::memcpy(msg->data.data(), packet.data(), core::kPacketSize);
}

namespace {
// The revolution boundary's decision on one packet, shared by the assembler and the streaming
// decoder: false when the packet belongs to no revolution (invalid or stray); else the open
// revolution is closed into *finished (close()) or dropped (a drop, a forced cut, a new
// start), and the packet goes into the open revolution (or a new one when *current is null).
template <class Ptr, class Close>
bool atBoundary(core::RevolutionBoundary* boundary, const core::RawPacket& packet, Ptr* current,
                Ptr* finished, const Close& close) {
  switch (boundary->add(packet.data(), packet.size())) {
    case core::RevolutionBoundary::Action::kSkip:
      return false;
    case core::RevolutionBoundary::Action::kAppend:
      break;
    case core::RevolutionBoundary::Action::kClose:
      *finished = close();
      break;
    case core::RevolutionBoundary::Action::kDrop:
    case core::RevolutionBoundary::Action::kForcedCut:
    case core::RevolutionBoundary::Action::kOpen:
      current->reset();
      break;
  }
  return true;
}
}  // namespace

ScanAssembler::ScanAssembler(double cut_angle_deg, const std::string& frame_id,
                             std::size_t expected_packets, ScanStamp stamp)
    : boundary_(cut_angle_deg),
      frame_id_(frame_id),
      stamp_(stamp),
      expected_packets_(expected_packets > 0 ? expected_packets : 700),
      nominal_packets_(expected_packets) {}

VelodyneScan::Ptr ScanAssembler::add(const core::RawPacket& packet, const ros::Time& stamp) {
  VelodyneScan::Ptr finished;
  if (!atBoundary(&boundary_, packet, &current_, &finished, [this] { return close(); }))
    return finished;
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

VelodyneScan::Ptr ScanAssembler::close() {
  VelodyneScan::Ptr finished;
  expected_packets_ = last_packets_ = current_->packets.size();
  current_->header.seq = ++revolutions_;
  if (stamp_ == ScanStamp::kLastPacket) current_->header.stamp = current_->packets.back().stamp;
  finished.swap(current_);
  return finished;
}

void ScanAssembler::reset() {
  boundary_.reset();
  current_.reset();
}

namespace {
std::size_t endExpectation(std::size_t last, std::size_t nominal) {
  if (last > 0) return last;
  return nominal > 0 ? nominal : core::PcapRevolutionReader::kNominalPackets;
}
}  // namespace

void ScanAssembler::startFile(double tolerance_deg) {
  boundary_.startFile(tolerance_deg);
  current_.reset();
}

VelodyneScan::Ptr ScanAssembler::finishFile() {
  const bool whole = boundary_.finishFile(endExpectation(last_packets_, nominal_packets_));
  if (!whole || !current_ || current_->packets.empty()) {
    current_.reset();
    return VelodyneScan::Ptr();
  }
  return close();
}

void ScanAssembler::shiftOpen(double s) {
  if (!current_) return;
  const ros::Duration d(s);
  current_->header.stamp += d;
  for (VelodynePacket& p : current_->packets) p.stamp += d;
}

std::string emptyRevolutionCause(const core::DecodeStats& stats,
                                 const core::DecoderParams& params) {
  if (stats.packets <= stats.bad_packets) return "";  // nothing decodable: counted elsewhere
  char text[256];
  if (stats.out_of_range > 0 && 100 * stats.points < stats.out_of_range) {
    std::snprintf(text, sizeof(text),
                  "a revolution with %zu points: %zu returns outside the range [%.1f, %.1f] m "
                  "(every return at maximum range: sensor blinded or covered, or "
                  "min_range_m / max_range_m wrong?)",
                  stats.points, stats.out_of_range, params.min_range_m, params.max_range_m);
    return text;
  }
  if (stats.points == 0) {
    std::snprintf(text, sizeof(text),
                  "a revolution of %zu packets without a single return (lasers off or the "
                  "sensor covered?)",
                  stats.packets - stats.bad_packets);
    return text;
  }
  return "";
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

void decodePacket(const core::PacketDecoder& decoder, const std::uint8_t* data, std::size_t size,
                  const ros::Time& stamp, const ros::Time& start, const Eigen::Affine3f* transform,
                  CloudXYZIRT* cloud, ScanDecodeStats* stats) {
  const std::size_t begin = cloud->points.size();
  // In nanoseconds, not ros::Time - ros::Time: that Duration throws std::runtime_error when
  // two stamps of one scan are more than 68 years apart (a corrupt or hostile message), and
  // the exception would escape the subscriber callback and take the nodelet manager down.
  const std::uint64_t t = stamp.toNSec(), t0 = start.toNSec();
  const double packet_time_s =
      t >= t0 ? static_cast<double>(t - t0) * 1e-9 : -static_cast<double>(t0 - t) * 1e-9;
  // A fresh counter per packet: correct whether decode() adds to or overwrites its stats.
  core::DecodeStats packet_stats;
  const core::PacketStatus status = decoder.decode(data, size, packet_time_s, cloud, &packet_stats);
  accumulate(packet_stats, &stats->decode);
  if (status != core::PacketStatus::kOk) {
    stats->last_bad_status = status;
    return;
  }
  if (transform) {
    for (std::size_t i = begin; i < cloud->points.size(); ++i) {
      PointXYZIRT& p = cloud->points[i];
      p.getVector3fMap() = *transform * p.getVector3fMap();
    }
  }
}

namespace {
void finishCloud(CloudXYZIRT* cloud) {
  cloud->width = static_cast<std::uint32_t>(cloud->points.size());
  cloud->height = 1;
  cloud->is_dense = true;
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
    decodePacket(decoder, packet.data.data(), packet.data.size(), packet.stamp, start,
                 transform ? &packet_transform : nullptr, cloud, stats);
  }
  finishCloud(cloud);
}

StreamingScanDecoder::StreamingScanDecoder(const core::PacketDecoder* decoder, double cut_angle_deg,
                                           const std::string& frame_id,
                                           std::size_t expected_packets, ScanStamp stamp)
    : decoder_(decoder),
      boundary_(cut_angle_deg),
      frame_id_(frame_id),
      stamp_(stamp),
      expected_packets_(expected_packets > 0 ? expected_packets : 700),
      nominal_packets_(expected_packets) {}

void StreamingScanDecoder::open(const ros::Time& stamp) {
  constexpr std::size_t kReturnsPerPacket = core::kBlocksPerPacket * core::kLasersPerBlock;
  current_ = boost::make_shared<CloudXYZIRT>();
  current_->header.frame_id = frame_id_;
  current_->points.reserve((expected_packets_ + expected_packets_ / 8) * kReturnsPerPacket);
  first_stamp_ = stamp;
  stats_ = ScanDecodeStats();
  ++opened_;
}

boost::shared_ptr<CloudXYZIRT> StreamingScanDecoder::add(const core::RawPacket& packet,
                                                         const ros::Time& stamp) {
  boost::shared_ptr<CloudXYZIRT> finished;
  if (!atBoundary(&boundary_, packet, &current_, &finished, [this] { return close(); }))
    return finished;
  if (!current_) open(stamp);
  last_stamp_ = stamp;
  decodePacket(*decoder_, packet.data(), packet.size(), stamp, first_stamp_, nullptr,
               current_.get(), &stats_);
  return finished;
}

boost::shared_ptr<CloudXYZIRT> StreamingScanDecoder::close() {
  boost::shared_ptr<CloudXYZIRT> finished;
  last_packets_ = stats_.decode.packets;
  expected_packets_ = last_packets_;
  finishCloud(current_.get());
  const ros::Time& header_stamp = stamp_ == ScanStamp::kLastPacket ? last_stamp_ : first_stamp_;
  current_->header.stamp = pcl_conversions::toPCL(header_stamp);
  current_->header.seq = ++revolutions_;
  last_stats_ = stats_;
  finished.swap(current_);
  return finished;
}

void StreamingScanDecoder::reset() {
  boundary_.reset();
  current_.reset();
}

void StreamingScanDecoder::startFile(double tolerance_deg) {
  boundary_.startFile(tolerance_deg);
  current_.reset();
}

boost::shared_ptr<CloudXYZIRT> StreamingScanDecoder::finishFile() {
  const bool whole = boundary_.finishFile(endExpectation(last_packets_, nominal_packets_));
  if (!whole || !current_) {
    current_.reset();
    return boost::shared_ptr<CloudXYZIRT>();
  }
  return close();
}

void StreamingScanDecoder::shiftOpen(double s) {
  const ros::Duration d(s);
  first_stamp_ += d;
  last_stamp_ += d;
}

}  // namespace ros_conv
}  // namespace urban_detection
