/// \file lidar_simulator.h
/// Virtual HDL-64E on a moving platform: casts every laser of every firing against a Scene and
/// emits real 1206-byte packets (through PacketEncoder) plus per-return ground truth in the
/// exact order PacketDecoder emits the decoded points (ROS-free).
///
/// Timing: firing k of the drive happens at drive time t = (k / 6) * 6 tau + firingTimeOffset(k
/// mod 6), tau the decoder's firing period; the head turns at `rpm`, so the firing's raw
/// azimuth advances by 36000 * rpm / 60 * tau per firing. Each firing is cast from the platform
/// pose at its own time (the motion skew of a real drive), with moving objects placed at that
/// time. The stream starts at the cut angle and is cut into revolutions by the core
/// RevolutionCutter, exactly as PacketSource/PacketToCloud cut it.
///
/// Foliage (Primitive::porous(), sim_scene.h): a ray that reaches a porous primitive passes
/// through it with the primitive's `transmission` probability and goes on to the next surface
/// (possibly another porous one); otherwise it returns from an exponential depth inside the
/// volume (mean `penetration_m`), cut at the back of the volume and at any solid surface inside
/// it. Leaves therefore give rough range profiles along a scan line and let part of the rays
/// reach what stands behind a hedge or under a crown. Each return is labelled with the surface
/// or volume it came from.
///
/// Intensity: the byte sent for a return is 255 x r x fade x jitter x partial, with r the
/// surface's reflectivity drawn per return (Primitive::reflectivity + reflectivity_spread x a
/// near-normal deviate of unit variance, clamped to [0, 1]), fade = 1 / (1 + 0.004 range [m]),
/// jitter uniform in [0.85, 1.15], partial uniform in [0.5, 1] for a return from inside foliage (a
/// partly covered footprint) and 1 otherwise. Without fade and jitter this is KITTI's scale,
/// reflectance x 255; the materials behind r are listed in scene_generator.h.
///
/// Every random draw (noise, dropout, foliage, intensity) is a hash of (noise_seed, firing,
/// laser), so a revolution is the same whichever revolutions were simulated before it.
#pragma once

#include <cmath>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/sim_scene.h"

namespace urban_detection {
namespace core {

/// Sensor model parameters.
struct SimSensorParams {
  double rpm = 600.0;                  // [rev/min] 300..1200
  double height_m = 1.73;              // [m] sensor origin above the ground (KITTI: 1.73 m)
  double range_noise_m = 0.01;         // [m] std dev of the Gaussian range noise (>= 0)
  double dropout_probability = 0.003;  // [-] chance a surface return is lost
  /// [m] Returns outside [min_range_m, max_range_m] are sent as "no return". Keep this window
  /// strictly inside the decoder's (DecoderParams 0.9..130 m), so that the decoder drops
  /// exactly the returns the simulator dropped and the ground truth stays aligned.
  double min_range_m = 1.0;
  double max_range_m = 120.0;
  double start_stamp_s = 1700000000.0;  // [s] epoch stamp of drive time 0
  double cut_angle_deg = 0.0;           // [deg] revolution cut (as PacketToCloud's cut_angle)
  std::uint64_t noise_seed = 1;         // seed of noise and dropouts
};

template <>
struct ParamFields<SimSensorParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("rpm", "rev/min", 300, 1200, "spin rate"), p.rpm);
    f(FieldInfo("height_m", "m", 0.3, 5, "sensor origin above the ground (KITTI: 1.73 m)"),
      p.height_m);
    f(FieldInfo("range_noise_m", "m", 0, 0.5, "std dev of the Gaussian range noise"),
      p.range_noise_m);
    f(FieldInfo("dropout_probability", "", 0, 1, "chance a surface return is lost"),
      p.dropout_probability);
    f(FieldInfo("min_range_m", "m", 0, 130,
                "returns nearer are sent as no return (keep inside the decoder's window)"),
      p.min_range_m);
    f(FieldInfo("max_range_m", "m", 0, 130,
                "returns farther are sent as no return (> min_range_m; inside the decoder's)"),
      p.max_range_m);
    f(FieldInfo("start_stamp_s", "s", 0, 1e10, "epoch stamp of drive time 0"), p.start_stamp_s);
    f(FieldInfo("cut_angle_deg", "deg", 0, 360,
                "revolution cut, as PacketToCloud's cut_angle (< 360)"),
      p.cut_angle_deg);
    f(FieldInfo("noise_seed", "", 0, 1e15, "seed of noise and dropouts"), p.noise_seed);
  }
};

