/// \file hdl64e_packet.h
/// HDL-64E data packet layout, decoding (packets -> calibrated points) and encoding
/// (returns -> packets), ROS-free.
///
/// Packet: 12 blocks of 100 bytes (block id 0xEEFF = upper lasers 0-31, 0xDDFF = lower lasers
/// 32-63; azimuth in 1/100 degree; 32 returns of distance in distance_resolution units and an
/// intensity byte), then a 4-byte timestamp [us past the hour] and 2 status bytes: 1206 bytes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/sensor/calibration.h"

namespace urban_detection {
namespace core {

constexpr std::size_t kPacketSize = 1206;
constexpr int kBlocksPerPacket = 12;
constexpr int kLasersPerBlock = 32;
constexpr std::uint16_t kUpperBlockId = 0xEEFF;
constexpr std::uint16_t kLowerBlockId = 0xDDFF;

using RawPacket = std::array<std::uint8_t, kPacketSize>;

/// Time between two consecutive firings (one upper + one lower block) [s]. The HDL-64E S2
/// datasheet gives > 1.33 M points/s, i.e. 20.8 k firings of 64 lasers per second: 48 us per
/// firing, 288 us per packet (~3472 packets/s whatever the spin rate). The 32 pulses of a block
/// are emitted within that period; every point of a firing gets the firing's start time.
constexpr double kFiringPeriodS = 48.0e-6;

/// Why a packet was rejected (nothing of a rejected packet is emitted).
enum class PacketStatus {
  kOk,
  kWrongSize,       // not 1206 bytes
  kUnknownBlockId,  // a block id other than 0xEEFF / 0xDDFF
  kBadAzimuth,      // azimuth >= 36000
  kOtherModel,      // no block carries the lower-bank id 0xDDFF: the single-bank layout of
                    // other Velodyne models (VLP-16, VLP-32C, HDL-32E, ...), whose blocks all
                    // read as upper blocks; velodyneModelName() names the model
  kDualReturn,      // S3 dual-return packet: rejected with a clear status, never misread.
                    // Rule: two blocks of one packet with the same block id and the same
                    // azimuth (a single-return packet never fires one bank twice at one angle;
                    // a dual-return packet carries the strongest and last echo of a firing in
                    // two blocks at the same angle). Status bytes are not used for this.
  kStoppedMotor,    // every block of the packet at one azimuth: the motor stands still (or
                    // its encoder is broken); checked before kDualReturn, whose firings move
};
const char* toString(PacketStatus status);

/// The Velodyne model and return mode a 1206-byte packet's factory bytes (offsets 1204: return
/// mode, 1205: product id) name, e.g. "VLP-16 (strongest return)", or "an unknown model
/// (factory bytes 0x37 0x99)". For the message of a refused kOtherModel packet; HDL-64E
/// packets carry status bytes there instead, so this is not a test for an HDL-64E.
std::string velodyneModelName(const std::uint8_t* data, std::size_t size);

/// Parameters of the decoder.
struct DecoderParams {
  double min_range_m = 0.9;    // [m] returns closer than this are dropped
  double max_range_m = 130.0;  // [m] returns farther than this are dropped
};

/// "" when valid: the table's ranges, then min_range < max_range.
std::string validate(const DecoderParams& params);

/// DecoderParams' field table (core/common/param_fields.h); the parameter names are
/// velodyne_pointcloud's (`min_range`, `max_range`).
template <>
struct ParamFields<DecoderParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"min_range", "m", 0.0, 250.0, "returns closer than this are dropped"}, p.min_range_m);
    f({"max_range", "m", 0.1, 250.0, "returns farther than this are dropped"}, p.max_range_m);
  }
};

/// Counters of one decode call (accumulate them across calls for diagnostics).
struct DecodeStats {
  std::size_t packets = 0;       // packets seen
  std::size_t bad_packets = 0;   // packets rejected (any non-kOk status)
  std::size_t points = 0;        // points emitted
  std::size_t no_return = 0;     // raw distance 0 (no echo)
  std::size_t out_of_range = 0;  // dropped by min/max range
};

