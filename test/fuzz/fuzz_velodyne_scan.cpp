// libFuzzer target: an urban_detection/VelodyneScan message arriving as bytes (a bag, a remote
// publisher, a driver we do not control), deserialised by ros::serialization and decoded by
// decodeScan() (PacketToCloud's path), then re-assembled by ScanAssembler (PacketSource's path).
//
// Checked: deserialisation either succeeds or throws ros::serialization's own exception;
// a message that deserialises re-serialises to the same bytes; decodeScan() never throws and
// accounts for every packet (decoded, rejected or dropped for a missing transform); points are
// finite; ScanAssembler numbers revolutions 1, 2, ... and never exceeds its packet limit.
#include <ros/serialization.h>
#include <urban_detection/VelodyneScan.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_common.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace ud = urban_detection;
namespace rc = urban_detection::ros_conv;
namespace core = urban_detection::core;
namespace ser = ros::serialization;

namespace {

constexpr std::size_t kSerializedPacket = 8 + core::kPacketSize;  // time + uint8[1206]

// ros::serialization resizes the packet vector to the count read from the stream before it
// checks that the stream holds that many packets, so a 4-byte count of 0xFFFFFFFF asks for
// ~5 TB. roscpp's transport hands over one whole message, so a count larger than the bytes
// left can never be satisfied; reject it here as the message length would (see the report:
// this is ros::serialization behaviour, not ours).
bool countFits(const std::uint8_t* data, std::size_t size) {
  std::size_t off = 12;             // header.seq, header.stamp
  if (size < off + 4) return true;  // the deserialiser will throw on its own
  std::uint32_t len;
  std::memcpy(&len, data + off, 4);
  off += 4;
  if (len > size - off) return true;  // frame_id overruns: throws before the vector
  off += len;
  if (size < off + 4) return true;
  std::uint32_t count;
  std::memcpy(&count, data + off, 4);
  off += 4;
  return count <= (size - off) / kSerializedPacket;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const core::PacketDecoder decoder(core::Calibration::nominalHdl64eS2(),
                                           core::DecoderParams());
  if (!countFits(data, size)) return 0;

  // An exact-size heap copy (ASan catches overreads); never a null pointer, which roscpp
  // never passes either (ros::serialization does pointer arithmetic on it before checking).
  std::vector<std::uint8_t> buffer(size > 0 ? size : 1);
  if (size > 0) std::memcpy(buffer.data(), data, size);
  ud::VelodyneScan scan;
  try {
    ser::IStream stream(buffer.data(), static_cast<std::uint32_t>(size));
    ser::deserialize(stream, scan);
  } catch (const ser::StreamOverrunException&) {
    return 0;
  }
  // Round trip: the bytes consumed are exactly what serialising the message gives back.
  const std::uint32_t length = ser::serializationLength(scan);
  UD_FUZZ_CHECK(length <= size);
  std::vector<std::uint8_t> out(length);
  ser::OStream ostream(out.data(), length);
  ser::serialize(ostream, scan);
  UD_FUZZ_CHECK(std::memcmp(out.data(), data, length) == 0);

  // PacketToCloud without and with a per-packet transform (some stamps "unavailable").
  for (int with_tf = 0; with_tf < 2; ++with_tf) {
    rc::PacketTransformFn transform;
    if (with_tf) {
      transform = [](const ros::Time& stamp, Eigen::Affine3f* t) {
        if (stamp.nsec % 3 == 0) return false;
        *t = Eigen::AngleAxisf(static_cast<float>(stamp.nsec % 628) * 0.01f,
                               Eigen::Vector3f::UnitZ()) *
             Eigen::Translation3f(1.0f, -2.0f, 0.5f);
        return true;
      };
    }
    ud::CloudXYZIRT cloud;
    rc::ScanDecodeStats stats;
    rc::decodeScan(decoder, scan, transform, &cloud, &stats);
    UD_FUZZ_CHECK(stats.decode.packets + stats.tf_failures == scan.packets.size());
    UD_FUZZ_CHECK(stats.decode.points == cloud.size() && cloud.width == cloud.size());
    std::size_t valid_packets = 0;
    for (const ud::VelodynePacket& p : scan.packets) {
      if (core::PacketDecoder::validate(p.data.data(), p.data.size()) == core::PacketStatus::kOk &&
          !(with_tf && p.stamp.nsec % 3 == 0)) {
        ++valid_packets;
      }
    }
    UD_FUZZ_CHECK(stats.decode.packets - stats.decode.bad_packets == valid_packets);
    for (const ud::PointXYZIRT& p : cloud.points) {
      UD_FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      UD_FUZZ_CHECK(std::isfinite(p.time));
    }
  }

  // PacketSource: the same packets through the revolution assembler and, in step, through the
  // streaming decoder, which must cut the same revolutions with the same points.
  const rc::ScanStamp convention =
      scan.header.seq % 2 ? rc::ScanStamp::kFirstPacket : rc::ScanStamp::kLastPacket;
  rc::ScanAssembler assembler(scan.header.seq % 360, scan.header.frame_id, 700, convention);
  rc::StreamingScanDecoder streamer(&decoder, scan.header.seq % 360, scan.header.frame_id, 700,
                                    convention);
  std::uint32_t expected_seq = 1;
  for (const ud::VelodynePacket& p : scan.packets) {
    core::RawPacket raw;
    std::memcpy(raw.data(), p.data.data(), core::kPacketSize);
    const ud::VelodyneScan::Ptr rev = assembler.add(raw, p.stamp);
    const boost::shared_ptr<ud::CloudXYZIRT> streamed = streamer.add(raw, p.stamp);
    UD_FUZZ_CHECK(static_cast<bool>(rev) == static_cast<bool>(streamed));
    if (rev) {
      ud::CloudXYZIRT batch;
      rc::ScanDecodeStats batch_stats;
      rc::decodeScan(decoder, *rev, rc::PacketTransformFn(), &batch, &batch_stats);
      UD_FUZZ_CHECK(batch.size() == streamed->size());
      UD_FUZZ_CHECK(streamed->header.seq == rev->header.seq);
      UD_FUZZ_CHECK(rev->header.seq == expected_seq);
      ++expected_seq;
      UD_FUZZ_CHECK(!rev->packets.empty() &&
                    rev->packets.size() <= rc::ScanAssembler::kMaxPacketsPerScan);
      UD_FUZZ_CHECK(rev->header.stamp == (convention == rc::ScanStamp::kLastPacket
                                              ? rev->packets.back().stamp
                                              : rev->packets.front().stamp));
    }
  }
  return 0;
}
