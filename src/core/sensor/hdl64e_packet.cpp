// HDL-64E packet decoding and encoding.
//
// Correction model (Velodyne HDL-64E S2/S3 manuals, as applied by velodyne_pointcloud), for a
// laser with rotational correction rot, vertical angle v, distance correction dc, two-point terms
// dcx/dcy, vertical offset vo and horizontal offset ho, a raw azimuth a and raw distance r:
//   d       = r * resolution + dc                      (far-field corrected distance)
//   theta   = a - rot
//   xy0     = d cos v - vo sin v
//   xx, yy  = |xy0 sin theta - ho cos theta|, |xy0 cos theta + ho sin theta|
//   dx      = d + (dc - dcx) (xx - 2.4) / (25.04 - 2.4) + dcx - dc      (two-point, along x)
//   dy      = d + (dc - dcy) (yy - 1.93) / (25.04 - 1.93) + dcy - dc    (two-point, along y)
//   X       = (dx cos v - vo sin v) sin theta - ho cos theta   (Velodyne frame: X right,
//   Y       = (dy cos v - vo sin v) cos theta + ho sin theta    Y forward, Z up)
//   Z       = dy sin v + vo cos v
// and the ROS frame (x forward, y left) is x = Y, y = -X, z = Z. The two-point terms are affine
// in |X|, |Y|, so they are stored as ax + bx |X| per laser.
//
// Intensity (HDL-64E S2 manual, intensity compensation): with the focal distance f and both
// distances normalised by the full raw scale (65535 units = 131.07 m),
//   i = raw_i + focal_slope * |256 (1 - f / 131.07 m)^2 - 256 (1 - r / 65535)^2|
// clamped to [min_intensity, max_intensity]. velodyne_pointcloud divides f by 13100 although
// its YAML stores f in metres, which makes the focal offset a constant ~256; we keep f in metres
// and normalise it by the same full scale as the distance, as the manual intends.
#include "urban_detection/core/sensor/hdl64e_packet.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace urban_detection {
namespace core {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRawAzimuthToRad = kPi / 18000.0;  // 1/100 degree
constexpr int kBlockSize = 100;
constexpr int kReturnSize = 3;
constexpr std::size_t kTimestampOffset = kBlocksPerPacket * kBlockSize;     // 1200
constexpr double kFullScaleM = 65535 * 0.002;                               // 131.07 m
constexpr double kTwoPtXNear = 2.4, kTwoPtYNear = 1.93, kTwoPtFar = 25.04;  // [m]

// The vector stores of the decoder write PointXYZIRT as two 16-byte halves.
static_assert(sizeof(PointXYZIRT) == 32 && alignof(PointXYZIRT) == 16, "PointXYZIRT layout");
static_assert(offsetof(PointXYZIRT, intensity) == 16 && offsetof(PointXYZIRT, ring) == 20 &&
                  offsetof(PointXYZIRT, time) == 24,
              "PointXYZIRT layout");

inline std::uint16_t readU16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline void writeU16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}

// Two-point correction as ax + bx * |X| (and the same along Y).
void twoPointCoefficients(const LaserCorrection& c, double* ax, double* bx, double* ay,
                          double* by) {
  if (!c.two_pt_correction_available) {
    *ax = *bx = *ay = *by = 0.0;
    return;
  }
  *bx = (c.dist_correction_m - c.dist_correction_x_m) / (kTwoPtFar - kTwoPtXNear);
  *ax = c.dist_correction_x_m - c.dist_correction_m - kTwoPtXNear * *bx;
  *by = (c.dist_correction_m - c.dist_correction_y_m) / (kTwoPtFar - kTwoPtYNear);
  *ay = c.dist_correction_y_m - c.dist_correction_m - kTwoPtYNear * *by;
}

}  // namespace

const char* toString(PacketStatus status) {
  switch (status) {
    case PacketStatus::kOk:
      return "ok";
    case PacketStatus::kWrongSize:
      return "wrong packet size (expected 1206 bytes)";
    case PacketStatus::kUnknownBlockId:
      return "unknown block id (expected 0xEEFF or 0xDDFF)";
    case PacketStatus::kBadAzimuth:
      return "azimuth out of range (>= 36000)";
    case PacketStatus::kOtherModel:
      return "not an HDL-64E packet (no lower-bank block: the layout of VLP-16, VLP-32C, "
             "HDL-32E)";
    case PacketStatus::kDualReturn:
      return "dual-return packet (not supported, set the sensor to single return)";
    case PacketStatus::kStoppedMotor:
      return "azimuth constant across the packet: the sensor's motor is stopped (or its "
             "encoder is broken)";
  }
  return "unknown status";
}

