// libFuzzer target: pcap reader (core::PcapReader over libpcap) with its hand-written
// Ethernet / VLAN / Linux-cooked / raw-IPv4 / UDP parsing.
//
// The input is the capture file. Checked: the constructor fails only with std::runtime_error;
// next() ends (kEnd or kTruncated) within as many calls as the file has bytes; every packet
// returned is a whole 1206-byte payload that the decoder then handles; after rewind() the
// same packets come back in the same order.
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "fuzz_common.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"

namespace core = urban_detection::core;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static urban_detection::fuzz::ScratchFile file(".pcap");
  static const core::PacketDecoder decoder(core::Calibration::nominalHdl64eS2(),
                                           core::DecoderParams());
  file.write(data, size);
  std::unique_ptr<core::PcapReader> reader;
  try {
    reader = std::make_unique<core::PcapReader>(file.path());
  } catch (const std::runtime_error&) {
    return 0;  // not a capture: a clear error naming the file is the contract
  }
  // Each record needs at least a 16-byte header, so a file of `size` bytes holds fewer
  // records than size / 16 + 1; more next() calls than that means the reader does not end.
  const std::size_t max_calls = size / 16 + 2;
  std::vector<double> stamps;
  std::vector<std::uint16_t> first_azimuths;
  core::PcapReader::Result last = core::PcapReader::Result::kPacket;
  for (std::size_t calls = 0;; ++calls) {
    UD_FUZZ_CHECK(calls < max_calls);
    core::PcapPacket packet;
    last = reader->next(&packet);
    if (last != core::PcapReader::Result::kPacket) break;
    stamps.push_back(packet.stamp_s);
    first_azimuths.push_back(core::blockAzimuth(packet.data.data(), 0));
    urban_detection::CloudXYZIRT cloud;
    core::DecodeStats stats;
    decoder.decode(packet.data.data(), packet.data.size(), 0.0, &cloud, &stats);
    UD_FUZZ_CHECK(stats.packets == 1);
  }
  const std::size_t skipped = reader->skipped();
  // After the end, next() keeps reporting the end without reading anything.
  core::PcapPacket extra;
  UD_FUZZ_CHECK(reader->next(&extra) != core::PcapReader::Result::kPacket);

  reader->rewind();
  std::size_t k = 0;
  for (;;) {
    core::PcapPacket packet;
    const core::PcapReader::Result r = reader->next(&packet);
    if (r != core::PcapReader::Result::kPacket) {
      UD_FUZZ_CHECK(r == last);
      break;
    }
    UD_FUZZ_CHECK(k < stamps.size());
    UD_FUZZ_CHECK(packet.stamp_s == stamps[k] ||
                  (packet.stamp_s != packet.stamp_s && stamps[k] != stamps[k]));
    UD_FUZZ_CHECK(core::blockAzimuth(packet.data.data(), 0) == first_azimuths[k]);
    ++k;
  }
  UD_FUZZ_CHECK(k == stamps.size());
  UD_FUZZ_CHECK(reader->skipped() == 2 * skipped);  // the counter is cumulative over rewinds
  return 0;
}
