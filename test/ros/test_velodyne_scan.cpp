// ScanAssembler (packets -> whole revolutions) and decodeScan (VelodyneScan -> cloud), no master.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <pcl_conversions/pcl_conversions.h>

#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/simulation_config.h"

#include "../core/spin_packets.h"
#include "urban_detection/ros/velodyne_scan.h"

namespace urban_detection {
namespace ros_conv {
namespace {

constexpr std::size_t kReturnsPerPacket = 384;

// Packets 6 deg apart (1 deg per firing), first block at `first_az_deg`, all returns at 10 m.
std::vector<core::RawPacket> makePackets(int count, double first_az_deg) {
  return test::spinPackets(count, first_az_deg, 1.0, 0);
}

TEST(ScanAssembler, PublishesOnlyWholeRevolutionsCutAtTheCutAngle) {
  // Cut at 90 deg: a partial revolution from 30.5 deg, two whole ones, one packet more.
  ScanAssembler assembler(90.0, "lidar");
  const auto packets = makePackets(10 + 2 * 60 + 1, 30.5);  // 30.5 + 6 * 10 = 90.5: first cut
  std::vector<VelodyneScan::Ptr> scans;
  std::vector<std::size_t> at_packet;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    auto scan = assembler.add(packets[i], ros::Time(10.0 + 0.001 * static_cast<double>(i)));
    if (scan) scans.push_back(scan), at_packet.push_back(i);
  }
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(at_packet[0], 70u);  // packet 70 (90.5 deg again) closes the first whole revolution
  EXPECT_EQ(at_packet[1], 130u);
  EXPECT_EQ(assembler.partialDropped(), 1u);
  for (std::size_t s = 0; s < 2; ++s) {
    ASSERT_EQ(scans[s]->packets.size(), 60u);
    EXPECT_EQ(scans[s]->header.frame_id, "lidar");
    EXPECT_EQ(scans[s]->header.stamp, scans[s]->packets.back().stamp);  // velodyne_driver's
    EXPECT_EQ(scans[s]->header.seq, s + 1);
    EXPECT_EQ(core::blockAzimuth(scans[s]->packets.front().data.data(), 0), 9050);
    const std::size_t first = 10 + 60 * s;
    EXPECT_NEAR(scans[s]->packets.front().stamp.toSec(), 10.0 + 0.001 * first, 1e-9);
    EXPECT_TRUE(std::equal(packets[first].begin(), packets[first].end(),
                           scans[s]->packets.front().data.begin()));
  }
  EXPECT_NE(scans[0], scans[1]);  // fresh messages
  assembler.reset();              // the open revolution (one packet) is dropped
  EXPECT_EQ(assembler.partialDropped(), 2u);
}

TEST(ScanAssembler, StuckAzimuthIsCutAtTheSafetyLimitAndDropped) {
  ScanAssembler assembler(0.0, "velodyne");
  const auto packet = makePackets(1, 45.5).front();
  std::size_t returned = 0;
  for (std::size_t i = 0; i < ScanAssembler::kMaxPacketsPerScan + 5; ++i) {
    if (assembler.add(packet, ros::Time(1.0))) ++returned;
  }
  EXPECT_EQ(returned, 0u);
  EXPECT_EQ(assembler.forcedCuts(), 1u);
}

TEST(DecodeScan, PointTimesFollowPacketStampsAndBadPacketsAreDroppedWhole) {
  const core::Calibration calibration = core::Calibration::nominalHdl64eS2();
  const core::PacketDecoder decoder(calibration, core::DecoderParams());
  auto packets = makePackets(3, 0.5);
  packets[1][0] = 0x00;  // block 0 id 0xEEFF -> 0xEE00: unknown block id
  VelodyneScan scan;
  scan.header.frame_id = "velodyne";
  const double stamps[3] = {5.0, 5.010, 5.020};
  for (int i = 0; i < 3; ++i) {
    scan.packets.emplace_back();
    toMessage(packets[i], ros::Time(stamps[i]), &scan.packets.back());
  }
  CloudXYZIRT cloud;
  ScanDecodeStats stats;
  decodeScan(decoder, scan, PacketTransformFn(), &cloud, &stats);
  EXPECT_EQ(cloud.size(), 2 * kReturnsPerPacket);
  EXPECT_EQ(cloud.width, cloud.size());
  EXPECT_EQ(cloud.height, 1u);
  EXPECT_EQ(stats.decode.bad_packets, 1u);
  EXPECT_EQ(stats.decode.points, 2 * kReturnsPerPacket);
  EXPECT_EQ(stats.last_bad_status, core::PacketStatus::kUnknownBlockId);

  // Reference: the decoder called directly with the times relative to the first packet.
  CloudXYZIRT reference;
  core::DecodeStats ref_stats;
  decoder.decode(packets[0].data(), packets[0].size(), 0.0, &reference, &ref_stats);
  decoder.decode(packets[2].data(), packets[2].size(), 0.020, &reference, &ref_stats);
  ASSERT_EQ(reference.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_FLOAT_EQ(cloud.points[i].x, reference.points[i].x);
    EXPECT_FLOAT_EQ(cloud.points[i].time, reference.points[i].time);
  }
  // Second packet's points start 20 ms after the first packet's, plus firing offsets < 0.3 ms.
  EXPECT_NEAR(cloud.points[kReturnsPerPacket].time, 0.020, 1e-6);
  EXPECT_LT(cloud.points[kReturnsPerPacket - 1].time, 0.0003);
}

TEST(DecodeScan, EachPacketGetsTheTransformAtItsOwnStamp) {
  const core::PacketDecoder decoder(core::Calibration::nominalHdl64eS2(), core::DecoderParams());
  const auto packets = makePackets(3, 0.5);
  VelodyneScan scan;
  for (int i = 0; i < 3; ++i) {
    scan.packets.emplace_back();
    toMessage(packets[i], ros::Time(7.0 + 0.1 * i), &scan.packets.back());
  }
  CloudXYZIRT plain;
  ScanDecodeStats plain_stats;
  decodeScan(decoder, scan, PacketTransformFn(), &plain, &plain_stats);

  // A platform moving at 10 m/s along x: the packet at 7.1 s is shifted by 1 m; no transform is
  // available for the packet at 7.2 s.
  std::vector<double> asked;
  const PacketTransformFn moving = [&](const ros::Time& t, Eigen::Affine3f* transform) {
    asked.push_back(t.toSec());
    if (t.toSec() > 7.15) return false;
    *transform = Eigen::Translation3f(10.0f * static_cast<float>(t.toSec() - 7.0), 0.f, 0.f);
    return true;
  };
  CloudXYZIRT moved;
  ScanDecodeStats stats;
  decodeScan(decoder, scan, moving, &moved, &stats);
  ASSERT_EQ(asked.size(), 3u);
  EXPECT_DOUBLE_EQ(asked[1], 7.1);
  EXPECT_EQ(stats.tf_failures, 1u);
  ASSERT_EQ(moved.size(), 2 * kReturnsPerPacket);
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const float shift = i < kReturnsPerPacket ? 0.0f : 1.0f;
    EXPECT_NEAR(moved.points[i].x, plain.points[i].x + shift, 1e-4);
    EXPECT_FLOAT_EQ(moved.points[i].y, plain.points[i].y);
    EXPECT_FLOAT_EQ(moved.points[i].z, plain.points[i].z);
  }
}

TEST(DecodeScan, EmptyScanGivesAnEmptyCloud) {
  const core::PacketDecoder decoder(core::Calibration::nominalHdl64eS2(), core::DecoderParams());
  CloudXYZIRT cloud;
  ScanDecodeStats stats;
  decodeScan(decoder, VelodyneScan(), PacketTransformFn(), &cloud, &stats);
  EXPECT_TRUE(cloud.empty());
  EXPECT_EQ(cloud.width, 0u);
  EXPECT_EQ(stats.decode.packets, 0u);
}

}  // namespace
}  // namespace ros_conv
}  // namespace urban_detection

