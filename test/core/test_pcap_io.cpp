// pcap I/O: write -> read -> decode, foreign and malformed frames, truncated captures.
#include <gtest/gtest.h>
#include <pcap/pcap.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "spin_packets.h"
#include "test_files.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"

namespace uc = urban_detection::core;

namespace {

std::string tempPath(const std::string& name) {
  return ud_test::tempPath("pcap_" + name);
}

// Packets of a sensor looking at a 10 m cylinder, azimuth advancing 0.2 deg per firing.
std::vector<uc::RawPacket> makePackets(int count) {
  const uc::PacketEncoder encoder(uc::Calibration::nominalHdl64eS2());
  std::vector<uc::RawPacket> out;
  for (int p = 0; p < count; ++p) {
    uc::Firing f[6];
    for (int i = 0; i < 6; ++i) {
      f[i].azimuth = static_cast<std::uint16_t>(((p * 6 + i) * 20) % 36000);
      for (int l = 0; l < 64; ++l) {
        f[i].distance[l] = static_cast<std::uint16_t>(5000 + l);
        f[i].intensity[l] = static_cast<std::uint8_t>(l);
      }
    }
    out.push_back(encoder.encode(f, static_cast<std::uint32_t>(p * 288)));
  }
  return out;
}

// An IPv4/UDP datagram (without link header).
std::vector<std::uint8_t> ipUdp(const std::vector<std::uint8_t>& payload, int dport,
                                int ihl_words = 5, std::uint16_t frag = 0x4000) {
  std::vector<std::uint8_t> ip(ihl_words * 4 + 8 + payload.size(), 0);
  const std::size_t total = ip.size();
  ip[0] = static_cast<std::uint8_t>(0x40 | ihl_words);
  ip[2] = total >> 8;
  ip[3] = total & 0xFF;
  ip[6] = frag >> 8;
  ip[7] = frag & 0xFF;
  ip[8] = 64;
  ip[9] = 17;
  std::uint8_t* udp = ip.data() + ihl_words * 4;
  udp[0] = 2368 >> 8;
  udp[1] = 2368 & 0xFF;
  udp[2] = static_cast<std::uint8_t>(dport >> 8);
  udp[3] = dport & 0xFF;
  udp[4] = (8 + payload.size()) >> 8;
  udp[5] = (8 + payload.size()) & 0xFF;
  std::copy(payload.begin(), payload.end(), udp + 8);
  return ip;
}

std::vector<std::uint8_t> ethernet(const std::vector<std::uint8_t>& ip, std::uint16_t type = 0x0800,
                                   bool vlan = false) {
  std::vector<std::uint8_t> f(12, 0xAA);
  if (vlan) {
    f.push_back(0x81);
    f.push_back(0x00);
    f.push_back(0x00);
    f.push_back(0x05);
  }
  f.push_back(type >> 8);
  f.push_back(type & 0xFF);
  f.insert(f.end(), ip.begin(), ip.end());
  return f;
}

void dumpFrames(const std::string& path, int linktype,
                const std::vector<std::vector<std::uint8_t>>& frames) {
  pcap_t* dead = pcap_open_dead(linktype, 65535);
  pcap_dumper_t* d = pcap_dump_open(dead, path.c_str());
  ASSERT_NE(d, nullptr);
  int i = 0;
  for (const auto& f : frames) {
    pcap_pkthdr h{};
    h.ts.tv_sec = 1000 + i++;
    h.caplen = h.len = static_cast<bpf_u_int32>(f.size());
    pcap_dump(reinterpret_cast<u_char*>(d), &h, f.data());
  }
  pcap_dump_close(d);
  pcap_close(dead);
}

}  // namespace

