/// \file eval_datasets.h
/// Readers that turn public LiDAR datasets into (cloud, per-point ground truth) frames for the
/// detection scoring of evaluation.h (paper Sec. 5). ROS-free.
///
/// Ground-truth rules (they are what makes the F-rate honest; docs/measurements.md repeats them):
/// - KITTI object: a GT object is the set of points inside a labelled 3-D box (every class but
///   DontCare) enlarged by `box_margin_m` on each side; points in the bottom `ground_band_m` of
///   the box (the road under the object) are excluded from both point sets. KITTI labels only
///   the front camera's view, so points that project outside the image of camera 2 (or lie
///   behind it) and points that project into a DontCare rectangle are don't-care: a detection
///   made mostly of them is ignored. GT objects with fewer than `min_points` points are ignored.
/// - SemanticKITTI: GT objects are the instance ids of the thing classes (vehicles, persons,
///   riders, moving classes). Pole, trunk, traffic-sign, other-object, unlabelled and outlier
///   points, and thing points without an instance id, are don't-care (real objects without an
///   instance label). Everything else (building, fence, other-structure, vegetation, ground
///   classes) is scored background: a detection made mostly of it is false.
/// - Simulated drives (urban_detection_simulate: a pcap plus its ground-truth file): exact
///   per-point instances. GT objects are the instances of the street-object classes
///   (isStreetObject: cars, vans, pedestrians, cyclists, bins, benches). Ground, terrain (grass
///   verges, gardens), walls and vegetation (tree crowns, hedges, bushes) are scored
///   background, as in the SemanticKITTI rule: a detection made mostly of them is false, as it
///   is for a user. Trunks, poles and signs are don't-care: real objects, but not targets of
///   the detector (as SemanticKITTI's trunk, pole and traffic-sign). GT objects with fewer
///   than `min_points` points are ignored.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/core/simulation/ground_truth.h"

namespace urban_detection {
namespace core {

/// Files of `dir` whose name ends with `suffix`, sorted by name (empty if `dir` is missing).
/// Point clouds and SemanticKITTI labels are read with kitti_io.h.
std::vector<std::string> listFiles(const std::string& dir, const std::string& suffix);

/// The SemanticKITTI sequence folders `dir` names: `dir` itself when it holds `velodyne/`, else
/// every `dir/sequences/NN` that does, sorted.
std::vector<std::string> semanticKittiSequences(const std::string& dir);

// ------------------------------------------------------------------------------------------
// KITTI object benchmark

/// The calibration of one KITTI object frame (calib/*.txt).
struct KittiCalibration {
  Eigen::Matrix<double, 3, 4> p2 = Eigen::Matrix<double, 3, 4>::Zero();  ///< camera 2 projection
  Eigen::Matrix3d r0_rect = Eigen::Matrix3d::Identity();                 ///< rectifying rotation
  Eigen::Matrix<double, 3, 4> tr_velo_to_cam = Eigen::Matrix<double, 3, 4>::Zero();  ///< [m]