double firingTimeOffset(int firing) {
  return firing * kFiringPeriodS;
}

std::uint16_t blockAzimuth(const std::uint8_t* data, int block) {
  return readU16(data + block * kBlockSize + 2);
}

// ------------------------------------------------------------------------------------------------
PacketDecoder::PacketDecoder(const Calibration& calibration, const DecoderParams& params)
    : calibration_(calibration), params_(params) {
  if (calibration_.ring_of_laser.size() != static_cast<std::size_t>(kNumLasers)) {
    calibration_.finalize();  // throws CalibrationError if unusable
  }
  cos_azimuth_.resize(36000);
  sin_azimuth_.resize(36000);
  for (int a = 0; a < 36000; ++a) {
    cos_azimuth_[a] = static_cast<float>(std::cos(a * kRawAzimuthToRad));
    sin_azimuth_[a] = static_cast<float>(std::sin(a * kRawAzimuthToRad));
  }
  LaserTables& t = table_;
  for (int l = 0; l < kNumLasers; ++l) {
    const LaserCorrection& c = calibration_.lasers[l];
    t.cos_rot[l] = static_cast<float>(std::cos(c.rot_correction_rad));
    t.sin_rot[l] = static_cast<float>(std::sin(c.rot_correction_rad));
    t.cos_vert[l] = static_cast<float>(std::cos(c.vert_correction_rad));
    t.sin_vert[l] = static_cast<float>(std::sin(c.vert_correction_rad));
    t.dist_corr[l] = static_cast<float>(c.dist_correction_m);
    t.vert_off_sin[l] =
        static_cast<float>(c.vert_offset_correction_m * std::sin(c.vert_correction_rad));
    t.vert_off_cos[l] =
        static_cast<float>(c.vert_offset_correction_m * std::cos(c.vert_correction_rad));
    t.horiz_off[l] = static_cast<float>(c.horiz_offset_correction_m);
    double ax, bx, ay, by;
    twoPointCoefficients(c, &ax, &bx, &ay, &by);
    t.two_pt_ax[l] = static_cast<float>(ax);
    t.two_pt_bx[l] = static_cast<float>(bx);
    t.two_pt_ay[l] = static_cast<float>(ay);
    t.two_pt_by[l] = static_cast<float>(by);
    const double f = 1.0 - c.focal_distance / kFullScaleM;
    t.focal_offset[l] = static_cast<float>(256.0 * f * f);
    t.focal_slope[l] = static_cast<float>(c.focal_slope);
    t.min_intensity[l] = static_cast<float>(c.min_intensity);
    t.max_intensity[l] = static_cast<float>(c.max_intensity);
    t.ring[l] = calibration_.ring_of_laser[l];
  }
}

std::string validate(const DecoderParams& params) {
  std::string error = checkFieldRanges(params);
  if (error.empty() && !(params.min_range_m < params.max_range_m)) {
    std::ostringstream msg;
    msg << "parameters 'min_range' = " << params.min_range_m
        << " and 'max_range' = " << params.max_range_m << ": accepted min_range < max_range";
    error = msg.str();
  }
  return error;
}

std::string velodyneModelName(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size != kPacketSize) return "an unknown model (not a 1206-byte packet)";
  const std::uint8_t mode = data[1204], product = data[1205];
  const char* model = nullptr;
  switch (product) {  // factory byte: Velodyne's interface manuals (VLP-16, VLP-32C, HDL-32E)
    case 0x21:
      model = "HDL-32E";
      break;
    case 0x22:
      model = "VLP-16";
      break;
    case 0x24:
      model = "Puck Hi-Res";
      break;
    case 0x28:
      model = "VLP-32C";
      break;
    case 0x31:
      model = "Velarray";
      break;
    case 0xA1:
      model = "VLS-128";
      break;
    default:
      break;
  }
  const char* returns = mode == 0x37   ? "strongest return"
                        : mode == 0x38 ? "last return"
                        : mode == 0x39 ? "dual return"
                                       : nullptr;
  char bytes[64];
  std::snprintf(bytes, sizeof(bytes), "factory bytes 0x%02X 0x%02X", mode, product);
  if (!model) return std::string("an unknown model (") + bytes + ")";
  return std::string(model) + " (" + (returns ? returns : bytes) + ")";
}

