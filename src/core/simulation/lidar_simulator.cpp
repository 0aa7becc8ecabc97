#include "urban_detection/core/simulation/lidar_simulator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace urban_detection {
namespace core {

namespace {

// Counter-based noise: the value for (seed, firing, laser) does not depend on which revolution
// is simulated first, so any revolution can be regenerated identically.
inline std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}
inline double unit(std::uint64_t h) {  // (0, 1]
  return (static_cast<double>(h >> 11) + 1.0) * (1.0 / 9007199254740992.0);
}
// Standard normal from two counter-based uniforms (Box-Muller).
inline double gaussian(std::uint64_t h1, std::uint64_t h2) {
  return std::sqrt(-2.0 * std::log(unit(h1))) * std::cos(6.283185307179586 * unit(h2));
}

// Cheap near-normal deviate (mean 0, variance 1) from one hash: the sum of four 16-bit uniforms
// (Irwin-Hall), for the per-return reflectivity, where the tails do not matter.
inline double nearGaussian(std::uint64_t h) {
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) sum += static_cast<double>((h >> (16 * k)) & 0xFFFFu) / 65535.0;
  return (sum - 2.0) * 1.7320508075688772;  // sqrt(12 / 4)
}

constexpr int kMaxFoliagePasses = 8;  // porous volumes one ray may pass through
constexpr double kStepM = 1e-4;       // [m] restart a cast this far past a surface

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

void validate(const SimSensorParams& s) {
  const std::string range =
      checkFieldRanges(s, [](const std::string& name) { return "sensor/" + name; });
  require(range.empty(), range);
  require(s.max_range_m > s.min_range_m, "sensor: need min_range_m < max_range_m");
  require(s.cut_angle_deg < 360.0, "parameter 'sensor/cut_angle_deg' must be < 360");
}

LidarSimulator::LidarSimulator(Scene scene, const SceneParams& scene_params,
                               const DriveParams& drive, const Calibration& calibration,
                               const SimSensorParams& sensor)
    : scene_(std::move(scene)),
      scene_params_(scene_params),
      drive_(drive),
      sensor_(sensor),
      encoder_(calibration),
      cutter_(sensor.cut_angle_deg) {
  validate(sensor_);
  validate(drive_);
  validate(scene_params_);
  firing_period_s_ = firingTimeOffset(1) - firingTimeOffset(0);
  require(firing_period_s_ > 1e-6 && firing_period_s_ < 1e-3,
          "firingTimeOffset(): firing period out of range");
  azimuth_step_ = 36000.0 * sensor_.rpm / 60.0 * firing_period_s_;
  caster_ = std::make_unique<RayCaster>(scene_);
  dist_correction_m_.resize(kNumLasers);
  for (int l = 0; l < kNumLasers; ++l) {
    dist_correction_m_[l] = static_cast<float>(calibration.lasers.at(l).dist_correction_m);
  }
  // The far-field rays of PacketEncoder::ray turn rigidly with the azimuth; if this holds for
  // every laser at a spread of azimuths, rays are built from the azimuth-0 ones (saves a
  // sin/cos per ray). Otherwise every ray is asked from the encoder.
  base_origin_.resize(kNumLasers);
  base_dir_.resize(kNumLasers);
  for (int l = 0; l < kNumLasers; ++l) {
    float o[3], d[3];
    encoder_.ray(l, 0, o, d);
    base_origin_[l] = Eigen::Vector3d(o[0], o[1], o[2]);
    base_dir_[l] = Eigen::Vector3d(d[0], d[1], d[2]).normalized();
  }
  fast_rays_ = true;
  for (std::uint16_t az : {1u, 4500u, 9001u, 17999u, 22222u, 35999u}) {
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(-az * (3.14159265358979323846 / 18000.0), Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    for (int l = 0; l < kNumLasers; ++l) {
      float o[3], d[3];
      encoder_.ray(l, az, o, d);
      const double e_o = (turn * base_origin_[l] - Eigen::Vector3d(o[0], o[1], o[2])).norm();
      const double e_d =
          (turn * base_dir_[l] - Eigen::Vector3d(d[0], d[1], d[2]).normalized()).norm();
      if (e_o > 1e-5 || e_d > 1e-6) fast_rays_ = false;
    }
  }
  reset();
}

LidarSimulator::~LidarSimulator() = default;

void LidarSimulator::reset() {
  next_packet_ = 0;
  next_revolution_ = 0;
  pending_start_ = false;
  cutter_.reset();
}

double LidarSimulator::firingTime(std::uint64_t firing) const {
  const std::uint64_t packet = firing / 6;
  return static_cast<double>(packet) * 6.0 * firing_period_s_ +
         firingTimeOffset(static_cast<int>(firing % 6));
}

std::uint16_t LidarSimulator::rawAzimuth(std::uint64_t firing) const {
  const double a = sensor_.cut_angle_deg * 100.0 + static_cast<double>(firing) * azimuth_step_;
  return static_cast<std::uint16_t>(static_cast<std::uint64_t>(std::llround(a)) % 36000);
}

bool LidarSimulator::driveFinished() const {
  return firingTime(next_packet_ * 6) >= drive_.duration();
}

std::size_t LidarSimulator::revolutionsInDrive() const {
  const double rev_s = 60.0 / sensor_.rpm;
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(drive_.duration() / rev_s)));
}