/// Decodes packets with the full per-laser correction model (rotational and vertical
/// correction, distance correction with the two-point near-range correction, vertical and
/// horizontal offsets, intensity focal correction) using tables precomputed at construction.
class PacketDecoder {
 public:
  PacketDecoder(const Calibration& calibration, const DecoderParams& params);

  /// Decodes one packet and appends its points to `cloud`. `packet_time_s` is the time of the
  /// packet's first firing relative to the revolution start [s]; each point's `time` adds the
  /// firing offset within the packet. On a non-kOk status nothing is appended.
  PacketStatus decode(const std::uint8_t* data, std::size_t size, double packet_time_s,
                      CloudXYZIRT* cloud, DecodeStats* stats) const;

  /// Same, but also records the laser id and raw azimuth [1/100 deg] of each emitted point
  /// (used by tests and the simulator's ground-truth bookkeeping). Either vector may be null.
  PacketStatus decode(const std::uint8_t* data, std::size_t size, double packet_time_s,
                      CloudXYZIRT* cloud, DecodeStats* stats, std::vector<std::uint8_t>* laser,
                      std::vector<std::uint16_t>* raw_azimuth) const;

  /// Checks a packet without decoding it (size, block ids, azimuths, stopped motor, dual
  /// return).
  static PacketStatus validate(const std::uint8_t* data, std::size_t size);

  const Calibration& calibration() const { return calibration_; }
  const DecoderParams& params() const { return params_; }

  /// Per-laser constants of the correction model in float, one array per term so the
  /// per-block loop vectorises (implementation detail).
  struct LaserTables {
    using Row = std::array<float, kNumLasers>;
    Row cos_rot, sin_rot;      // [-] of the rotational correction
    Row cos_vert, sin_vert;    // [-] of the vertical correction
    Row dist_corr;             // [m] far-field distance correction
    Row vert_off_sin;          // [m] vert_offset * sin_vert
    Row vert_off_cos;          // [m] vert_offset * cos_vert
    Row horiz_off;             // [m] horizontal offset
    Row two_pt_ax, two_pt_bx;  // [m], [-]: near-range correction along x = ax + bx * |x|
    Row two_pt_ay, two_pt_by;  // [m], [-]: same along y
    Row focal_offset;          // [-] 256 * (1 - focal_distance / 131.07 m)^2
    Row focal_slope;           // [-]
    Row min_intensity, max_intensity;
    std::array<std::int32_t, kNumLasers> ring;  // ring_of_laser (int32 for vector stores)
  };

 private:
  template <bool kRecord>
  PacketStatus decodeImpl(const std::uint8_t* data, std::size_t size, double packet_time_s,
                          CloudXYZIRT* cloud, DecodeStats* stats, std::vector<std::uint8_t>* laser,
                          std::vector<std::uint16_t>* raw_azimuth) const;

  Calibration calibration_;
  DecoderParams params_;
  // Precomputed tables (implementation detail, free to change).
  std::vector<float> cos_azimuth_, sin_azimuth_;  // [36000] cos/sin of raw azimuth
  LaserTables table_;
};

/// Time offset of firing `firing` (0..5) within a packet [s]; each firing fires an upper and a
/// lower block together.
double firingTimeOffset(int firing);

/// Reads the azimuth [1/100 deg] of block `block` of a packet (no validation).
std::uint16_t blockAzimuth(const std::uint8_t* data, int block);

/// One firing of all 64 lasers at one azimuth, in raw units.
struct Firing {
  std::uint16_t azimuth = 0;                         // [1/100 deg] 0..35999
  std::array<std::uint16_t, kNumLasers> distance{};  // [distance_resolution] 0 = no return
  std::array<std::uint8_t, kNumLasers> intensity{};  // raw intensity
};

/// Builds packets from firings: every 6 firings make one packet (upper + lower block each),
/// with the given timestamp [us past the hour] and status bytes. Inverse of PacketDecoder.
class PacketEncoder {
 public:
  explicit PacketEncoder(const Calibration& calibration);

  /// Packs 6 firings into one packet (status bytes 0).
  RawPacket encode(const Firing* firings6, std::uint32_t timestamp_us) const;
  /// Same with explicit status type/value bytes (bytes 1204 and 1205).
  RawPacket encode(const Firing* firings6, std::uint32_t timestamp_us, std::uint8_t status_type,
                   std::uint8_t status_value) const;

