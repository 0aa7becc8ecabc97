// The simulator's packets written with the core PcapWriter replay through PcapReader and the
// decoder into exactly the ground-truth length, revolution by revolution.
#include <gtest/gtest.h>

#include <cstdio>

#include "test_files.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/core/simulation/ground_truth.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace ud = urban_detection::core;

TEST(SimulationPcap, PcapReplaysThroughReaderCutterAndDecoder) {
  const ud::SimulationConfig c =
      ud::loadSimulationConfig(std::string(UD_SOURCE_DIR) + "/config/demo_drive.yaml");
  ud::LidarSimulator sim(ud::generateScene(c.scene, c.drive), c.scene, c.drive,
                         ud::Calibration::nominalHdl64eS2(), c.sensor);
  const std::string path = ud_test::tempPath("sim_test.pcap");
  std::vector<std::size_t> gt_sizes;
  std::vector<ud::RawPacket> written;
  std::vector<ud::GroundTruthFrame> frames;
  {
    ud::PcapWriter w(path);
    ud::SimRevolution rev;
    for (int r = 0; r < 3; ++r) {
      sim.simulateNext(&rev);
      gt_sizes.push_back(rev.instance_ids.size());
      frames.emplace_back();
      ud::makeGroundTruthFrame(sim, rev, &frames.back());
      for (std::size_t i = 0; i < rev.packets.size(); ++i) {
        w.write(rev.packets[i], rev.packet_stamps_s[i]);
        written.push_back(rev.packets[i]);
      }
    }
  }
  // Replay as PacketSource + PacketToCloud do: cut at the configured angle, decode.
  ud::PcapReader reader(path);
  ud::RevolutionCutter cutter(c.sensor.cut_angle_deg);
  ud::PacketDecoder decoder(sim.calibration(), ud::DecoderParams());
  std::vector<std::size_t> decoded;
  std::vector<double> rev_stamps;
  urban_detection::CloudXYZIRT cloud;
  ud::PcapPacket p;
  std::size_t n = 0;
  double rev_stamp = 0.0;
  while (reader.next(&p) == ud::PcapReader::Result::kPacket) {
    ASSERT_LT(n, written.size());
    EXPECT_EQ(p.data, written[n]) << "packet " << n;
    ++n;
    if (cutter.startsNewRevolution(ud::blockAzimuth(p.data.data(), 0)) && n > 1) {
      decoded.push_back(cloud.size());
      rev_stamps.push_back(rev_stamp);
      cloud.clear();
      rev_stamp = p.stamp_s;
    }
    if (n == 1) rev_stamp = p.stamp_s;
    ASSERT_EQ(decoder.decode(p.data.data(), p.data.size(), p.stamp_s - rev_stamp, &cloud, nullptr),
              ud::PacketStatus::kOk);
  }
  decoded.push_back(cloud.size());
  rev_stamps.push_back(rev_stamp);
  EXPECT_EQ(n, written.size());
  EXPECT_EQ(decoded, gt_sizes);
  // Stamps read back from the pcap (1 us resolution) find their ground-truth frame.
  ASSERT_EQ(rev_stamps.size(), frames.size());
  for (std::size_t r = 0; r < rev_stamps.size(); ++r) {
    EXPECT_EQ(ud::findGroundTruthFrame(frames, rev_stamps[r]), static_cast<std::ptrdiff_t>(r));
    EXPECT_EQ(frames[r].instance_ids.size(), decoded[r]);
  }
  EXPECT_EQ(ud::findGroundTruthFrame(frames, rev_stamps[1] + 0.01), -1);
  std::remove(path.c_str());
}
