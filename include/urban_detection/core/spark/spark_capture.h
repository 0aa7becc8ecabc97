/// \file spark_capture.h
/// Image retrieval of the SPARK workflow (second seed paper, Sec. 3.2 and 3.4): an orthographic
/// virtual camera moved along a polyline captures images of a (accumulated) point cloud at a
/// fixed interval, several rotations per capture point. Points are drawn as square splats into
/// a z-buffer, which also remembers the point each pixel shows, so casting a mask pixel back
/// into the cloud ("the first point hit along the view ray") is a look-up. ROS-free.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Capture path and image parameters, read from a JSON file (see readCapturePathJson()).
struct CapturePathParams {
  std::vector<Eigen::Vector3d> path;  ///< [m] polyline of camera positions in the cloud frame
  double interval_m = 5.0;            ///< [m] distance between capture points along the path
  int rotations = 4;                  ///< captures per point, yaw evenly spaced over 360 deg,
                                      ///< the first one along the path direction
  double pitch_deg = -30.0;           ///< [deg] camera pitch, negative looks down, -90 = nadir
  int image_width_px = 640;           ///< [px]
  int image_height_px = 480;          ///< [px]
  double metres_per_pixel = 0.05;     ///< [m/px] orthographic pixel size
  double max_depth_m = 80.0;          ///< [m] points farther along the view ray are not drawn
  int splat_radius_px = 1;            ///< [px] a point covers a (2r+1)^2 square
  std::string colour = "rgb";         ///< point colours: "rgb", "intensity" or "height"
  double height_min_m = -2.0;         ///< [m] z mapped to the first colour of "height"
  double height_max_m = 4.0;          ///< [m] z mapped to the last colour of "height"
};

/// CapturePathParams' field table (core/common/param_fields.h): the keys of the capture path JSON
/// file besides "path" (readCapturePathJson() reads exactly these).
template <>
struct ParamFields<CapturePathParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"interval_m", "m", 0.01, 1e5, "distance between capture points along the path"},
      p.interval_m);
    f({"rotations", "", 1, 360, "captures per point, yaw evenly spaced over 360 deg"}, p.rotations);
    f({"pitch_deg", "deg", -90, 90, "camera pitch, negative looks down, -90 = nadir"}, p.pitch_deg);
    f({"image_width_px", "px", 8, 8192, "image width"}, p.image_width_px);
    f({"image_height_px", "px", 8, 8192, "image height"}, p.image_height_px);
    f({"metres_per_pixel", "m/px", 1e-4, 100, "orthographic pixel size"}, p.metres_per_pixel);
    f({"max_depth_m", "m", 1e-3, 1e5, "points farther along the view ray are not drawn"},
      p.max_depth_m);
    f({"splat_radius_px", "px", 0, 16, "a point covers a (2r+1)^2 square"}, p.splat_radius_px);
    f({"colour", "point colours: rgb, intensity or height"}, p.colour);
    f({"height_min_m", "m", -1e4, 1e4, "z mapped to the first colour of height"}, p.height_min_m);
    f({"height_max_m", "m", -1e4, 1e4, "z mapped to the last colour of height"}, p.height_max_m);
  }
};

/// Reads a capture path JSON file:
/// `{"path": [[x, y, z], ...], "interval_m": 5, "rotations": 4, "pitch_deg": -30,
///   "image_width_px": 640, "image_height_px": 480, "metres_per_pixel": 0.05,
///   "max_depth_m": 80, "splat_radius_px": 1, "colour": "rgb"}` (all but "path" optional).
/// Returns false with `error` for a missing file, a path of fewer than one point, unknown keys
/// or out-of-range values.
bool readCapturePathJson(const std::string& path, CapturePathParams* params, std::string* error);
/// Checks `params`: the path, the table's ranges, the colour mode and height_min_m <
/// height_max_m; false with `error` naming the field (and the accepted range).
bool validateCapturePath(const CapturePathParams& params, std::string* error);

/// Pose and projection of one orthographic capture. Camera axes in the cloud frame: `right`
/// (image x), `down` (image y) and `forward` (view direction); the image centre looks at
/// `position`.
struct OrthoCamera {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< [m]
  double yaw_deg = 0.0;    ///< [deg] heading of the view direction about z (0 = +x)
  double pitch_deg = 0.0;  ///< [deg]
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< rows: right, down, forward
  int width_px = 0, height_px = 0;                         ///< [px]
  double metres_per_pixel = 0.05;                          ///< [m/px]
  double max_depth_m = 80.0;                               ///< [m]

  /// Builds the rotation from yaw and pitch.
  static OrthoCamera make(const Eigen::Vector3d& position, double yaw_deg, double pitch_deg,
                          int width_px, int height_px, double metres_per_pixel, double max_depth_m);
  /// Image coordinates (continuous, pixel centres at +0.5) and depth along the view ray [m].
  void project(const Eigen::Vector3d& p, double* x_px, double* y_px, double* depth_m) const;
  /// The point on the view ray of pixel centre (x, y) at `depth_m` (inverse of project()).
  Eigen::Vector3d unproject(double x_px, double y_px, double depth_m) const;
};

/// All captures of a path: capture points every interval_m along the polyline (the first at its
/// start; a one-point path gives one capture point looking along +x), `rotations` yaws each.
std::vector<OrthoCamera> capturePoses(const CapturePathParams& params);

/// Per-point 8-bit BGR colours for rendering: "rgb" uses `rgb` (one per point, e.g. from a
/// PCD's rgb field; missing -> grey), "intensity" maps 0..255 to grey, "height" maps z through
/// OpenCV's JET colour map between height_min_m and height_max_m.
void pointColours(const CloudXYZIRT& cloud, const std::vector<cv::Vec3b>& rgb,
                  const CapturePathParams& params, std::vector<cv::Vec3b>* colours);

/// Z-buffer renderer of point splats.
class OrthoRenderer {
 public:
  /// Renders `cloud` seen by `camera`: `image` (CV_8UC3 BGR, black background) and the
  /// internal z-buffer (nearest depth and point index per pixel). Non-finite points are
  /// skipped. Returns the number of points drawn.
  std::size_t render(const CloudXYZIRT& cloud, const std::vector<cv::Vec3b>& colours,
                     const OrthoCamera& camera, int splat_radius_px, cv::Mat* image);
  /// Index of the first point hit by the view ray of pixel (x, y) of the last render, or -1.
  std::int32_t hit(int x, int y) const { return index_[static_cast<std::size_t>(y) * width_ + x]; }
  /// [m] depth of that hit (infinity when none).
  float depth(int x, int y) const { return depth_[static_cast<std::size_t>(y) * width_ + x]; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_ = 0, height_ = 0;
  std::vector<float> depth_;
  std::vector<std::int32_t> index_;
};

}  // namespace core
}  // namespace urban_detection
