// pcap reading and writing of HDL-64E data packets with libpcap.
//
// Frames are parsed by hand with a bounds check before every field read, so a capture with
// odd link layers, IP options, VLAN tags, fragments or short records is skipped packet by
// packet and never read out of bounds.
#include "urban_detection/core/sensor/pcap_io.h"

#include <pcap/pcap.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace urban_detection {
namespace core {
namespace {

constexpr int kDefaultPort = 2368;
constexpr std::uint16_t kEtherTypeIpv4 = 0x0800;
constexpr std::uint16_t kEtherTypeVlan = 0x8100;
constexpr std::uint16_t kEtherTypeQinQ = 0x88A8;
constexpr std::uint8_t kProtoUdp = 17;
constexpr std::size_t kEthernetHeader = 14, kSllHeader = 16, kIpv4MinHeader = 20, kUdpHeader = 8;

inline std::uint16_t be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
inline void putBe16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v & 0xFF);
}

// Finds the IPv4 header in a frame of the given link type; false if it carries no IPv4.
bool ipv4Offset(int linktype, const std::uint8_t* frame, std::size_t len, std::size_t* offset) {
  switch (linktype) {
    case DLT_EN10MB: {
      std::size_t off = 12;  // EtherType after the two MAC addresses
      if (len < off + 2) return false;
      std::uint16_t type = be16(frame + off);
      // Up to two VLAN tags.
      for (int tags = 0; tags < 2 && (type == kEtherTypeVlan || type == kEtherTypeQinQ); ++tags) {
        off += 4;
        if (len < off + 2) return false;
        type = be16(frame + off);
      }
      *offset = off + 2;
      return type == kEtherTypeIpv4;
    }
    case DLT_LINUX_SLL:
      // Linux cooked capture: 16-byte header, protocol type in the last two bytes.
      *offset = kSllHeader;
      return len >= kSllHeader && be16(frame + 14) == kEtherTypeIpv4;
    case DLT_RAW:
      *offset = 0;
      return true;
    default:
      return false;
  }
}

// UDP payload of an IPv4 frame to `port`, or nullptr.
const std::uint8_t* udpPayload(int linktype, const std::uint8_t* frame, std::size_t len, int port,
                               std::size_t* payload_len) {
  std::size_t ip = 0;
  if (!ipv4Offset(linktype, frame, len, &ip)) return nullptr;
  if (len < ip + kIpv4MinHeader) return nullptr;
  const std::uint8_t* h = frame + ip;
  if ((h[0] >> 4) != 4) return nullptr;
  const std::size_t ihl = static_cast<std::size_t>(h[0] & 0x0F) * 4;
  if (ihl < kIpv4MinHeader || len < ip + ihl + kUdpHeader) return nullptr;
  if (h[9] != kProtoUdp) return nullptr;
  const std::uint16_t frag = be16(h + 6);
  if ((frag & 0x3FFF) != 0) return nullptr;  // fragment (MF set or offset): not a whole datagram
  const std::size_t total = be16(h + 2);
  const std::uint8_t* udp = h + ihl;
  if (be16(udp + 2) != port) return nullptr;
  const std::size_t udp_len = be16(udp + 4);
  if (udp_len < kUdpHeader || total < ihl + udp_len) return nullptr;
  const std::size_t available = len - ip - ihl - kUdpHeader;
  const std::size_t payload = udp_len - kUdpHeader;
  if (payload > available) return nullptr;  // snapped or truncated record
  *payload_len = payload;
  return udp + kUdpHeader;
}

std::uint16_t ipChecksum(const std::uint8_t* h, std::size_t n) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < n; i += 2) sum += be16(h + i);
  while (sum >> 16) sum = (sum & 0xFFFF) + (sum >> 16);
  return static_cast<std::uint16_t>(~sum & 0xFFFF);
}

}  // namespace

// ------------------------------------------------------------------------------------------------
struct PcapReader::Impl {
  std::string path;
  int port = kDefaultPort;
  pcap_t* handle = nullptr;
  int linktype = DLT_EN10MB;
  // Once next() has reported kEnd or kTruncated it keeps reporting it until rewind(): after a
  // corrupt record header libpcap would otherwise go on parsing the record's payload as
  // headers and could hand out "packets" from the middle of a record.
  bool finished = false;
  Result final_result = Result::kEnd;

  void open() {
    char err[PCAP_ERRBUF_SIZE] = {0};
    handle = pcap_open_offline(path.c_str(), err);
    if (handle == nullptr) {
      throw std::runtime_error("pcap '" + path + "': cannot open capture: " + err);
    }
    linktype = pcap_datalink(handle);
  }
  void close() {
    if (handle != nullptr) pcap_close(handle);
    handle = nullptr;
  }
};