  /// Inverse correction model: the raw distance [units] and raw azimuth [1/100 deg] of laser
  /// `laser` for which the decoder reproduces the point (x, y, z) [m] to within one raw unit.
  /// The point is assumed to lie on the laser's beam surface (e.g. a ray() hit or a decoded
  /// point): the horizontal position is inverted exactly (fixed-point iteration through the
  /// two-point near-range terms), z follows from the laser's elevation and is not checked; an
  /// off-beam point gets the raw values of the beam point with the same horizontal position.
  /// Quantisation of the result: 0.01 deg in azimuth, one raw unit (2 mm) in distance.
  /// Returns false for an invalid laser, a non-finite point, a point inside the horizontal
  /// offset circle or beyond the raw range (raw distance 1..65535).
  bool invert(int laser, double x, double y, double z, std::uint16_t* raw_azimuth,
              std::uint16_t* raw_distance) const;

  /// Ray of laser `laser` at raw azimuth `raw_azimuth` in the sensor frame: origin [m] and unit
  /// direction, such that a surface hit at distance d along the ray is decoded at
  /// origin + d * direction (far-field model, used by the simulator's ray caster).
  /// The distance d along ray() is the corrected far-field distance
  /// raw * distance_resolution + dist_correction; the two-point near-range correction moves
  /// decoded points by up to a few centimetres below ~25 m (use invert() for exact raw values).
  void ray(int laser, std::uint16_t raw_azimuth, float origin[3], float direction[3]) const;

  /// Raw distance [units] of laser `laser` for the far-field distance `d_m` along ray().
  /// Returns false outside 1..65535 raw units.
  bool rawDistance(int laser, double d_m, std::uint16_t* raw_distance) const;

  const Calibration& calibration() const { return calibration_; }

 private:
  Calibration calibration_;
};

/// Cuts a stream of packets into whole revolutions at a configurable azimuth, so 300-1200 rpm
/// all give whole revolutions (no fixed packet count). Robust to a hostile stream: a packet
/// delivered out of order or a stray packet never cuts a revolution.
///
/// The head advances by about 1 deg per packet at 600 rpm (3472 packets/s, 2 deg at 1200 rpm).
/// A packet is a step of the stream when it advances the azimuth of the last step by at most
/// kMaxStep; the revolution ends where a step crosses the cut angle. A packet that goes back
/// by at most kMaxStep was delivered out of order: it belongs to the open revolution and does
/// not move the head. Any other packet (a jump) is held as a candidate: if the next packet is a
/// step from it and not from the head, the stream really jumped (packets lost, a restart) and
/// the head follows (a forward jump across the cut angle cuts there, one packet late);
/// otherwise the jump was a stray packet and is ignored.
class RevolutionCutter {
 public:
  static constexpr int kMaxStep = 1000;  // [1/100 deg] 10 deg: four lost packets at 1200 rpm

  enum class Step {
    kStep,       // the head moved forward (or stood still) without crossing the cut angle
    kCut,        // the head crossed the cut angle: this packet starts a new revolution
    kReordered,  // at most kMaxStep behind the head: late, belongs to the open revolution
    kJump,       // neither: a stray packet, or the first of a jump (not part of a revolution)
    kRestart,    // the head jumped backwards (confirmed): the open revolution is broken
  };

  explicit RevolutionCutter(double cut_angle_deg = 0.0);

  /// Classifies the next packet by the azimuth of its first block. The first packet after
  /// construction or reset() is a kStep (no crossing observed yet), so the revolution it
  /// belongs to is partial and callers drop it.
  Step step(std::uint16_t first_block_azimuth);
  /// step() == kCut: the cut angle lies in (head, this azimuth], going in the sense of
  /// rotation (increasing azimuth, modulo 360 deg).
  bool startsNewRevolution(std::uint16_t first_block_azimuth) {
    return step(first_block_azimuth) == Step::kCut;
  }
  void reset();
  double cutAngleDeg() const { return cut_ / 100.0; }

 private:
  bool crosses(int from, int to) const;  // the cut angle in (from, to], going forward

  int cut_;             // [1/100 deg]
  int last_ = -1;       // the head: azimuth of the last step, or -1
  int candidate_ = -1;  // azimuth of the last kJump packet, or -1
};