  /// LiDAR point -> rectified camera coordinates (x right, y down, z forward) [m].
  Eigen::Vector3d veloToRect(const Eigen::Vector3d& p_velo) const;
  /// Inverse of veloToRect.
  Eigen::Vector3d rectToVelo(const Eigen::Vector3d& p_rect) const;
  /// Projects a LiDAR point into image 2; returns false when it is not in front of the camera
  /// (depth <= min_depth_m). `u`, `v` in pixels.
  bool project(const Eigen::Vector3d& p_velo, double* u, double* v, double min_depth_m = 0.1) const;
};

/// Parses calib/*.txt (needs P2, R0_rect, Tr_velo_to_cam). Returns false with `error` set.
bool readKittiCalibration(const std::string& path, KittiCalibration* calib, std::string* error);

/// One line of label_2/*.txt.
struct KittiLabel {
  std::string type;              ///< Car, Van, Truck, Pedestrian, Person_sitting, Cyclist, Tram,
                                 ///< Misc or DontCare
  double truncated = 0.0;        ///< [0..1]
  int occluded = 0;              ///< 0..3
  double alpha = 0.0;            ///< [rad] observation angle
  std::array<double, 4> bbox{};  ///< [px] left, top, right, bottom in image 2
  double height_m = 0.0, width_m = 0.0, length_m = 0.0;  ///< [m] box dimensions
  Eigen::Vector3d location = Eigen::Vector3d::Zero();    ///< [m] bottom centre, rectified camera
  double rotation_y = 0.0;                               ///< [rad] yaw about the camera y axis
};

/// Parses one label line; returns false if it has fewer than 15 fields or non-numbers.
bool parseKittiLabelLine(const std::string& line, KittiLabel* label);
/// Reads label_2/*.txt; returns false with `error` set on a missing file or a bad line.
bool readKittiLabels(const std::string& path, std::vector<KittiLabel>* labels, std::string* error);

/// Coordinates of a rectified-camera point in the frame of a label's box: x along the length,
/// y up from the bottom face, z along the width; the box is |x| <= l/2, 0 <= y <= h,
/// |z| <= w/2.
Eigen::Vector3d kittiBoxLocal(const KittiLabel& label, const Eigen::Vector3d& p_rect);
/// The 8 corners of a label's box in the LiDAR frame [m]: bottom face first (in the order
/// (+l,+w), (+l,-w), (-l,-w), (-l,+w) of the box frame above), then the top face likewise.
std::array<Eigen::Vector3d, 8> kittiBoxCornersVelo(const KittiLabel& label,
                                                   const KittiCalibration& calib);

/// Ground-truth construction parameters for KITTI object frames.
struct KittiGroundTruthParams {
  double box_margin_m = 0.1;    ///< [m] boxes are enlarged by this on each side
  double ground_band_m = 0.2;   ///< [m] points this close to the box bottom are excluded
  int image_width_px = 1242;    ///< used when the frame has no image_2/*.png
  int image_height_px = 375;    ///< used when the frame has no image_2/*.png
  std::size_t min_points = 10;  ///< GT objects with fewer scored points are ignored
};

/// True when a LiDAR point projects into the `width` x `height` image 2 and lies in front of
/// the camera.
bool inKittiCameraFrustum(const KittiCalibration& calib, const Eigen::Vector3d& p_velo,
                          int width_px, int height_px);

/// Builds the ground truth of one KITTI object frame (rules in the file comment).
void buildKittiGroundTruth(const CloudXYZIRT& cloud, const std::vector<KittiLabel>& labels,
                           const KittiCalibration& calib, const KittiGroundTruthParams& params,
                           int width_px, int height_px, EvalFrame* gt);

/// Width and height of a PNG file from its header; false if it is not a readable PNG.
bool readPngSize(const std::string& path, int* width_px, int* height_px);

// ------------------------------------------------------------------------------------------
// SemanticKITTI

/// world_T_lidar of every scan of a SemanticKITTI / KITTI odometry sequence folder, indexed by
/// scan number: poses.txt holds the left camera's pose per scan in the first scan's camera
/// frame, calib.txt its `Tr` (camera <- LiDAR); the LiDAR pose is Tr^-1 * pose * Tr, so the
/// world frame is the first scan's LiDAR frame (x forward, z up) [m]. Without a Tr line the
/// nominal KITTI axes are used (camera x = -LiDAR y, y = -LiDAR z, z = LiDAR x) and
/// `nominal_tr` is set. False with `error` set when poses.txt is missing or malformed.
bool readSemanticKittiPoses(const std::string& seq_dir, std::vector<Eigen::Isometry3d>* poses,
                            bool* nominal_tr, std::string* error);

/// Semantic class of a SemanticKITTI label (low 16 bits).
inline std::uint16_t semanticKittiClass(std::uint32_t label) {
  return static_cast<std::uint16_t>(label & 0xFFFFu);
}
/// Instance id of a SemanticKITTI label (high 16 bits; 0 = none).
inline std::uint16_t semanticKittiInstance(std::uint32_t label) {
  return static_cast<std::uint16_t>(label >> 16);
}

/// Scoring category of a SemanticKITTI class.
enum class SemanticKittiCategory : std::uint8_t {
  kThing = 0,       ///< vehicles, persons, riders (static and moving): GT objects by instance
  kDontCare = 1,    ///< pole, trunk, traffic-sign, other-object, unlabelled, outlier
  kBackground = 2,  ///< building, fence, structures, vegetation, ground classes, others
};
SemanticKittiCategory semanticKittiCategory(std::uint16_t semantic_class);
/// Name of a class ("car", "person", ...; "class_<n>" when unknown).
std::string semanticKittiClassName(std::uint16_t semantic_class);

/// Ground-truth construction parameters for SemanticKITTI.
struct SemanticKittiGroundTruthParams {
  std::size_t min_points = 10;  ///< GT objects with fewer points are ignored
};

/// Builds the ground truth of one SemanticKITTI scan from its per-point labels.
void buildSemanticKittiGroundTruth(const std::vector<std::uint32_t>& labels,
                                   const SemanticKittiGroundTruthParams& params, EvalFrame* gt);

// ------------------------------------------------------------------------------------------
// Simulated drives

/// Ground-truth construction parameters for simulated drives.
struct SimulatedGroundTruthParams {
  std::size_t min_points = 10;  ///< GT objects with fewer points are ignored
};

/// Builds the ground truth of one simulated revolution from its per-point labels (rules in the
/// file comment). `frame.instance_ids[i]` labels point i of the decoded revolution.
void buildSimulatedGroundTruth(const GroundTruthFrame& frame,
                               const SimulatedGroundTruthParams& params, EvalFrame* gt);

/// Replays a simulated drive for evaluation: reads the packets of a pcap, cuts them into
/// revolutions at `cut_angle_deg` (PcapRevolutionReader, as PacketSource does), decodes them with
/// the calibration the drive was simulated with, and pairs each revolution with the
/// ground-truth frame of the same stamp (findGroundTruthFrame; the stamp of a revolution is
/// the capture time of its first packet). Both files are streamed: memory does not grow with
/// the drive's length.
class SimulatedDriveReader {
 public:
  /// Throws std::runtime_error (naming the file) when either file cannot be opened.
  SimulatedDriveReader(const std::string& pcap_path, const std::string& gt_path,
                       const Calibration& calibration, double cut_angle_deg = 0.0,
                       const DecoderParams& decoder_params = DecoderParams());