PacketStatus PacketDecoder::validate(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size != kPacketSize) return PacketStatus::kWrongSize;
  std::uint16_t id[kBlocksPerPacket], az[kBlocksPerPacket];
  bool lower = false;
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    id[b] = readU16(data + b * kBlockSize);
    az[b] = readU16(data + b * kBlockSize + 2);
    if (id[b] != kUpperBlockId && id[b] != kLowerBlockId) return PacketStatus::kUnknownBlockId;
    lower = lower || id[b] == kLowerBlockId;
  }
  if (!lower) return PacketStatus::kOtherModel;
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    if (az[b] >= 36000) return PacketStatus::kBadAzimuth;
  }
  if (std::all_of(az + 1, az + kBlocksPerPacket, [&](std::uint16_t a) { return a == az[0]; })) {
    return PacketStatus::kStoppedMotor;
  }
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    for (int o = b + 1; o < kBlocksPerPacket; ++o) {
      if (id[b] == id[o] && az[b] == az[o]) return PacketStatus::kDualReturn;
    }
  }
  return PacketStatus::kOk;
}

PacketStatus PacketDecoder::decode(const std::uint8_t* data, std::size_t size, double packet_time_s,
                                   CloudXYZIRT* cloud, DecodeStats* stats) const {
  return decodeImpl<false>(data, size, packet_time_s, cloud, stats, nullptr, nullptr);
}

PacketStatus PacketDecoder::decode(const std::uint8_t* data, std::size_t size, double packet_time_s,
                                   CloudXYZIRT* cloud, DecodeStats* stats,
                                   std::vector<std::uint8_t>* laser,
                                   std::vector<std::uint16_t>* raw_azimuth) const {
  if (laser == nullptr && raw_azimuth == nullptr) {
    return decodeImpl<false>(data, size, packet_time_s, cloud, stats, nullptr, nullptr);
  }
  return decodeImpl<true>(data, size, packet_time_s, cloud, stats, laser, raw_azimuth);
}