// ------------------------------------------------------------------------------------------
// Streaming decoding (PacketSource ~decode) against the batch path (ScanAssembler +
// decodeScan, as PacketToCloud decodes a VelodyneScan): on the simulated drive's packet stream,
// starting mid-revolution, the same revolutions with the same points bit for bit, the same
// header stamps under both stamp conventions, and the same seq.
namespace urban_detection {
namespace ros_conv {
namespace stream_test {

bool samePointBits(const PointXYZIRT& a, const PointXYZIRT& b) {
  return std::memcmp(a.data, b.data, sizeof(a.data)) == 0 && a.intensity == b.intensity &&
         a.ring == b.ring && std::memcmp(&a.time, &b.time, sizeof(a.time)) == 0;
}

void compareOnSimulatedDrive(ScanStamp convention) {
  core::SimulationConfig c =
      core::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  const core::Calibration cal = core::loadCalibration(c.calibration_file);
  core::LidarSimulator sim(core::generateScene(c.scene, c.drive), c.scene, c.drive, cal, c.sensor);
  const core::PacketDecoder decoder(cal, core::DecoderParams());
  ScanAssembler assembler(0.0, "velodyne", 700, convention);
  StreamingScanDecoder streamer(&decoder, 0.0, "velodyne", 700, convention);
  core::SimRevolution rev;
  std::size_t compared = 0, packets_seen = 0;
  for (int r = 0; r < 5; ++r) {
    sim.simulateNext(&rev);
    // Start the stream a third into the first revolution: the partial one must be dropped.
    const std::size_t first = r == 0 ? rev.packets.size() / 3 : 0;
    for (std::size_t i = first; i < rev.packets.size(); ++i) {
      const ros::Time stamp(rev.packet_stamps_s[i]);
      ++packets_seen;
      const VelodyneScan::Ptr scan = assembler.add(rev.packets[i], stamp);
      const boost::shared_ptr<CloudXYZIRT> streamed = streamer.add(rev.packets[i], stamp);
      ASSERT_EQ(static_cast<bool>(scan), static_cast<bool>(streamed)) << "packet " << packets_seen;
      if (!scan) continue;
      CloudXYZIRT batch;
      ScanDecodeStats stats;
      decodeScan(decoder, *scan, PacketTransformFn(), &batch, &stats);
      ASSERT_EQ(streamed->size(), batch.size());
      ASSERT_GT(batch.size(), 100000u);
      for (std::size_t k = 0; k < batch.size(); ++k) {
        ASSERT_TRUE(samePointBits(streamed->points[k], batch.points[k])) << "point " << k;
      }
      EXPECT_EQ(streamed->width, batch.width);
      EXPECT_EQ(streamed->height, 1u);
      EXPECT_EQ(streamed->header.frame_id, "velodyne");
      EXPECT_EQ(streamed->header.seq, scan->header.seq);
      EXPECT_EQ(streamed->header.stamp, pcl_conversions::toPCL(scan->header.stamp));  // [us]
      const ros::Time expected = convention == ScanStamp::kLastPacket ? scan->packets.back().stamp
                                                                      : scan->packets.front().stamp;
      EXPECT_EQ(scan->header.stamp, expected);
      EXPECT_EQ(streamer.lastPackets(), scan->packets.size());
      ++compared;
    }
  }
  EXPECT_EQ(compared, 3u);  // the partial first revolution is dropped by both
  EXPECT_EQ(streamer.partialDropped(), assembler.partialDropped());
}

}  // namespace stream_test

}  // namespace ros_conv
}  // namespace urban_detection

