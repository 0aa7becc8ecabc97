/// \file synthetic_scene.h
/// A small analytic scene for the decode benchmark: a closed street of 120 m x 24 m
/// (ground plane and four walls) with one car-sized box, scanned by the packet encoder at a
/// given spin rate. Every beam hits something within 70 m, so a revolution carries all
/// 384 returns per packet. Also: packets re-encoding a real KITTI scan. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace core {

struct SyntheticSceneParams {
  double sensor_height_m = 1.8;                                    // [m] above the ground
  double street_half_length_m = 60.0, street_half_width_m = 12.0;  // [m] walls
  double box_min[3] = {6.0, 2.0, -1.8};                            // [m] car-sized box
  double box_max[3] = {10.5, 3.8, -0.3};
  double rpm = 600.0;  // [1/min]
};

/// Distance along a ray to the first surface of the scene (infinity if none).
double castRay(const SyntheticSceneParams& s, const float o[3], const float d[3]);

/// Encodes `packets` consecutive packets of the scene starting at azimuth `start_deg`.
std::vector<RawPacket> scanScene(const PacketEncoder& encoder, const SyntheticSceneParams& s,
                                 int packets, double start_deg = 0.0);

/// Reads a KITTI velodyne .bin scan (float32 x, y, z, reflectance per point) into xyz triples;
/// empty if the file cannot be read.
std::vector<float> readKittiBinXyz(const std::string& path);

/// Packets of one revolution whose range pattern is taken from a real scan: each point goes to
/// the laser of nearest elevation (within 0.3 deg) and to the firing of its azimuth; slots that
/// receive no point stay "no return", as sky and dark surfaces do in a real recording.
std::vector<RawPacket> packetsFromScan(const PacketEncoder& encoder, const std::vector<float>& xyz,
                                       double rpm, int packets);

/// The calibration file `path`, else the SZTAKI one from $UD_SHARED_DATA or ../shared/data,
/// else the nominal geometry.
Calibration findCalibration(const std::string& path);

}  // namespace core
}  // namespace urban_detection