TEST(PcapIo, WriteReadDecodeRoundTrip) {
  const std::string path = tempPath("roundtrip.pcap");
  const auto packets = makePackets(50);
  {
    uc::PcapWriter writer(path);
    for (std::size_t i = 0; i < packets.size(); ++i) writer.write(packets[i], 1.7e9 + i * 288e-6);
  }
  uc::PcapReader reader(path);
  const uc::Calibration cal = uc::Calibration::nominalHdl64eS2();
  uc::PacketDecoder decoder(cal, uc::DecoderParams{});
  urban_detection::CloudXYZIRT from_file, direct;
  uc::PcapPacket pkt;
  std::size_t n = 0;
  while (reader.next(&pkt) == uc::PcapReader::Result::kPacket) {
    ASSERT_LT(n, packets.size());
    EXPECT_EQ(pkt.data, packets[n]);
    EXPECT_NEAR(pkt.stamp_s, 1.7e9 + n * 288e-6, 2e-6);
    EXPECT_EQ(decoder.decode(pkt.data.data(), pkt.data.size(), 0.0, &from_file, nullptr),
              uc::PacketStatus::kOk);
    decoder.decode(packets[n].data(), packets[n].size(), 0.0, &direct, nullptr);
    ++n;
  }
  EXPECT_EQ(n, packets.size());
  EXPECT_EQ(reader.next(&pkt), uc::PcapReader::Result::kEnd);
  EXPECT_EQ(reader.skipped(), 0u);
  ASSERT_EQ(from_file.size(), 50u * 384u);
  ASSERT_EQ(from_file.size(), direct.size());
  for (std::size_t i = 0; i < direct.size(); i += 97) {
    EXPECT_EQ(from_file[i].x, direct[i].x);
    EXPECT_EQ(from_file[i].ring, direct[i].ring);
  }
  // rewind starts over.
  reader.rewind();
  ASSERT_EQ(reader.next(&pkt), uc::PcapReader::Result::kPacket);
  EXPECT_EQ(pkt.data, packets[0]);
  std::remove(path.c_str());
}