template <bool kRecord>
PacketStatus PacketDecoder::decodeImpl(const std::uint8_t* data, std::size_t size,
                                       double packet_time_s, CloudXYZIRT* cloud, DecodeStats* stats,
                                       std::vector<std::uint8_t>* laser,
                                       std::vector<std::uint16_t>* raw_azimuth) const {
  const PacketStatus status = validate(data, size);
  if (stats != nullptr) {
    ++stats->packets;
    if (status != PacketStatus::kOk) ++stats->bad_packets;
  }
  if (status != PacketStatus::kOk || cloud == nullptr) return status;

  auto& points = cloud->points;
  constexpr std::size_t kMaxPoints = kBlocksPerPacket * kLasersPerBlock;
  if (points.capacity() < points.size() + kMaxPoints) {
    points.reserve(std::max(points.size() + kMaxPoints, 2 * points.capacity()));
  }
  const std::size_t base = points.size();
  points.resize(base + kMaxPoints);
  PointXYZIRT* out = points.data() + base;
  std::size_t n = 0, no_return = 0, out_of_range = 0;

  const float resolution = static_cast<float>(calibration_.distance_resolution_m);
  const float min_range = static_cast<float>(params_.min_range_m);
  const float max_range = static_cast<float>(params_.max_range_m);
  constexpr float kInvFullRaw = 1.0f / 65535.0f;
  const LaserTables& t = table_;

  // Per block: gather the 32 returns, run the correction model over all of them in a
  // branch-free loop over per-laser arrays (vectorised by the compiler), then append the valid
  // ones. Invalid returns are computed and discarded, which is cheaper than branching.
  alignas(32) float raw_f[kLasersPerBlock], raw_i[kLasersPerBlock];
  alignas(32) float px[kLasersPerBlock], py[kLasersPerBlock], pz[kLasersPerBlock];
  alignas(32) float pi[kLasersPerBlock];
  alignas(32) std::int32_t has_return[kLasersPerBlock], valid[kLasersPerBlock];
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    const std::uint8_t* block = data + b * kBlockSize;
    const int bank = readU16(block) == kLowerBlockId ? kLasersPerBlock : 0;
    const std::uint16_t azimuth = readU16(block + 2);
    const float cos_a = cos_azimuth_[azimuth];
    const float sin_a = sin_azimuth_[azimuth];
    const float time = static_cast<float>(packet_time_s + (b / 2) * kFiringPeriodS);
    const std::uint8_t* ret = block + 4;
    for (int j = 0; j < kLasersPerBlock; ++j) {
      raw_f[j] = static_cast<float>(readU16(ret + kReturnSize * j));
      raw_i[j] = static_cast<float>(ret[kReturnSize * j + 2]);
    }
    const float* cos_rot = t.cos_rot.data() + bank;
    const float* sin_rot = t.sin_rot.data() + bank;
    const float* cos_vert = t.cos_vert.data() + bank;
    const float* sin_vert = t.sin_vert.data() + bank;
    const float* dist_corr = t.dist_corr.data() + bank;
    const float* vo_sin = t.vert_off_sin.data() + bank;
    const float* vo_cos = t.vert_off_cos.data() + bank;
    const float* ho = t.horiz_off.data() + bank;
    const float* ax = t.two_pt_ax.data() + bank;
    const float* bx = t.two_pt_bx.data() + bank;
    const float* ay = t.two_pt_ay.data() + bank;
    const float* by = t.two_pt_by.data() + bank;
    const float* f_off = t.focal_offset.data() + bank;
    const float* f_slope = t.focal_slope.data() + bank;
    const float* i_min = t.min_intensity.data() + bank;
    const float* i_max = t.max_intensity.data() + bank;
    for (int j = 0; j < kLasersPerBlock; ++j) {
      const float d = raw_f[j] * resolution + dist_corr[j];
      // theta = azimuth - rot_correction by the angle-difference identities.
      const float cos_t = cos_a * cos_rot[j] + sin_a * sin_rot[j];
      const float sin_t = sin_a * cos_rot[j] - cos_a * sin_rot[j];
      const float xy0 = d * cos_vert[j] - vo_sin[j];
      const float xx = std::fabs(xy0 * sin_t - ho[j] * cos_t);
      const float yy = std::fabs(xy0 * cos_t + ho[j] * sin_t);
      const float dx = d + ax[j] + bx[j] * xx;
      const float dy = d + ay[j] + by[j] * yy;
      const float vx = (dx * cos_vert[j] - vo_sin[j]) * sin_t - ho[j] * cos_t;
      const float vy = (dy * cos_vert[j] - vo_sin[j]) * cos_t + ho[j] * sin_t;
      px[j] = vy;  // ROS frame: x forward = Velodyne Y, y left = -Velodyne X
      py[j] = -vx;
      pz[j] = dy * sin_vert[j] + vo_cos[j];
      const float near = 1.0f - raw_f[j] * kInvFullRaw;
      const float in = raw_i[j] + f_slope[j] * std::fabs(f_off[j] - 256.0f * near * near);
      pi[j] = std::min(std::max(in, i_min[j]), i_max[j]);
      has_return[j] = raw_f[j] != 0.0f;
      valid[j] = has_return[j] & (d >= min_range) & (d <= max_range);
    }
    for (int j = 0; j < kLasersPerBlock; ++j) {
      no_return += static_cast<std::size_t>(1 - has_return[j]);
      out_of_range += static_cast<std::size_t>(has_return[j] - valid[j]);
    }
    // Branch-free compaction: every slot is written, only valid ones advance the cursor (the
    // buffer has room for all 384 returns of a packet). Real scans have many no-return slots
    // in irregular patterns, where branches would mispredict.
    const std::int32_t* ring = t.ring.data() + bank;
    int j = 0;
#if defined(__SSE2__)
    // Four points at a time: transpose the per-laser arrays into the two 16-byte halves of
    // PointXYZIRT, (x, y, z, 1) and (intensity, ring, time, 0), and store each half at once.
    const __m128 one = _mm_set1_ps(1.0f), time4 = _mm_set1_ps(time), zero = _mm_setzero_ps();
    for (; !kRecord && j + 4 <= kLasersPerBlock; j += 4) {
      __m128 r0 = _mm_load_ps(px + j), r1 = _mm_load_ps(py + j), r2 = _mm_load_ps(pz + j), r3 = one;
      _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
      __m128 s0 = _mm_load_ps(pi + j),
             s1 = _mm_castsi128_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(ring + j))),
             s2 = time4, s3 = zero;
      _MM_TRANSPOSE4_PS(s0, s1, s2, s3);
      const __m128 xyz[4] = {r0, r1, r2, r3}, irt[4] = {s0, s1, s2, s3};
      for (int k = 0; k < 4; ++k) {
        float* dst = reinterpret_cast<float*>(out + n);
        _mm_store_ps(dst, xyz[k]);
        _mm_store_ps(dst + 4, irt[k]);
        n += static_cast<std::size_t>(valid[j + k]);
      }
    }