PcapReader::PcapReader(const std::string& path, int udp_port) : impl_(new Impl) {
  impl_->path = path;
  impl_->port = udp_port;
  impl_->open();
}

PcapReader::~PcapReader() {
  impl_->close();
}

PcapReader::Result PcapReader::next(PcapPacket* packet) {
  if (impl_->handle == nullptr) return Result::kEnd;
  if (impl_->finished) return impl_->final_result;
  for (;;) {
    pcap_pkthdr* header = nullptr;
    const u_char* frame = nullptr;
    const int rc = pcap_next_ex(impl_->handle, &header, &frame);
    if (rc == PCAP_ERROR_BREAK) {  // -2: end of file
      impl_->finished = true;
      impl_->final_result = Result::kEnd;
      return Result::kEnd;
    }
    if (rc != 1 || header == nullptr || frame == nullptr) {
      // -1: libpcap read error, which for an offline capture means a record cut short by
      // the end of the file ("truncated dump file") or a corrupt record header.
      impl_->finished = true;
      impl_->final_result = Result::kTruncated;
      return Result::kTruncated;
    }
    std::size_t payload_len = 0;
    const std::uint8_t* payload =
        udpPayload(impl_->linktype, frame, header->caplen, impl_->port, &payload_len);
    if (payload == nullptr || payload_len != kPacketSize) {
      ++skipped_;
      continue;
    }
    packet->stamp_s = static_cast<double>(header->ts.tv_sec) + header->ts.tv_usec * 1e-6;
    std::memcpy(packet->data.data(), payload, kPacketSize);
    return Result::kPacket;
  }
}

void PcapReader::rewind() {
  impl_->close();
  impl_->finished = false;
  impl_->open();
}

// ------------------------------------------------------------------------------------------------
struct PcapWriter::Impl {
  pcap_t* dead = nullptr;
  pcap_dumper_t* dumper = nullptr;
  std::string path;
};

PcapWriter::PcapWriter(const std::string& path) : impl_(new Impl) {
  impl_->path = path;
  impl_->dead = pcap_open_dead(DLT_EN10MB, 65535);
  if (impl_->dead == nullptr)
    throw std::runtime_error("pcap '" + path + "': pcap_open_dead failed");
  impl_->dumper = pcap_dump_open(impl_->dead, path.c_str());
  if (impl_->dumper == nullptr) {
    const std::string err = pcap_geterr(impl_->dead);
    pcap_close(impl_->dead);
    impl_->dead = nullptr;
    throw std::runtime_error("pcap '" + path + "': cannot create: " + err);
  }
}

PcapWriter::~PcapWriter() {
  if (impl_->dumper != nullptr) pcap_dump_close(impl_->dumper);
  if (impl_->dead != nullptr) pcap_close(impl_->dead);
}

void PcapWriter::write(const RawPacket& packet, double stamp_s) {
  constexpr std::size_t kIpLen = kIpv4MinHeader + kUdpHeader + kPacketSize;
  std::uint8_t frame[kEthernetHeader + kIpLen];
  std::memset(frame, 0, sizeof(frame));
  // Ethernet: broadcast from a Velodyne MAC (60:76:88 is Velodyne's OUI).
  std::memset(frame, 0xFF, 6);
  const std::uint8_t src_mac[6] = {0x60, 0x76, 0x88, 0x00, 0x00, 0x01};
  std::memcpy(frame + 6, src_mac, 6);
  putBe16(frame + 12, kEtherTypeIpv4);
  // IPv4 192.168.3.43 -> 255.255.255.255, UDP.
  std::uint8_t* ip = frame + kEthernetHeader;
  ip[0] = 0x45;
  putBe16(ip + 2, static_cast<std::uint16_t>(kIpLen));
  putBe16(ip + 6, 0x4000);  // don't fragment
  ip[8] = 255;              // TTL
  ip[9] = kProtoUdp;
  const std::uint8_t src_ip[4] = {192, 168, 3, 43};
  std::memcpy(ip + 12, src_ip, 4);
  std::memset(ip + 16, 0xFF, 4);
  putBe16(ip + 10, ipChecksum(ip, kIpv4MinHeader));
  std::uint8_t* udp = ip + kIpv4MinHeader;
  putBe16(udp, kDefaultPort);
  putBe16(udp + 2, kDefaultPort);
  putBe16(udp + 4, static_cast<std::uint16_t>(kUdpHeader + kPacketSize));
  // UDP checksum 0: not computed (allowed for IPv4).
  std::memcpy(udp + kUdpHeader, packet.data(), kPacketSize);

  pcap_pkthdr header{};
  const double whole = static_cast<double>(static_cast<long long>(stamp_s));
  header.ts.tv_sec = static_cast<time_t>(whole);
  header.ts.tv_usec = static_cast<suseconds_t>((stamp_s - whole) * 1e6 + 0.5);
  if (header.ts.tv_usec >= 1000000) {
    header.ts.tv_sec += 1;
    header.ts.tv_usec -= 1000000;
  }
  header.caplen = header.len = sizeof(frame);
  pcap_dump(reinterpret_cast<u_char*>(impl_->dumper), &header, frame);
}