namespace urban_detection {
namespace ros_conv {

TEST(StreamingScanDecoder, EqualsTheBatchDecodeBitForBitOnTheSimulatedDrive) {
  stream_test::compareOnSimulatedDrive(ScanStamp::kLastPacket);
}

TEST(StreamingScanDecoder, FirstPacketStampConvention) {
  stream_test::compareOnSimulatedDrive(ScanStamp::kFirstPacket);
}

// PacketSource's sectors: the open revolution's new points every 36 packets, numbered with the
// seq the revolution's cloud will carry (openSeq), restarted whenever a revolution opens
// (openedCount). Binned into a GridSegmenter as they come, they are the first points of the
// closed cloud (segment() uses them) and give the labels of the whole cloud.
TEST(StreamingScanDecoder, OpenRevolutionSectorsArePrefixesOfTheCloud) {
  core::SimulationConfig c =
      core::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  const core::Calibration cal = core::loadCalibration(c.calibration_file);
  core::LidarSimulator sim(core::generateScene(c.scene, c.drive), c.scene, c.drive, cal, c.sensor);
  const core::PacketDecoder decoder(cal, core::DecoderParams());
  StreamingScanDecoder streamer(&decoder, 0.0, "velodyne", 700, ScanStamp::kLastPacket);
  EXPECT_EQ(streamer.openCloud(), nullptr);
  core::GridSegmenter streamed, whole;
  std::vector<core::SegmentClass> ls, lw;
  std::uint64_t opened = 0;
  std::size_t begin = 0, packets = 0, closed = 0, sectors = 0;
  core::SimRevolution rev;
  for (int r = 0; r < 4; ++r) {
    sim.simulateNext(&rev);
    const std::size_t first = r == 0 ? rev.packets.size() / 2 : 0;  // a partial one first
    for (std::size_t i = first; i < rev.packets.size(); ++i) {
      const boost::shared_ptr<CloudXYZIRT> cloud =
          streamer.add(rev.packets[i], ros::Time(rev.packet_stamps_s[i]));
      if (cloud) {
        streamed.segment(*cloud, &ls);
        EXPECT_TRUE(streamed.lastUsedStream()) << "revolution " << cloud->header.seq;
        whole.segment(*cloud, &lw);
        ASSERT_EQ(ls, lw);
        ++closed;
      }
      const CloudXYZIRT* open = streamer.openCloud();
      ASSERT_NE(open, nullptr);
      if (streamer.openedCount() != opened) {
        opened = streamer.openedCount();
        begin = 0;
        packets = 0;
      }
      if (++packets < 36) continue;
      packets = 0;
      streamed.addPoints(streamer.openSeq(), open->points.data() + begin,
                         open->points.size() - begin);
      begin = open->points.size();
      ++sectors;
    }
  }
  EXPECT_EQ(closed, 2u);  // the partial first revolution is dropped
  EXPECT_GT(sectors, 25u);
}

}  // namespace ros_conv
}  // namespace urban_detection