#endif
    for (; j < kLasersPerBlock; ++j) {
      PointXYZIRT& p = out[n];
      p.x = px[j];
      p.y = py[j];
      p.z = pz[j];
      p.data[3] = 1.0f;
      p.intensity = pi[j];
      p.ring = static_cast<std::uint16_t>(ring[j]);
      p.time = time;
      if (kRecord && valid[j]) {
        if (laser != nullptr) laser->push_back(static_cast<std::uint8_t>(bank + j));
        if (raw_azimuth != nullptr) raw_azimuth->push_back(azimuth);
      }
      n += static_cast<std::size_t>(valid[j]);
    }
  }
  points.resize(base + n);
  cloud->width = static_cast<std::uint32_t>(points.size());
  cloud->height = 1;
  if (stats != nullptr) {
    stats->points += n;
    stats->no_return += no_return;
    stats->out_of_range += out_of_range;
  }
  return status;
}

template PacketStatus PacketDecoder::decodeImpl<false>(const std::uint8_t*, std::size_t, double,
                                                       CloudXYZIRT*, DecodeStats*,
                                                       std::vector<std::uint8_t>*,
                                                       std::vector<std::uint16_t>*) const;
template PacketStatus PacketDecoder::decodeImpl<true>(const std::uint8_t*, std::size_t, double,
                                                      CloudXYZIRT*, DecodeStats*,
                                                      std::vector<std::uint8_t>*,
                                                      std::vector<std::uint16_t>*) const;

// ------------------------------------------------------------------------------------------------
PacketEncoder::PacketEncoder(const Calibration& calibration) : calibration_(calibration) {
  if (calibration_.ring_of_laser.size() != static_cast<std::size_t>(kNumLasers)) {
    calibration_.finalize();
  }
}

RawPacket PacketEncoder::encode(const Firing* firings6, std::uint32_t timestamp_us) const {
  return encode(firings6, timestamp_us, 0, 0);
}

RawPacket PacketEncoder::encode(const Firing* firings6, std::uint32_t timestamp_us,
                                std::uint8_t status_type, std::uint8_t status_value) const {
  RawPacket packet{};
  for (int f = 0; f < kBlocksPerPacket / 2; ++f) {
    const Firing& firing = firings6[f];
    for (int half = 0; half < 2; ++half) {
      std::uint8_t* block = packet.data() + (2 * f + half) * kBlockSize;
      writeU16(block, half == 0 ? kUpperBlockId : kLowerBlockId);
      writeU16(block + 2, firing.azimuth);
      std::uint8_t* ret = block + 4;
      for (int j = 0; j < kLasersPerBlock; ++j, ret += kReturnSize) {
        const int l = half * kLasersPerBlock + j;
        writeU16(ret, firing.distance[l]);
        ret[2] = firing.intensity[l];
      }
    }
  }
  std::uint8_t* ts = packet.data() + kTimestampOffset;
  ts[0] = static_cast<std::uint8_t>(timestamp_us & 0xFF);
  ts[1] = static_cast<std::uint8_t>((timestamp_us >> 8) & 0xFF);
  ts[2] = static_cast<std::uint8_t>((timestamp_us >> 16) & 0xFF);
  ts[3] = static_cast<std::uint8_t>((timestamp_us >> 24) & 0xFF);
  packet[kTimestampOffset + 4] = status_type;
  packet[kTimestampOffset + 5] = status_value;
  return packet;
}