TEST(PcapIo, TruncatedCaptureReportsTruncatedNotCrash) {
  const std::string path = tempPath("truncated.pcap");
  const auto packets = makePackets(10);
  {
    uc::PcapWriter writer(path);
    for (const auto& p : packets) writer.write(p, 100.0);
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  ASSERT_EQ(bytes.size(), 24u + 10u * (16u + 14u + 20u + 8u + 1206u));
  bytes.resize(bytes.size() - 500);  // cut into the last record
  std::ofstream(path, std::ios::binary).write(bytes.data(), bytes.size());

  uc::PcapReader reader(path);
  uc::PcapPacket pkt;
  int read = 0;
  uc::PcapReader::Result r;
  while ((r = reader.next(&pkt)) == uc::PcapReader::Result::kPacket) ++read;
  EXPECT_EQ(read, 9);
  EXPECT_EQ(r, uc::PcapReader::Result::kTruncated);

  // A file cut inside its global header is not a capture: the constructor names the file.
  bytes.resize(10);
  std::ofstream(path, std::ios::binary).write(bytes.data(), bytes.size());
  try {
    uc::PcapReader bad(path);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
  EXPECT_THROW(uc::PcapReader("/nonexistent/x.pcap"), std::runtime_error);
}

TEST(PcapIo, ForeignAndMalformedFramesAreSkipped) {
  const std::string path = tempPath("mixed.pcap");
  const auto packets = makePackets(3);
  const std::vector<std::uint8_t> payload(packets[0].begin(), packets[0].end());
  const std::vector<std::uint8_t> payload2(packets[1].begin(), packets[1].end());
  const std::vector<std::uint8_t> payload3(packets[2].begin(), packets[2].end());
  std::vector<std::vector<std::uint8_t>> frames = {
      ethernet(std::vector<std::uint8_t>(28, 1), 0x0806),        // ARP
      ethernet(ipUdp(payload, 2369)),                            // other port
      ethernet(ipUdp(std::vector<std::uint8_t>(512, 7), 2368)),  // position packet size
      ethernet(ipUdp(payload, 2368, 5, 0x2000)),                 // first fragment
      std::vector<std::uint8_t>(9, 0xAA),                        // runt frame
      ethernet(ipUdp(payload, 2368)),                            // good
      ethernet(ipUdp(payload2, 2368), 0x0800, true),             // good, VLAN tagged
      ethernet(ipUdp(payload3, 2368, 6)),                        // good, IP options
  };
  // A frame whose UDP length claims more than the record holds.
  auto lying = ethernet(ipUdp(payload, 2368));
  lying.resize(lying.size() - 100);
  frames.push_back(lying);
  dumpFrames(path, DLT_EN10MB, frames);

  uc::PcapReader reader(path);
  uc::PcapPacket pkt;
  ASSERT_EQ(reader.next(&pkt), uc::PcapReader::Result::kPacket);
  EXPECT_EQ(pkt.data, packets[0]);
  ASSERT_EQ(reader.next(&pkt), uc::PcapReader::Result::kPacket);
  EXPECT_EQ(pkt.data, packets[1]);
  ASSERT_EQ(reader.next(&pkt), uc::PcapReader::Result::kPacket);
  EXPECT_EQ(pkt.data, packets[2]);
  EXPECT_EQ(reader.next(&pkt), uc::PcapReader::Result::kEnd);
  EXPECT_EQ(reader.skipped(), 6u);
  std::remove(path.c_str());
}

TEST(PcapIo, LinuxCookedCapture) {
  const std::string path = tempPath("sll.pcap");
  const auto packets = makePackets(1);
  std::vector<std::uint8_t> frame(16, 0);
  frame[14] = 0x08;  // protocol IPv4
  frame[15] = 0x00;
  const auto ip = ipUdp(std::vector<std::uint8_t>(packets[0].begin(), packets[0].end()), 2368);
  frame.insert(frame.end(), ip.begin(), ip.end());
  dumpFrames(path, DLT_LINUX_SLL, {frame});
  uc::PcapReader reader(path);
  uc::PcapPacket pkt;
  ASSERT_EQ(reader.next(&pkt), uc::PcapReader::Result::kPacket);
  EXPECT_EQ(pkt.data, packets[0]);
  EXPECT_DOUBLE_EQ(pkt.stamp_s, 1000.0);
  EXPECT_EQ(reader.next(&pkt), uc::PcapReader::Result::kEnd);
  std::remove(path.c_str());
}

TEST(PcapIo, OtherPortOption) {
  const std::string path = tempPath("port.pcap");
  const auto packets = makePackets(1);
  dumpFrames(
      path, DLT_EN10MB,
      {ethernet(ipUdp(std::vector<std::uint8_t>(packets[0].begin(), packets[0].end()), 2370))});
  uc::PcapPacket pkt;
  uc::PcapReader default_port(path);
  EXPECT_EQ(default_port.next(&pkt), uc::PcapReader::Result::kEnd);
  EXPECT_EQ(default_port.skipped(), 1u);
  uc::PcapReader port_2370(path, 2370);
  EXPECT_EQ(port_2370.next(&pkt), uc::PcapReader::Result::kPacket);
  std::remove(path.c_str());
}

TEST(PcapIo, CorruptedCapturesNeverCrash) {
  const std::string path = tempPath("corrupt.pcap");
  {
    uc::PcapWriter writer(path);
    for (const auto& p : makePackets(8)) writer.write(p, 5.0);
  }
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> original((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  in.close();
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::size_t> pos(24, original.size() - 1);  // after the header
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> cut(24, original.size());
  int truncated = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<char> bytes = original;
    for (int k = 0; k < 8; ++k) bytes[pos(rng)] = static_cast<char>(byte(rng));
    if (trial % 3 == 0) bytes.resize(cut(rng));
    std::ofstream(path, std::ios::binary).write(bytes.data(), bytes.size());
    uc::PcapReader reader(path);
    uc::PcapPacket pkt;
    uc::PcapReader::Result r;
    int packets = 0;
    while ((r = reader.next(&pkt)) == uc::PcapReader::Result::kPacket) {
      ASSERT_LE(++packets, 8);
    }
    truncated += r == uc::PcapReader::Result::kTruncated;
    EXPECT_LE(static_cast<std::size_t>(packets) + reader.skipped(), 8u);
  }
  EXPECT_GT(truncated, 50);  // every third file is cut at a random place
  std::remove(path.c_str());
}

// The replay timeline: capture times that go back, stand still or jump are
// replaced by the nominal packet period; sane stretches keep their recorded gaps.
TEST(ReplayTimeline, AnomaliesAdvanceByTheNominalPeriod) {
  using A = uc::ReplayTimeline::Anomaly;
  const double gap = 1.0 / 3472.0;
  uc::ReplayTimeline t(gap, 1.0);
  A a;
  EXPECT_DOUBLE_EQ(t.next(100.0, &a), 100.0);
  EXPECT_EQ(a, A::kNone);
  EXPECT_DOUBLE_EQ(t.next(100.0005, &a), 100.0005);
  EXPECT_DOUBLE_EQ(t.next(99.0, &a), 100.0005 + gap);  // back by 1 s
  EXPECT_EQ(a, A::kBackwards);
  EXPECT_DOUBLE_EQ(t.next(99.0003, &a), 100.0005 + gap + 0.0003);  // sane again from there
  EXPECT_EQ(a, A::kNone);
  EXPECT_DOUBLE_EQ(t.next(99.0003, &a), 100.0005 + 2 * gap + 0.0003);
  EXPECT_EQ(a, A::kStill);
  const double before = t.next(99.0006, &a);
  EXPECT_DOUBLE_EQ(t.next(99.0006 + 365 * 86400.0, &a), before + gap);  // a year ahead
  EXPECT_EQ(a, A::kJump);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_DOUBLE_EQ(t.next(nan, &a), before + 2 * gap);
  EXPECT_EQ(a, A::kBackwards);
  // All-zero capture times: paced at the nominal rate.
  uc::ReplayTimeline zeros(gap, 1.0);
  for (int i = 0; i < 3472; ++i) zeros.next(0.0);
  EXPECT_NEAR(zeros.next(0.0), 1.0, 1e-9);
  // A loop restarts one mean packet gap of the file later, without an anomaly.
  uc::ReplayTimeline loop(gap, 1.0);
  loop.next(5.0);
  loop.next(5.2);
  const double end = loop.next(5.6);
  loop.restart();
  EXPECT_NEAR(loop.next(5.0, &a), end + 0.3, 1e-12);
  EXPECT_EQ(a, A::kNone);
}

// One way to cut a capture into revolutions (bench, evaluation, tools): PcapRevolutionReader.
namespace {
constexpr int kPacketsPerRev = 348;
constexpr double kDegPerFiring = 360.0 / (6 * kPacketsPerRev);

std::string writeSpin(const std::string& name, double first_az_deg, int packets,
                      bool garbage_and_stray = false) {
  const std::string path = tempPath(name);
  const auto spin = urban_detection::test::spinPackets(packets, first_az_deg, kDegPerFiring, 288);
  uc::PcapWriter writer(path);
  for (int i = 0; i < packets; ++i) {
    const double t = 1.7e9 + i * 288e-6;
    writer.write(spin[static_cast<std::size_t>(i)], t);
    if (garbage_and_stray && i == kPacketsPerRev + 100) {
      uc::RawPacket garbage;
      garbage.fill(0x5A);
      writer.write(garbage, t);                                  // invalid
      writer.write(spin[static_cast<std::size_t>(i + 170)], t);  // 180 deg ahead: a stray
    }
  }
  return path;
}

std::vector<std::size_t> revolutionSizes(uc::PcapRevolutionReader* reader) {
  std::vector<std::size_t> sizes;
  std::vector<uc::PcapPacket> packets;
  while (reader->next(&packets) == uc::PcapRevolutionReader::Result::kRevolution) {
    sizes.push_back(packets.size());
  }
  EXPECT_TRUE(packets.empty());
  return sizes;
}
}  // namespace

TEST(PcapRevolutionReader, ACaptureFromTheCutGivesEveryRevolutionWholeIncludingFirstAndLast) {
  const std::string path = writeSpin("rev_whole.pcap", 0.0, 3 * kPacketsPerRev);
  uc::PcapRevolutionReader reader(path);
  const std::vector<std::size_t> expected(3, kPacketsPerRev);
  EXPECT_EQ(revolutionSizes(&reader), expected);
  EXPECT_EQ(reader.revolutions(), 3u);
  reader.rewind();  // the same again, the first-revolution rule included
  EXPECT_EQ(revolutionSizes(&reader), expected);
  std::remove(path.c_str());
}

TEST(PcapRevolutionReader, PartialRevolutionsAtBothEndsAreDropped) {
  // From 180 deg for 3.5 turns: 180..360 (partial), two whole ones, 0..180 (half: dropped).
  const std::string path = writeSpin("rev_partial.pcap", 180.0, 3 * kPacketsPerRev + 1);
  uc::PcapRevolutionReader reader(path);
  EXPECT_EQ(revolutionSizes(&reader), std::vector<std::size_t>(2, kPacketsPerRev));
  EXPECT_EQ(reader.boundary().partialDropped(), 1u);
  std::remove(path.c_str());
}

TEST(PcapRevolutionReader, InvalidAndStrayPacketsAreSkippedWithoutCutting) {
  const std::string path = writeSpin("rev_hostile.pcap", 0.0, 3 * kPacketsPerRev, true);
  uc::PcapRevolutionReader reader(path);
  std::vector<uc::PcapPacket> packets;
  std::vector<std::size_t> sizes;
  while (reader.next(&packets) == uc::PcapRevolutionReader::Result::kRevolution) {
    sizes.push_back(packets.size());
    for (const uc::PcapPacket& p : packets) {
      EXPECT_EQ(uc::PacketDecoder::validate(p.data.data(), p.data.size()), uc::PacketStatus::kOk);
    }
  }
  EXPECT_EQ(sizes, std::vector<std::size_t>(3, kPacketsPerRev));
  EXPECT_EQ(reader.boundary().invalidPackets(), 1u);
  EXPECT_EQ(reader.boundary().strayPackets(), 1u);
  std::remove(path.c_str());
}
