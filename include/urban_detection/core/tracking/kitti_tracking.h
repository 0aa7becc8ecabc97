/// \file kitti_tracking.h
/// Readers of the KITTI tracking benchmark layout (ROS-free):
///   velodyne/<seq>/<frame>.bin   point clouds (read with kitti_io.h)
///   label_02/<seq>.txt           one object per line:
///       frame track_id type truncated occluded alpha left top right bottom h w l x y z
///       rotation_y [score]
///     (bbox in pixels of image 2; dimensions h w l and location x y z = bottom centre in
///     rectified camera 2 coordinates [m]; DontCare rows have track_id -1 and only a bbox)
///   calib/<seq>.txt              P2 and R_rect / Tr_velo_cam (the object benchmark's names
///                                R0_rect / Tr_velo_to_cam are accepted too)
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace urban_detection {
namespace core {

/// One line of label_02/<seq>.txt.
struct KittiTrackingLabel {
  int frame = 0;
  int track_id = -1;             ///< -1 for DontCare
  std::string type;              ///< Car, Van, Truck, Pedestrian, Person_sitting, Cyclist, Tram,
                                 ///< Misc, DontCare
  double truncated = 0.0;        ///< 0..2 (0 none, 1 partly, 2 largely)
  int occluded = 0;              ///< 0..3
  double alpha = 0.0;            ///< [rad]
  std::array<double, 4> bbox{};  ///< [px] left, top, right, bottom
  double height_m = 0.0, width_m = 0.0, length_m = 0.0;
  Eigen::Vector3d location = Eigen::Vector3d::Zero();  ///< [m] bottom centre, rectified camera
  double rotation_y = 0.0;                             ///< [rad]
  double score = 1.0;  ///< detector confidence when given (results files), else 1

  bool dontCare() const { return type == "DontCare"; }
};

/// Parses one line: false when it has fewer than 17 fields, a field is not a number, or a
/// number is not finite.
bool parseKittiTrackingLine(const std::string& line, KittiTrackingLabel* label);

/// Reads label_02/<seq>.txt into labels grouped by frame. Empty lines are skipped. Returns
/// false with `error` naming the file and line on a missing file or a malformed line.
bool readKittiTrackingLabels(const std::string& path,
                             std::map<int, std::vector<KittiTrackingLabel>>* by_frame,
                             std::string* error);

/// Calibration of one tracking sequence.
struct KittiTrackingCalibration {
  Eigen::Matrix<double, 3, 4> p2 = Eigen::Matrix<double, 3, 4>::Zero();
  Eigen::Matrix3d r_rect = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 3, 4> tr_velo_cam = Eigen::Matrix<double, 3, 4>::Zero();

  Eigen::Vector3d veloToRect(const Eigen::Vector3d& p_velo) const;
  Eigen::Vector3d rectToVelo(const Eigen::Vector3d& p_rect) const;
  /// Pixel of a LiDAR point in image 2; false when not in front of the camera.
  bool project(const Eigen::Vector3d& p_velo, double* u, double* v) const;
};

/// Reads calib/<seq>.txt; false with `error` set when P2, the rectification or the
/// LiDAR-to-camera transform is missing or malformed.
bool readKittiTrackingCalibration(const std::string& path, KittiTrackingCalibration* calib,
                                  std::string* error);

/// True when LiDAR point `p_velo` lies inside the label's 3-D box grown by `margin_m`.
bool insideKittiTrackingBox(const KittiTrackingLabel& label, const KittiTrackingCalibration& calib,
                            const Eigen::Vector3d& p_velo, double margin_m = 0.0);

/// Centre of the label's box in the LiDAR frame [m].
Eigen::Vector3d kittiTrackingBoxCenterVelo(const KittiTrackingLabel& label,
                                           const KittiTrackingCalibration& calib);

}  // namespace core
}  // namespace urban_detection