bool PacketEncoder::invert(int laser, double x, double y, double z, std::uint16_t* raw_azimuth,
                           std::uint16_t* raw_distance) const {
  (void)z;  // the elevation follows from the laser; only the horizontal position is inverted
  if (laser < 0 || laser >= kNumLasers || !std::isfinite(x) || !std::isfinite(y)) return false;
  const LaserCorrection& c = calibration_.lasers[laser];
  double ax, bx, ay, by;
  twoPointCoefficients(c, &ax, &bx, &ay, &by);
  const double cv = std::cos(c.vert_correction_rad), sv = std::sin(c.vert_correction_rad);
  const double vo = c.vert_offset_correction_m, ho = c.horiz_offset_correction_m;
  const double vx = -y, vy = x;  // Velodyne frame

  // Model: (vx, vy) = (r + cx cv) (sin t, 0) + (r + cy cv) (0, cos t) + ho (-cos t, sin t) with
  // r = d cv - vo sv and cx, cy the two-point terms, which depend on (t, d) only weakly
  // (|bx|, |by| ~ 1e-3). Fixed point: move the two-point terms to the target, solve the offset
  // circle in closed form, re-evaluate the terms; converges to float precision in a few steps.
  double corr_x = 0.0, corr_y = 0.0, theta = 0.0, d = 0.0;
  for (int it = 0; it < 50; ++it) {
    const double tx = vx - corr_x * cv * std::sin(theta);
    const double ty = vy - corr_y * cv * std::cos(theta);
    const double rho2 = tx * tx + ty * ty;
    if (rho2 <= ho * ho) return false;  // inside the offset circle: not on this laser's cone
    const double r = std::sqrt(rho2 - ho * ho);
    const double new_theta = std::atan2(tx, ty) + std::atan2(ho, r);
    const double new_d = (r + vo * sv) / cv;
    const double xx = std::fabs(r * std::sin(new_theta) - ho * std::cos(new_theta));
    const double yy = std::fabs(r * std::cos(new_theta) + ho * std::sin(new_theta));
    corr_x = ax + bx * xx;
    corr_y = ay + by * yy;
    const bool converged =
        it > 0 && std::fabs(new_theta - theta) < 1e-12 && std::fabs(new_d - d) < 1e-10;
    theta = new_theta;
    d = new_d;
    if (converged) break;
  }
  const double raw_d = std::round((d - c.dist_correction_m) / calibration_.distance_resolution_m);
  if (!(raw_d >= 1.0 && raw_d <= 65535.0)) return false;
  long raw_a = std::lround((theta + c.rot_correction_rad) / kRawAzimuthToRad) % 36000;
  if (raw_a < 0) raw_a += 36000;
  *raw_azimuth = static_cast<std::uint16_t>(raw_a);
  *raw_distance = static_cast<std::uint16_t>(raw_d);
  return true;
}

void PacketEncoder::ray(int laser, std::uint16_t raw_azimuth, float origin[3],
                        float direction[3]) const {
  const LaserCorrection& c = calibration_.lasers[std::min(std::max(laser, 0), kNumLasers - 1)];
  const double theta = raw_azimuth * kRawAzimuthToRad - c.rot_correction_rad;
  const double st = std::sin(theta), ct = std::cos(theta);
  const double cv = std::cos(c.vert_correction_rad), sv = std::sin(c.vert_correction_rad);
  const double vo = c.vert_offset_correction_m, ho = c.horiz_offset_correction_m;
  // Velodyne frame origin (X, Y, Z) = (-vo sv st - ho ct, -vo sv ct + ho st, vo cv).
  const double ox = -vo * sv * st - ho * ct;
  const double oy = -vo * sv * ct + ho * st;
  origin[0] = static_cast<float>(oy);
  origin[1] = static_cast<float>(-ox);
  origin[2] = static_cast<float>(vo * cv);
  direction[0] = static_cast<float>(cv * ct);
  direction[1] = static_cast<float>(-cv * st);
  direction[2] = static_cast<float>(sv);
}

bool PacketEncoder::rawDistance(int laser, double d_m, std::uint16_t* raw_distance) const {
  if (laser < 0 || laser >= kNumLasers || !std::isfinite(d_m)) return false;
  const double raw = std::round((d_m - calibration_.lasers[laser].dist_correction_m) /
                                calibration_.distance_resolution_m);
  if (!(raw >= 1.0 && raw <= 65535.0)) return false;
  *raw_distance = static_cast<std::uint16_t>(raw);
  return true;
}

// ------------------------------------------------------------------------------------------------
RevolutionCutter::RevolutionCutter(double cut_angle_deg) {
  double a = std::fmod(cut_angle_deg, 360.0);
  if (!std::isfinite(a)) a = 0.0;
  if (a < 0) a += 360.0;
  cut_ = static_cast<int>(std::lround(a * 100.0)) % 36000;
}