Eigen::Isometry3d LidarSimulator::basePose(double t_s) const {
  Eigen::Vector2d xy;
  double yaw = 0.0;
  drive_.at(t_s, &xy, &yaw);
  // The platform pitches with the road's slope along its heading.
  const double pitch = -std::atan(scene_params_.slope * std::cos(yaw));
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(xy.x(), xy.y(), groundHeight(scene_params_, xy.x(), xy.y()));
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix();
  return pose;
}

Eigen::Isometry3d LidarSimulator::baseToSensor() const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation().z() = sensor_.height_m;
  return t;
}

void LidarSimulator::simulateNext(SimRevolution* out) {
  out->packets.clear();
  out->packet_stamps_s.clear();
  out->instance_ids.clear();
  out->classes.clear();
  out->world_points.clear();
  out->stats = SimStats();
  out->index = next_revolution_++;
  out->start_time_s = firingTime(next_packet_ * 6);
  out->stamp_s = stampOf(out->start_time_s);

  // Moving objects are binned for the whole revolution (plus slack for slow rpm).
  const double rev_s = 60.0 / sensor_.rpm;
  caster_->setTimeWindow(out->start_time_s, out->start_time_s + 1.2 * rev_s);
  // Guard: a revolution never needs more packets than 1.2 turns' worth.
  const std::size_t max_packets =
      static_cast<std::size_t>(1.2 * rev_s / (6.0 * firing_period_s_)) + 2;
  out->packets.reserve(max_packets);
  for (std::size_t n = 0; n < max_packets; ++n) {
    bool starts;
    if (pending_start_) {
      starts = true;
      pending_start_ = false;
    } else {
      starts = cutter_.startsNewRevolution(rawAzimuth(next_packet_ * 6));
    }
    if (starts && n > 0) {
      pending_start_ = true;
      break;
    }
    simulatePacket(next_packet_++, out);
  }
}

bool LidarSimulator::throughFoliage(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                    double t_s, std::uint64_t h, RayHit* hit, bool* inside,
                                    SimStats* stats) {
  *inside = false;
  const double max_d = sensor_.max_range_m + 1.0;
  for (int pass = 0; pass < kMaxFoliagePasses; ++pass) {
    const Primitive& p = scene_.primitives[hit->primitive];
    if (!p.porous()) return true;
    double t_in, t_out;
    if (!p.span(origin, dir, t_s, &t_in, &t_out)) return true;  // grazing: keep the surface
    t_out = std::max(t_out, hit->distance_m);
    const std::uint64_t hp = mix(h + 100 + 2 * static_cast<std::uint64_t>(pass));
    if (unit(hp) <= p.transmission) {
      // Through the gaps between the leaves: on to whatever lies behind the volume.
      ++stats->transmitted;
      const double start = t_out + kStepM;
      if (start >= max_d) return false;
      RayHit next = caster_->cast(origin + start * dir, dir, max_d - start, t_s);
      if (next.distance_m < 0.0) return false;
      next.distance_m += start;
      *hit = next;
      continue;
    }
    // Stopped by a leaf at an exponential depth, at the latest at the back of the volume or at
    // a solid surface inside it (a trunk in a crown, a wall behind a hedge).
    const double depth =
        std::min(-std::log(unit(mix(hp + 1))) * p.penetration_m, 0.98 * (t_out - hit->distance_m));
    if (depth > kStepM) {
      const double start = hit->distance_m + kStepM;
      const RayHit in = caster_->cast(origin + start * dir, dir, depth, t_s);
      if (in.distance_m >= 0.0 && !scene_.primitives[in.primitive].porous()) {
        hit->distance_m = start + in.distance_m;
        hit->primitive = in.primitive;
        return true;
      }
      hit->distance_m += depth;
      *inside = true;
    }
    ++stats->foliage_returns;
    return true;
  }
  return true;
}