namespace urban_detection {
namespace ros_conv {
namespace {

// A revolution whose returns all lie beyond the decoder's range (a blinded or covered sensor)
// gets a WARN naming that cause, as does one without any return; a normal one none.
TEST(EmptyRevolutionCause, NamesReturnsOutOfRangeAndMissingReturns) {
  const core::Calibration calibration = core::Calibration::nominalHdl64eS2();
  core::DecoderParams params;
  params.max_range_m = 20.0;
  const core::PacketDecoder decoder(calibration, params);
  const auto decodeAt = [&](std::uint16_t distance_raw) {
    VelodyneScan scan;
    for (const auto& raw : test::spinPackets(10, 0.5, 1.0, 1667, 40, 1, distance_raw)) {
      scan.packets.emplace_back();
      toMessage(raw, ros::Time(1.0), &scan.packets.back());
    }
    CloudXYZIRT cloud;
    ScanDecodeStats stats;
    decodeScan(decoder, scan, PacketTransformFn(), &cloud, &stats);
    return emptyRevolutionCause(stats.decode, params);
  };
  EXPECT_EQ(decodeAt(5000), "");            // 10 m
  const std::string far = decodeAt(60000);  // 120 m, beyond max_range 20 m
  EXPECT_NE(far.find("outside the range [0.9, 20.0] m"), std::string::npos) << far;
  EXPECT_NE(far.find("every return at maximum range"), std::string::npos) << far;
  const std::string none = decodeAt(0);
  EXPECT_NE(none.find("without a single return"), std::string::npos) << none;
}

}  // namespace
}  // namespace ros_conv
}  // namespace urban_detection