  enum class Result {
    kFrame,    ///< `cloud` and `gt` hold one revolution and its ground truth
    kSkipped,  ///< a revolution without a usable GT frame (no frame of its stamp, e.g. a
               ///< partial first revolution, or a point count that differs); `message` says
               ///< why, `cloud` holds the revolution
    kEnd,      ///< no more revolutions; a truncated pcap or GT file ends the drive early and
               ///< sets `message`
  };
  Result next(CloudXYZIRT* cloud, GroundTruthFrame* gt, std::string* message);

  std::size_t revolutions() const { return pcap_.revolutions(); }  ///< revolutions cut so far
  /// Packets refused (invalid: skipped when the revolutions are cut, or rejected by the decoder).
  std::size_t badPackets() const { return bad_packets_ + pcap_.boundary().invalidPackets(); }

 private:
  bool fillWindow(double stamp_s);

  PcapRevolutionReader pcap_;
  GroundTruthReader gt_reader_;
  PacketDecoder decoder_;
  std::vector<PcapPacket> packets_;  // the current revolution's (reused)
  bool gt_end_ = false;
  std::string end_message_;
  std::vector<GroundTruthFrame> window_;  // GT frames read ahead, sorted by stamp
  std::size_t bad_packets_ = 0;
};

}  // namespace core
}  // namespace urban_detection
