// libFuzzer target: HDL-64E packet decoding and revolution cutting (core/hdl64e_packet.h).
//
// The first input byte picks a mode:
//   0: the rest is one datagram of arbitrary length and content (what a UDP socket or a pcap
//      may hand over), decoded with the nominal and with an offset-laden calibration;
//   1: the rest is a stream of datagrams, each prefixed by a 16-bit length;
//   2: a stream of mostly well-formed packets built from a template (block ids right,
//      azimuths and distances from the input), so the correction model and the
//      RevolutionCutter see many valid packets, not only rejections.
// Invariants checked on every accepted packet (independently of the decoder's own code path):
// the status equals validate(); every return is counted exactly once as a point, a no-return
// or out of range; points are finite, on rings 0..63; with the nominal calibration (no offsets)
// a point's range lies within the decoder's range limits and its bearing is minus the raw
// azimuth. The cutter's cut count equals the number of times the unwrapped azimuth crosses
// the cut angle.
#include <cmath>
#include <cstdint>
#include <vector>

#include "fuzz_common.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace ud = urban_detection;
namespace core = urban_detection::core;
using urban_detection::fuzz::ByteReader;

namespace {

constexpr double kPi = 3.14159265358979323846;

core::Calibration offsetCalibration() {
  core::Calibration cal = core::Calibration::nominalHdl64eS2();
  cal.source = "fuzz offsets";
  for (int i = 0; i < core::kNumLasers; ++i) {
    core::LaserCorrection& c = cal.lasers[i];
    c.rot_correction_rad = -0.09 + 0.003 * i;
    c.dist_correction_m = 1.2 + 0.001 * i;
    c.dist_correction_x_m = 1.1;
    c.dist_correction_y_m = 1.15;
    c.two_pt_correction_available = true;
    c.vert_offset_correction_m = 0.2 + 0.001 * i;
    c.horiz_offset_correction_m = (i % 2 == 0) ? 0.026 : -0.026;
    c.focal_distance = 10.5;
    c.focal_slope = 1.3;
    c.min_intensity = 5;
    c.max_intensity = 250;
  }
  cal.finalize();
  return cal;
}

struct Decoders {
  core::DecoderParams params;
  core::PacketDecoder nominal{core::Calibration::nominalHdl64eS2(), params};
  core::PacketDecoder offsets{offsetCalibration(), params};
};

const Decoders& decoders() {
  static const Decoders d;
  return d;
}

void checkPacket(const std::uint8_t* data, std::size_t size, double time_s) {
  const Decoders& d = decoders();
  const core::PacketStatus expected = core::PacketDecoder::validate(data, size);

  ud::CloudXYZIRT cloud;
  core::DecodeStats stats;
  std::vector<std::uint8_t> laser;
  std::vector<std::uint16_t> azimuth;
  const core::PacketStatus status =
      d.nominal.decode(data, size, time_s, &cloud, &stats, &laser, &azimuth);
  UD_FUZZ_CHECK(status == expected);
  UD_FUZZ_CHECK(stats.packets == 1);
  if (status != core::PacketStatus::kOk) {
    UD_FUZZ_CHECK(stats.bad_packets == 1 && cloud.empty() && laser.empty());
  } else {
    UD_FUZZ_CHECK(stats.bad_packets == 0);
    UD_FUZZ_CHECK(stats.points + stats.no_return + stats.out_of_range ==
                  static_cast<std::size_t>(core::kBlocksPerPacket * core::kLasersPerBlock));
    UD_FUZZ_CHECK(cloud.size() == stats.points && laser.size() == cloud.size() &&
                  azimuth.size() == cloud.size());
    UD_FUZZ_CHECK(cloud.width == cloud.size() && cloud.height == 1);
    const core::Calibration& cal = d.nominal.calibration();
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const ud::PointXYZIRT& p = cloud[i];
      UD_FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
      UD_FUZZ_CHECK(laser[i] < core::kNumLasers);
      UD_FUZZ_CHECK(p.ring == cal.ring_of_laser[laser[i]]);
      UD_FUZZ_CHECK(azimuth[i] < 36000);
      const double range = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
      UD_FUZZ_CHECK(range >= d.params.min_range_m * (1 - 1e-5) - 1e-4);
      UD_FUZZ_CHECK(range <= d.params.max_range_m * (1 + 1e-5) + 1e-4);
      // Bearing: x forward, y left, the raw azimuth turns clockwise seen from above.
      const double bearing = std::atan2(p.y, p.x);
      double diff = std::remainder(bearing + azimuth[i] * kPi / 18000.0, 2 * kPi);
      UD_FUZZ_CHECK(std::fabs(diff) < 1e-3);
      UD_FUZZ_CHECK(p.intensity >= 0.0f && p.intensity <= 255.0f);
    }
  }

  // The same bytes through the fast path (no recording) and with the offset calibration.
  ud::CloudXYZIRT fast;
  core::DecodeStats fast_stats;
  UD_FUZZ_CHECK(d.nominal.decode(data, size, time_s, &fast, &fast_stats) == expected);
  UD_FUZZ_CHECK(fast.size() == cloud.size());
  for (std::size_t i = 0; i < fast.size(); ++i) {
    UD_FUZZ_CHECK(fast[i].x == cloud[i].x && fast[i].y == cloud[i].y && fast[i].z == cloud[i].z);
  }
  ud::CloudXYZIRT off;
  UD_FUZZ_CHECK(d.offsets.decode(data, size, time_s, &off, nullptr) == expected);
  for (const ud::PointXYZIRT& p : off.points) {
    UD_FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    UD_FUZZ_CHECK(p.intensity >= 5.0f && p.intensity <= 250.0f);
  }
  // A null cloud must only validate.
  UD_FUZZ_CHECK(d.nominal.decode(data, size, time_s, nullptr, nullptr) == expected);
}