void LidarSimulator::simulatePacket(std::uint64_t packet, SimRevolution* out) {
  const Calibration& cal = encoder_.calibration();
  const double res = cal.distance_resolution_m;
  Firing firings[6];
  for (int f = 0; f < 6; ++f) {
    const std::uint64_t k = packet * 6 + static_cast<std::uint64_t>(f);
    const double t = firingTime(k);
    Firing& fi = firings[f];
    fi.azimuth = rawAzimuth(k);
    const Eigen::Isometry3d pose = sensorPose(t);
    const Eigen::Matrix3d rot = pose.linear();
    // Fast path: the encoder's ray at azimuth a is its ray at azimuth 0 turned by -a about z.
    const double a = fi.azimuth * (3.14159265358979323846 / 18000.0);
    const Eigen::Matrix3d turn =
        rot * Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (int l = 0; l < kNumLasers; ++l) {
      fi.distance[l] = 0;
      fi.intensity[l] = 0;
      ++out->stats.rays;
      Eigen::Vector3d origin, dir;
      if (fast_rays_) {
        origin = pose.translation() + turn * base_origin_[l];
        dir = turn * base_dir_[l];
      } else {
        float o[3], d[3];
        encoder_.ray(l, fi.azimuth, o, d);
        origin = pose * Eigen::Vector3d(o[0], o[1], o[2]);
        dir = (rot * Eigen::Vector3d(d[0], d[1], d[2])).normalized();
      }
      RayHit hit = caster_->cast(origin, dir, sensor_.max_range_m + 1.0, t);
      if (hit.distance_m < 0.0) {
        ++out->stats.no_hit;
        continue;
      }
      const std::uint64_t h = mix(sensor_.noise_seed * 0x9E3779B97F4A7C15ULL ^ mix(k * 64 + l));
      bool inside = false;
      if (!throughFoliage(origin, dir, t, h, &hit, &inside, &out->stats)) {
        ++out->stats.no_hit;
        continue;
      }
      if (unit(mix(h)) <= sensor_.dropout_probability) {
        ++out->stats.dropped;
        continue;
      }
      const double range =
          hit.distance_m + sensor_.range_noise_m * gaussian(mix(h + 1), mix(h + 2));
      if (range < sensor_.min_range_m || range > sensor_.max_range_m) {
        ++out->stats.out_of_range;
        continue;
      }
      // Far-field model of PacketEncoder::ray: decoded distance = raw * res + dist_correction.
      const long raw = std::lround((range - dist_correction_m_[l]) / res);
      if (raw <= 0 || raw > 65535) {
        ++out->stats.out_of_range;
        continue;
      }
      const Primitive& prim = scene_.primitives[hit.primitive];
      fi.distance[l] = static_cast<std::uint16_t>(raw);
      // Intensity by material (a per-return draw around the surface's reflectivity), slightly
      // fading with range and jittered; a return from inside foliage comes from a partly
      // covered footprint and is dimmer.
      const double refl = std::clamp(
          prim.reflectivity + prim.reflectivity_spread * nearGaussian(mix(h + 4)), 0.0, 1.0);
      const double fade = 1.0 / (1.0 + 0.004 * hit.distance_m);
      const double jitter = 0.85 + 0.3 * unit(mix(h + 3));
      const double partial = inside ? 0.5 + 0.5 * unit(mix(h + 6)) : 1.0;
      fi.intensity[l] =
          static_cast<std::uint8_t>(std::clamp(255.0 * refl * fade * jitter * partial, 0.0, 255.0));
      out->instance_ids.push_back(prim.instance_id);
      out->classes.push_back(static_cast<std::uint8_t>(prim.object_class));
      out->world_points.push_back((origin + hit.distance_m * dir).cast<float>());
      ++out->stats.returns;
    }
  }
  const double t0 = firingTime(packet * 6);
  const double stamp = stampOf(t0);
  const double past_hour = std::fmod(stamp, 3600.0);
  const auto ts_us = static_cast<std::uint32_t>(std::llround(past_hour * 1e6)) % 3600000000u;
  out->packets.push_back(encoder_.encode(firings, ts_us));
  out->packet_stamps_s.push_back(stamp);
}

}  // namespace core
}  // namespace urban_detection