ReplayTimeline::ReplayTimeline(double nominal_gap_s, double max_gap_s)
    : nominal_gap_s_(nominal_gap_s), max_gap_s_(max_gap_s) {}

double ReplayTimeline::next(double capture_s, Anomaly* anomaly) {
  Anomaly a = Anomaly::kNone;
  if (!started_) {
    started_ = true;
    now_s_ = std::isfinite(capture_s) ? capture_s : 0.0;
  } else {
    const double gap = capture_s - last_capture_s_;
    if (restarted_) {  // a loop, not an anomaly: the file's own mean packet gap
      now_s_ += sane_gaps_ > 0 ? sane_sum_s_ / static_cast<double>(sane_gaps_) : nominal_gap_s_;
    } else if (std::isnan(gap) || gap < 0.0) {
      a = Anomaly::kBackwards;
    } else if (gap == 0.0) {
      a = Anomaly::kStill;
    } else if (gap > max_gap_s_) {
      a = Anomaly::kJump;
    } else {
      now_s_ += gap;
      sane_sum_s_ += gap;
      ++sane_gaps_;
    }
    if (a != Anomaly::kNone) now_s_ += nominal_gap_s_;
  }
  restarted_ = false;
  last_capture_s_ = capture_s;
  if (anomaly) *anomaly = a;
  return now_s_;
}

const char* toString(ReplayTimeline::Anomaly anomaly) {
  switch (anomaly) {
    case ReplayTimeline::Anomaly::kNone:
      return "none";
    case ReplayTimeline::Anomaly::kBackwards:
      return "goes back";
    case ReplayTimeline::Anomaly::kStill:
      return "stands still";
    case ReplayTimeline::Anomaly::kJump:
      return "jumps forward";
  }
  return "?";
}

PcapRevolutionReader::PcapRevolutionReader(const std::string& path, double cut_angle_deg)
    : reader_(path), boundary_(cut_angle_deg) {}

void PcapRevolutionReader::rewind() {
  reader_.rewind();
  boundary_.reset();
  has_pending_ = false;
  first_ = true;
  first_whole_ = false;
  done_ = false;
  previous_packets_ = 0;
}

PcapRevolutionReader::Result PcapRevolutionReader::next(std::vector<PcapPacket>* packets) {
  packets->clear();
  if (done_) return end_ == PcapReader::Result::kTruncated ? Result::kTruncated : Result::kEnd;
  if (has_pending_) {
    packets->push_back(pending_);
    has_pending_ = false;
  }
  const auto emit = [&] {
    previous_packets_ = packets->size();
    ++revolutions_;
    first_whole_ = false;
    return Result::kRevolution;
  };
  PcapPacket p;
  for (;;) {
    const PcapReader::Result r = reader_.next(&p);
    if (r != PcapReader::Result::kPacket) {
      done_ = true;
      end_ = r;
      const std::size_t expected = previous_packets_ > 0 ? previous_packets_ : kNominalPackets;
      if ((boundary_.openWhole() || first_whole_) && !packets->empty() &&
          10 * packets->size() >= 9 * expected) {
        return emit();
      }
      packets->clear();
      return r == PcapReader::Result::kTruncated ? Result::kTruncated : Result::kEnd;
    }
    const RevolutionBoundary::Action action = boundary_.add(p.data.data(), p.data.size());
    switch (action) {
      case RevolutionBoundary::Action::kSkip:
        continue;
      case RevolutionBoundary::Action::kAppend:
        packets->push_back(p);
        continue;
      case RevolutionBoundary::Action::kClose:
        pending_ = p;
        has_pending_ = true;
        return emit();
      case RevolutionBoundary::Action::kDrop:
        // The file's first revolution, begun at the cut and closed by a cut (not a restart).
        if (first_whole_ && boundary_.openWhole()) {
          pending_ = p;
          has_pending_ = true;
          return emit();
        }
        break;
      case RevolutionBoundary::Action::kOpen:
        if (first_) {
          const double cut = boundary_.cutAngleDeg();
          const double past =
              std::fmod(blockAzimuth(p.data.data(), 0) / 100.0 - cut + 720.0, 360.0);
          first_whole_ = past < kStartToleranceDeg;
        }
        break;
      case RevolutionBoundary::Action::kForcedCut:
        first_whole_ = false;
        break;
    }
    first_ = false;
    packets->clear();
    packets->push_back(p);
  }
}

}  // namespace core
}  // namespace urban_detection