bool RevolutionCutter::crosses(int from, int to) const {
  const int advance = (to - from + 36000) % 36000;        // rotation from `from` to `to`
  const int to_cut = (cut_ - from + 36000) % 36000;       // rotation from `from` to the cut
  return advance > 0 && to_cut > 0 && to_cut <= advance;  // cut in (from, to]
}

RevolutionCutter::Step RevolutionCutter::step(std::uint16_t first_block_azimuth) {
  const int az = first_block_azimuth % 36000;
  if (last_ < 0) {
    last_ = az;
    return Step::kStep;
  }
  const int advance = (az - last_ + 36000) % 36000;  // forward rotation from the head
  if (advance <= kMaxStep) {                         // a step (0: the head stands still)
    candidate_ = -1;
    const bool cut = crosses(last_, az);
    last_ = az;
    return cut ? Step::kCut : Step::kStep;
  }
  if (36000 - advance <= kMaxStep) {  // a little behind the head: delivered late
    candidate_ = -1;
    return Step::kReordered;
  }
  // A jump: confirmed when this packet is a step from the previous jump's packet.
  const int candidate = candidate_;
  candidate_ = az;
  if (candidate < 0 || (az - candidate + 36000) % 36000 > kMaxStep) return Step::kJump;
  candidate_ = -1;
  const int from = last_;
  last_ = az;
  if ((candidate - from + 36000) % 36000 < 18000) {  // forward: packets were lost
    return crosses(from, az) ? Step::kCut : Step::kStep;
  }
  return Step::kRestart;
}

void RevolutionCutter::reset() {
  last_ = -1;
  candidate_ = -1;
}

const char* revolutionSizeProblem(std::size_t packets, std::size_t expected) {
  if (expected == 0) return "";
  if (10 * packets < 9 * expected) return "too few packets";
  if (10 * packets > 11 * expected) return "too many packets";
  return "";
}

RevolutionBoundary::Action RevolutionBoundary::add(const std::uint8_t* data, std::size_t size) {
  last_status_ = PacketDecoder::validate(data, size);
  if (last_status_ != PacketStatus::kOk) {
    ++invalid_;
    return Action::kSkip;
  }
  return add(blockAzimuth(data, 0));
}

RevolutionBoundary::Action RevolutionBoundary::add(std::uint16_t first_block_azimuth) {
  Action action = Action::kAppend;
  const RevolutionCutter::Step step = cutter_.step(first_block_azimuth);
  if (step == RevolutionCutter::Step::kJump) {
    ++strays_;
    return Action::kSkip;
  }
  if (step == RevolutionCutter::Step::kReordered) ++reordered_;
  if (step == RevolutionCutter::Step::kRestart) {  // the open revolution cannot be whole
    if (packets_ > 0) ++partial_dropped_;
    action = packets_ > 0 ? Action::kDrop : Action::kOpen;
    whole_ = false;
    packets_ = 0;
  } else if (step == RevolutionCutter::Step::kCut) {
    if (packets_ > 0) {
      action = whole_ ? Action::kClose : Action::kDrop;
      if (!whole_) ++partial_dropped_;
    } else {
      action = Action::kOpen;
    }
    whole_ = true;
    packets_ = 0;
  } else if (packets_ >= kMaxPacketsPerRevolution) {
    ++forced_cuts_;
    action = Action::kForcedCut;
    whole_ = false;
    packets_ = 0;
  } else if (packets_ == 0) {
    action = Action::kOpen;
  }
  if (start_tolerance_ >= 0 && action == Action::kOpen) {
    const int cut = static_cast<int>(std::lround(cutter_.cutAngleDeg() * 100.0)) % 36000;
    const int after = (static_cast<int>(first_block_azimuth) - cut + 36000) % 36000;
    whole_ = after <= start_tolerance_;
  }
  if (action != Action::kAppend) start_tolerance_ = -1;
  ++packets_;
  return action;
}

void RevolutionBoundary::startFile(double tolerance_deg) {
  reset();
  start_tolerance_ = static_cast<int>(std::lround(std::max(0.0, tolerance_deg) * 100.0));
}

bool RevolutionBoundary::finishFile(std::size_t expected_packets) {
  const bool keep = packets_ > 0 && whole_ && 10 * packets_ >= 9 * expected_packets;
  if (keep) packets_ = 0;
  reset();
  return keep;
}

void RevolutionBoundary::reset() {
  if (packets_ > 0) ++partial_dropped_;
  packets_ = 0;
  whole_ = false;
  cutter_.reset();
}

}  // namespace core
}  // namespace urban_detection