// The cutter against a plain transcription of its documented rules (hdl64e_packet.h), packet by
// packet; and on a stream that only ever steps forward by at most kMaxStep, the cuts must equal
// the crossings of the unwrapped azimuth.
class CutterCheck {
 public:
  using Step = core::RevolutionCutter::Step;
  explicit CutterCheck(double cut_deg) : cutter_(cut_deg) {
    cut_ = static_cast<long>(std::lround(cutter_.cutAngleDeg() * 100.0));
    UD_FUZZ_CHECK(cut_ >= 0 && cut_ < 36000);
  }
  void feed(std::uint16_t first_azimuth) {
    const long az = first_azimuth % 36000;
    const Step got = cutter_.step(first_azimuth);
    UD_FUZZ_CHECK(got == reference(az));
    if (got == Step::kCut) ++cuts_;
    if (have_last_) {
      const long advance = (az - last_ + 36000) % 36000;
      monotone_ = monotone_ && advance <= core::RevolutionCutter::kMaxStep;
      unwrapped_ += advance;
    } else {
      start_ = unwrapped_ = az;
      have_last_ = true;
    }
    last_ = az;
  }
  void verify() const {
    if (!have_last_ || !monotone_) return;
    auto floorDiv = [](long a, long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
    const long crossings = floorDiv(unwrapped_ - cut_, 36000) - floorDiv(start_ - cut_, 36000);
    UD_FUZZ_CHECK(crossings == cuts_);
  }

 private:
  static long forward(long from, long to) { return ((to - from) % 36000 + 36000) % 36000; }
  bool crosses(long from, long to) const {
    const long d = forward(from, to), c = forward(from, cut_);
    return d > 0 && c > 0 && c <= d;
  }
  Step reference(long az) {
    const long max_step = core::RevolutionCutter::kMaxStep;
    if (head_ < 0) {
      head_ = az;
      return Step::kStep;
    }
    if (forward(head_, az) <= max_step) {
      candidate_ = -1;
      const bool cut = crosses(head_, az);
      head_ = az;
      return cut ? Step::kCut : Step::kStep;
    }
    if (forward(az, head_) <= max_step) {
      candidate_ = -1;
      return Step::kReordered;
    }
    if (candidate_ >= 0 && forward(candidate_, az) <= max_step) {
      const long from = head_, jumped_to = candidate_;
      candidate_ = -1;
      head_ = az;
      if (forward(from, jumped_to) < 18000) return crosses(from, az) ? Step::kCut : Step::kStep;
      return Step::kRestart;
    }
    candidate_ = az;
    return Step::kJump;
  }

  core::RevolutionCutter cutter_;
  long cut_ = 0, cuts_ = 0, start_ = 0, unwrapped_ = 0, last_ = 0;
  long head_ = -1, candidate_ = -1;
  bool have_last_ = false, monotone_ = true;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  const std::uint8_t mode = in.u8() % 3;
  if (mode == 0) {
    std::size_t n = 0;
    const std::uint8_t* p = in.rest(&n);
    std::vector<std::uint8_t> copy(p, p + n);  // exact-size heap buffer: ASan sees overreads
    checkPacket(copy.empty() ? nullptr : copy.data(), copy.size(), 0.0);
    return 0;
  }
  if (mode == 1) {
    CutterCheck cut(in.u16() / 100.0);
    for (int k = 0; k < 64 && !in.empty(); ++k) {
      std::size_t n = 0;
      const std::uint8_t* p = in.take(in.u16() % 1400, &n);
      std::vector<std::uint8_t> copy(p, p + n);
      checkPacket(copy.empty() ? nullptr : copy.data(), copy.size(), k * 288e-6);
      if (copy.size() == core::kPacketSize) cut.feed(core::blockAzimuth(copy.data(), 0));
    }
    cut.verify();
    return 0;
  }
  // Mode 2: template packets. Cut angle as raw float bits (NaN, inf, negative, huge).
  CutterCheck cut(static_cast<double>(in.rawFloat()));
  for (int k = 0; k < 48 && !in.empty(); ++k) {
    core::RawPacket packet{};
    const std::uint16_t base = in.u16();
    const std::uint8_t step = in.u8();
    const std::uint8_t flags = in.u8();
    for (int b = 0; b < core::kBlocksPerPacket; ++b) {
      std::uint8_t* block = packet.data() + 100 * b;
      const bool lower = (b % 2) == 1;
      const std::uint16_t id = (flags & 1) && b == 11 ? 0x1234 : lower ? 0xDDFF : 0xEEFF;
      std::uint16_t az = static_cast<std::uint16_t>(base + (b / 2) * step);
      if (!(flags & 2)) az %= 36000;  // bit 1 set: azimuths may be out of range
      block[0] = id & 0xFF;
      block[1] = id >> 8;
      block[2] = az & 0xFF;
      block[3] = az >> 8;
      for (int j = 0; j < core::kLasersPerBlock; ++j) {
        const std::uint16_t raw = (flags & 4) ? in.u16() : static_cast<std::uint16_t>(in.u8() * 97);
        block[4 + 3 * j] = raw & 0xFF;
        block[5 + 3 * j] = raw >> 8;
        block[6 + 3 * j] = static_cast<std::uint8_t>(j * 7 + k);
      }
    }
    checkPacket(packet.data(), packet.size(), k * 288e-6);
    cut.feed(core::blockAzimuth(packet.data(), 0));
  }
  cut.verify();
  return 0;
}