/// Where each packet of a stream goes when the stream is cut into whole revolutions: the one
/// boundary logic of every revolution builder (PacketSource's scans, its streaming decoder).
/// Only revolutions bounded by two observed cuts are whole: the partial one at the start of a
/// stream (and whatever is open at reset()) is dropped; a run of packets that never crosses
/// the cut angle is dropped at kMaxPacketsPerRevolution.
class RevolutionBoundary {
 public:
  /// Three revolutions at 300 rpm, the slowest HDL-64E setting.
  static constexpr std::size_t kMaxPacketsPerRevolution = 3 * 695;

  /// What to do with the open revolution before the packet is added to it.
  enum class Action {
    kAppend,     // the packet continues the open revolution
    kClose,      // the open revolution is whole and complete: emit it; the packet opens the next
    kDrop,       // the open revolution was partial: drop it; the packet opens the next (whole)
    kForcedCut,  // no cut within kMaxPacketsPerRevolution: drop it; the packet opens a partial one
    kOpen,       // nothing was open: the packet opens a revolution (partial)
    kSkip,       // the packet is not part of any revolution: invalid (lastStatus() says why) or
                 // a stray (RevolutionCutter::kJump); nothing changes
  };

  explicit RevolutionBoundary(double cut_angle_deg = 0.0) : cutter_(cut_angle_deg) {}

  /// Validates the packet (PacketDecoder::validate: size, block ids, azimuths, model, dual
  /// return) and classifies it by the azimuth of its first block; unless kSkip, the packet
  /// afterwards belongs to the open revolution.
  Action add(const std::uint8_t* data, std::size_t size);
  /// The same for a packet known to be valid, by its first block azimuth.
  Action add(std::uint16_t first_block_azimuth);
  /// Why the last kSkip packet was invalid (kOk: it was a stray).
  PacketStatus lastStatus() const { return last_status_; }
  /// Drops the open revolution (counted as partial) and restarts cut detection.
  void reset();
  /// A file's stream starts (a capture, or a new pass over it): its first valid packet opens a
  /// whole revolution when its azimuth lies within `tolerance_deg` after the cut angle (a
  /// capture that starts at the cut), PcapRevolutionReader's first-revolution rule.
  void startFile(double tolerance_deg);
  /// The file's stream ends: true when the open revolution is whole by PcapRevolutionReader's
  /// end rule (begun at a cut, at least 90 % of `expected_packets`); then it is the caller's,
  /// otherwise it is dropped and counted as partial. Cut detection restarts either way.
  bool finishFile(std::size_t expected_packets);

  bool open() const { return packets_ > 0; }
  /// The open revolution was opened by an observed cut (it will be whole when it closes).
  bool openWhole() const { return whole_; }
  std::size_t openPackets() const { return packets_; }
  std::size_t partialDropped() const { return partial_dropped_; }
  std::size_t forcedCuts() const { return forced_cuts_; }
  std::size_t invalidPackets() const { return invalid_; }      // skipped: failed validation
  std::size_t strayPackets() const { return strays_; }         // skipped: RevolutionCutter::kJump
  std::size_t reorderedPackets() const { return reordered_; }  // appended although late
  double cutAngleDeg() const { return cutter_.cutAngleDeg(); }

 private:
  RevolutionCutter cutter_;
  std::size_t packets_ = 0;  // of the open revolution
  bool whole_ = false;       // the open revolution was opened by an observed cut
  std::size_t partial_dropped_ = 0;
  std::size_t forced_cuts_ = 0;
  std::size_t invalid_ = 0, strays_ = 0, reordered_ = 0;
  PacketStatus last_status_ = PacketStatus::kOk;
  int start_tolerance_ = -1;  // [1/100 deg] startFile() pending for the next opened revolution
};

/// "" when a whole revolution of `packets` packets is plausible against the `expected` count
/// (the sensor's packet rate over its spin period; 0 = unknown), else "too few packets" (less
/// than 90 %: packets lost) or "too many packets" (more than 110 %: another sender's packets
/// mixed in, or the sensor spins slower than configured).
const char* revolutionSizeProblem(std::size_t packets, std::size_t expected);

}  // namespace core
}  // namespace urban_detection