/// Counters of one revolution.
struct SimStats {
  std::size_t rays = 0;             // lasers fired
  std::size_t returns = 0;          // returns emitted (= ground-truth length)
  std::size_t no_hit = 0;           // rays that hit nothing within max range
  std::size_t dropped = 0;          // hits lost by dropout
  std::size_t out_of_range = 0;     // hits outside [min_range_m, max_range_m] after noise
  std::size_t transmitted = 0;      // passes of a ray through a porous volume
  std::size_t foliage_returns = 0;  // rays stopped inside a porous volume
};

/// Output of one simulated revolution.
struct SimRevolution {
  std::uint64_t index = 0;    // 0, 1, ... since the start (or the last reset())
  double start_time_s = 0.0;  // [s] drive time of the revolution's first firing
  double stamp_s = 0.0;       // [s] epoch stamp of the first packet (scan header stamp)
  std::vector<RawPacket> packets;
  std::vector<double> packet_stamps_s;  // [s] epoch stamp of each packet's first firing
  /// Ground truth, one entry per decoded point, in decoder order (packet, block, laser).
  std::vector<std::uint32_t> instance_ids;  // 0 = background
  std::vector<std::uint8_t> classes;        // ObjectClass values
  /// True (noise-free) world hit point of each return [m], same order (tests, evaluation).
  std::vector<Eigen::Vector3f> world_points;
  SimStats stats;
};

/// Checks the parameters; throws std::invalid_argument naming the field and accepted range.
void validate(const SimSensorParams& sensor);

/// The simulator. Owns its scene; not copyable.
class LidarSimulator {
 public:
  /// Throws std::invalid_argument on invalid parameters.
  LidarSimulator(Scene scene, const SceneParams& scene_params, const DriveParams& drive,
                 const Calibration& calibration, const SimSensorParams& sensor);
  ~LidarSimulator();
  LidarSimulator(const LidarSimulator&) = delete;
  LidarSimulator& operator=(const LidarSimulator&) = delete;

  /// Simulates the next revolution of the continuous packet stream into `out` (its buffers
  /// are reused).
  void simulateNext(SimRevolution* out);
  /// Restarts the stream at drive time 0.
  void reset();
  /// True once the platform has reached the end of its path (the tools stop there).
  bool driveFinished() const;
  /// Number of whole revolutions the drive lasts (at least 1).
  std::size_t revolutionsInDrive() const;

  /// Pose of base_link (on the ground under the sensor, x forward) in the world at drive time t.
  Eigen::Isometry3d basePose(double t_s) const;
  /// Pose of the sensor (velodyne frame) relative to base_link.
  Eigen::Isometry3d baseToSensor() const;
  /// world_T_velodyne at drive time t.
  Eigen::Isometry3d sensorPose(double t_s) const { return basePose(t_s) * baseToSensor(); }

  /// Drive time [s] <-> epoch stamp [s].
  /// Whole microseconds, as a real driver stamps packets (and as PCL headers keep stamps), so
  /// scan, cloud and ground-truth stamps compare equal along the pipeline.
  double stampOf(double drive_time_s) const {
    return std::round((sensor_.start_stamp_s + drive_time_s) * 1e6) / 1e6;
  }

  const Scene& scene() const { return scene_; }
  const SimSensorParams& sensorParams() const { return sensor_; }
  const DriveParams& drive() const { return drive_; }
  const Calibration& calibration() const { return encoder_.calibration(); }
  double firingPeriod() const { return firing_period_s_; }
  /// True if rays are turned from the encoder's azimuth-0 rays (checked against
  /// PacketEncoder::ray at construction), false if every ray is asked from the encoder.
  bool fastRays() const { return fast_rays_; }

 private:
  std::uint16_t rawAzimuth(std::uint64_t firing) const;
  double firingTime(std::uint64_t firing) const;
  void simulatePacket(std::uint64_t packet, SimRevolution* out);
  /// Follows a ray that hit `*hit` through porous primitives (see the file comment); false
  /// when it leaves the range. `*inside`: the return lies inside a porous volume.
  bool throughFoliage(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_s,
                      std::uint64_t h, RayHit* hit, bool* inside, SimStats* stats);

  Scene scene_;
  SceneParams scene_params_;
  DriveParams drive_;
  SimSensorParams sensor_;
  PacketEncoder encoder_;
  std::unique_ptr<RayCaster> caster_;
  RevolutionCutter cutter_;
  double firing_period_s_ = 0.0;  // [s]
  double azimuth_step_ = 0.0;     // [1/100 deg] per firing
  std::uint64_t next_packet_ = 0;
  std::uint64_t next_revolution_ = 0;
  bool pending_start_ = false;            // next_packet_ was already seen by the cutter as a start
  std::vector<float> dist_correction_m_;  // per laser
  bool fast_rays_ = false;                // rays turned from the azimuth-0 ones (see ctor)
  std::vector<Eigen::Vector3d> base_origin_, base_dir_;  // per laser, azimuth 0, sensor frame
};

}  // namespace core
}  // namespace urban_detection
