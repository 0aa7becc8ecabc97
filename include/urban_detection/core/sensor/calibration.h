/// \file calibration.h
/// Per-laser calibration of a Velodyne HDL-64E (S2, S2.1, S3), ROS-free.
///
/// Readers for velodyne_pointcloud's YAML format and Velodyne's own db.xml, plus a built-in
/// nominal HDL-64E S2 geometry derived from the datasheet for running without a file.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace urban_detection {
namespace core {

/// Number of lasers of an HDL-64E.
constexpr int kNumLasers = 64;

/// Correction parameters of one laser, as stored in the calibration file, plus derived
/// trigonometric values filled in by Calibration::finalize().
struct LaserCorrection {
  int laser_id = 0;
  double rot_correction_rad = 0.0;         // [rad] azimuth offset of the laser
  double vert_correction_rad = 0.0;        // [rad] elevation angle of the laser
  double dist_correction_m = 0.0;          // [m] range offset (far field)
  double dist_correction_x_m = 0.0;        // [m] range offset at 2.4 m along x (two-point)
  double dist_correction_y_m = 0.0;        // [m] range offset at 1.93 m along y (two-point)
  double vert_offset_correction_m = 0.0;   // [m] vertical offset of the laser origin
  double horiz_offset_correction_m = 0.0;  // [m] horizontal offset of the laser origin
  double focal_distance = 0.0;             // [m] intensity focal distance (db.xml: cm)
  double focal_slope = 0.0;                // [-] intensity focal slope
  int min_intensity = 0;                   // [0..255]
  int max_intensity = 255;                 // [0..255]
  bool two_pt_correction_available = false;

  // Derived (finalize()).
  double cos_rot = 1.0, sin_rot = 0.0, cos_vert = 1.0, sin_vert = 0.0;
};

/// Raised by the calibration readers. The message names the file, the laser (when one is
/// concerned) and the field that is missing or malformed.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Geometry of the whole sensor.
struct Calibration {
  double distance_resolution_m = 0.002;  // [m] size of one raw distance unit
  std::vector<LaserCorrection> lasers;   // indexed by laser id, kNumLasers entries
  /// ring_of_laser[laser_id] = rank of the laser by vertical angle (0 = lowest beam).
  std::vector<int> ring_of_laser;
  std::string source;  // file it was read from, or "nominal HDL-64E S2"

  /// Checks consistency (64 lasers, ids 0..63 once each, finite values, angles in range)
  /// and computes derived values and ring_of_laser. Throws CalibrationError.
  void finalize();

  /// Built-in nominal HDL-64E S2 geometry (datasheet vertical angles +2 deg to -24.8 deg,
  /// no per-laser offsets).
  static Calibration nominalHdl64eS2();
};

/// Reads velodyne_pointcloud's YAML calibration. Throws CalibrationError.
Calibration loadCalibrationYaml(const std::string& path);
/// Reads Velodyne's db.xml calibration. Throws CalibrationError.
Calibration loadCalibrationDbXml(const std::string& path);
/// Chooses the reader by extension (.yaml/.yml or .xml); an empty path gives the nominal
/// geometry. Throws CalibrationError.
Calibration loadCalibration(const std::string& path);

}  // namespace core
}  // namespace urban_detection
