/// \file image_label_transfer_ros.h
/// ROS glue of the image -> object label transfer (core/spark/camera_labeller.h):
/// sensor_msgs/Image and CameraInfo to OpenCV / core types, the camera <- LiDAR transform, and
/// the objects' classes to and from DetectedObjectArray, the segmented images waiting for the
/// objects (CameraMasks), and the objects' labelling from them (ObjectLabelling). No ROS master
/// needed.
#pragma once

#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>

#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/core/spark/camera_labeller.h"
#include "urban_detection/core/spark/camera_model.h"
#include "urban_detection/core/spark/mask_history.h"

namespace urban_detection {
namespace ros_conv {

/// Views an 8-bit image message as a BGR (or grey) cv::Mat: bgr8 and mono8 are wrapped without
/// copying (valid while `msg` lives), rgb8, rgba8 and bgra8 are converted into `scratch`.
/// Returns false with `error` for other encodings or a step/size mismatch (truncated data).
bool imageToBgr(const sensor_msgs::Image& msg, cv::Mat* scratch, cv::Mat* bgr, std::string* error);

/// The pinhole model of a rectified image: CameraInfo.P, or K (with a zero fourth column) when
/// P is all zero. Returns false with `error` for a zero size or an unusable matrix.
bool cameraFromInfo(const sensor_msgs::CameraInfo& info, core::PinholeCamera* camera,
                    std::string* error);

/// The transform of cloud-frame points into the camera's optical frame: at the image stamp, or,
/// with a `fixed_frame` (moving platform), from the cloud stamp to the image stamp through it.
/// Waits up to `timeout_s`; false with `error` when tf has no answer.
bool lookupCameraFromCloud(const tf2_ros::Buffer& tf, const std_msgs::Header& image,
                           const std_msgs::Header& cloud, const std::string& fixed_frame,
                           double timeout_s, Eigen::Isometry3d* camera_from_cloud,
                           std::string* error);

/// The camera stage's view of `objects` (core/spark/camera_labeller.h): id, class label and
/// confidence of each, in order.
void toClassLabels(const DetectedObjectArray& objects, std::vector<core::ObjectClassLabel>* labels);

/// `objects` with the classes the camera stage gave them (`labels[k]` for `objects.objects[k]`);
/// vetoed objects are left out of `out` (their points stay in objects/points under their id).
void applyClassLabels(const DetectedObjectArray& objects,
                      const std::vector<core::ObjectClassLabel>& labels, DetectedObjectArray* out);

/// The camera half of the ImageLabelTransfer stage: the newest camera_info, each image through
/// the network into an owned mask (it outlives the network's next run), and the last few masks
/// for the objects to pick from. segment() runs on the stage's inference thread, the rest on
/// any thread.
class CameraMasks {
 public:
  struct Mask {
    std_msgs::Header header;  // the image's
    core::PinholeCamera camera;
    core::SegmentationScores scores;
  };
  /// segment()'s error before the first camera_info (a warning, not a fault).
  static constexpr const char* kNoCameraInfo = "no camera_info yet";
  /// `network` (loaded) is used by segment() only.
  explicit CameraMasks(core::SegmentationModel* network) : network_(network) {}

  void setInfo(const sensor_msgs::CameraInfo::ConstPtr& info);
  /// Segments `image` with the newest camera_info into a new mask. False with `error` when the
  /// image is skipped (no camera_info yet, bad encoding or camera_info, network failure);
  /// `warning` is set when camera_info's size differs from the image's (projected with
  /// camera_info's).
  bool segment(const sensor_msgs::Image& image, std::string* error, std::string* warning);
  /// The newest mask whose image stamp is within `max_gap_s` of `stamp` (null if none).
  std::shared_ptr<const Mask> newestWithin(const ros::Time& stamp, double max_gap_s) const {
    return history_.newestWithin(stamp.toSec(), max_gap_s);
  }

 private:
  core::SegmentationModel* network_;
  std::mutex info_mutex_;
  sensor_msgs::CameraInfo::ConstPtr info_;
  cv::Mat scratch_, bgr_;
  core::SegmentationScores scores_;
  core::MaskHistory<Mask> history_{4};
};

/// Reads the camera stage's parameters under `pnh` (config/image_label_transfer.yaml) and loads
/// its model (the network unless `fusion` is lidar); throws ParamError naming the parameter at
/// fault. The one ROS path to core::loadCameraModel().
void loadCameraStage(const ros::NodeHandle& pnh, core::CameraStageParams* params,
                     core::CameraModel* model);

/// The objects half of the stage: a revolution's objects take the newest mask within
/// `max_mask_gap_s` of their stamp, projected with tf (camera <- LiDAR) and labelled by
/// core::CameraLabeller under the fusion mode; without a mask or a transform (or in lidar mode)
/// they keep their LiDAR classes.
class ObjectLabelling {
 public:
  /// `model` (its names, class map and kept classes), `masks` and `tf` must outlive this.
  ObjectLabelling(const core::CameraStageParams& params, const core::CameraModel& model,
                  const CameraMasks& masks, const tf2_ros::Buffer& tf);
  /// objects/classified of `objects` and their points (label = object id). Returns whether a
  /// mask was used; `why_not` says why a mask found was not (no camera <- LiDAR transform).
  bool label(const DetectedObjectArray& objects, const LabeledCloud& points,
             DetectedObjectArray* out, std::string* why_not);

 private:
  core::CameraStageParams params_;
  core::CameraLabeller labeller_;
  const CameraMasks& masks_;
  const tf2_ros::Buffer& tf_;
  std::vector<core::ObjectClassLabel> labels_;
};

}  // namespace ros_conv
}  // namespace urban_detection
