/// \file image_label_transfer_ros.h
/// ROS glue of the image -> object label transfer: sensor_msgs/Image and CameraInfo
/// to OpenCV / core types, parameter loading, and writing the votes into DetectedObjectArray.
/// No ROS master needed except for loadImageLabelTransferParams().
#pragma once

#include <ros/node_handle.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/spark/spark_segmenter.h"

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

/// Copies `objects` into `out` and fills class_label / class_confidence of every object from
/// `votes` (matched by id): the class name (`names[id]`, or "class_<id>") when a class won,
/// "unknown" and 0 otherwise.
void applyVotes(const DetectedObjectArray& objects, const std::vector<core::ObjectClassVote>& votes,
                const std::vector<std::string>& names, DetectedObjectArray* out);

/// Writes the fused classes into `out` (a copy of `objects`): per object, `fused[k]` for
/// `objects.objects[k]`; objects the camera vetoed are left out of `out` (their points stay in
/// objects/points under their id). Category names as the LiDAR classifier's ("vehicle", ...).
/// Objects the camera did not see (camera_used false) keep their label and confidence verbatim.
void applyFusedClasses(const DetectedObjectArray& objects,
                       const std::vector<core::FusedClass>& fused, DetectedObjectArray* out);

/// The LiDAR class of a message object: its class_label parsed as an ObjectCategory
/// (kUnknown for "unknown" or any other name).
core::ObjectCategory lidarCategory(const DetectedObject& o);

/// Everything the ImageLabelTransfer nodelet reads from its private namespace
/// (config/image_label_transfer.yaml).
struct ImageLabelTransferRosParams {
  core::SegmentationModelParams model;      // model/*
  core::ImageLabelTransferParams transfer;  // transfer/* (kept_classes from keep_classes)
  core::CameraFusionParams fusion;          // fusion (mode) and fusion_rule/*
  std::string class_names_file;             // one class name per line; empty: "class_<id>"
  std::string model_dir;                    // relative model/config/names paths start here
  std::vector<std::string> keep_classes;    // names or ids that vote; empty: all
  /// model/{vehicle,pedestrian,cyclist,other_object,background}_classes: camera classes of each
  /// object category (fusion and the veto); background = road, building, vegetation, ...
  std::vector<std::string> vehicle_classes, pedestrian_classes, cyclist_classes,
      other_object_classes, background_classes;
  int inference_nice = 19;            // [-] nice of the inference thread (0..19)
  int inference_threads = 1;          // [-] OpenCV threads (process-wide); 0 = OpenCV's
  double max_mask_gap_s = 0.15;       // [s] newest mask within this of the cloud stamp
  int queue_size = 5;                 // [-] per input and for the synchroniser
  double max_sync_interval_s = 0.06;  // [s] objects vs. objects/points stamps
  std::string fixed_frame;            // [-] non-empty: tf between the image and cloud
                                      // stamps through this frame (moving platform)
  double tf_timeout_s = 0.0;          // [s] wait for the camera <- LiDAR transform (0:
                                      // use what tf has; the LiDAR side never waits)
};

/// Loads the parameters from `pnh` (model/*, transfer/*); throws ParamError naming the
/// parameter and its accepted range. The model and class names files are read by the caller.
void loadImageLabelTransferParams(const ros::NodeHandle& pnh, ImageLabelTransferRosParams* p);

}  // namespace ros_conv
}  // namespace urban_detection
