#include "urban_detection/ros/image_label_transfer_ros.h"
#include "urban_detection/ros/param_loading.h"

#include <tf2_eigen/tf2_eigen.h>
#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace urban_detection {
namespace ros_conv {

bool imageToBgr(const sensor_msgs::Image& msg, cv::Mat* scratch, cv::Mat* bgr, std::string* error) {
  int channels = 0;
  int code = -1;  // cvtColor code, -1 = wrap as is
  if (msg.encoding == "bgr8") {
    channels = 3;
  } else if (msg.encoding == "mono8") {
    channels = 1;
  } else if (msg.encoding == "rgb8") {
    channels = 3;
    code = cv::COLOR_RGB2BGR;
  } else if (msg.encoding == "rgba8") {
    channels = 4;
    code = cv::COLOR_RGBA2BGR;
  } else if (msg.encoding == "bgra8") {
    channels = 4;
    code = cv::COLOR_BGRA2BGR;
  } else {
    *error = "unsupported image encoding '" + msg.encoding +
             "' (accepted: bgr8, rgb8, bgra8, rgba8, mono8)";
    return false;
  }
  const std::size_t row_bytes = static_cast<std::size_t>(msg.width) * channels;
  if (msg.width == 0 || msg.height == 0 || msg.width > 16384 || msg.height > 16384 ||
      msg.step < row_bytes || msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height) {
    *error = "image " + std::to_string(msg.width) + "x" + std::to_string(msg.height) + " step " +
             std::to_string(msg.step) + " does not match its " + std::to_string(msg.data.size()) +
             " data bytes";
    return false;
  }
  const cv::Mat view(static_cast<int>(msg.height), static_cast<int>(msg.width), CV_8UC(channels),
                     const_cast<std::uint8_t*>(msg.data.data()), msg.step);
  if (code < 0) {
    *bgr = view;
  } else {
    cv::cvtColor(view, *scratch, code);
    *bgr = *scratch;
  }
  return true;
}

bool cameraFromInfo(const sensor_msgs::CameraInfo& info, core::PinholeCamera* camera,
                    std::string* error) {
  camera->width_px = static_cast<int>(info.width);
  camera->height_px = static_cast<int>(info.height);
  const bool has_p = std::any_of(info.P.begin(), info.P.end(), [](double v) { return v != 0.0; });
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      camera->projection(r, c) = has_p ? info.P[r * 4 + c] : (c < 3 ? info.K[r * 3 + c] : 0.0);
    }
  }
  if (!camera->valid()) {
    *error = "CameraInfo (" + std::to_string(info.width) + "x" + std::to_string(info.height) +
             ") has no usable P or K (zero size, non-finite or non-positive focal length)";
    return false;
  }
  return true;
}

bool lookupCameraFromCloud(const tf2_ros::Buffer& tf, const std_msgs::Header& image,
                           const std_msgs::Header& cloud, const std::string& fixed_frame,
                           double timeout_s, Eigen::Isometry3d* camera_from_cloud,
                           std::string* error) {
  try {
    const ros::Duration timeout(timeout_s);
    const geometry_msgs::TransformStamped t =
        fixed_frame.empty()
            ? tf.lookupTransform(image.frame_id, cloud.frame_id, image.stamp, timeout)
            : tf.lookupTransform(image.frame_id, image.stamp, cloud.frame_id, cloud.stamp,
                                 fixed_frame, timeout);
    *camera_from_cloud = tf2::transformToEigen(t);
  } catch (const tf2::TransformException& e) {
    *error = std::string("no transform camera <- LiDAR: ") + e.what();
    return false;
  }
  return true;
}

void toClassLabels(const DetectedObjectArray& objects,
                   std::vector<core::ObjectClassLabel>* labels) {
  labels->resize(objects.objects.size());
  for (std::size_t k = 0; k < labels->size(); ++k) {
    const DetectedObject& o = objects.objects[k];
    (*labels)[k] = {o.id, o.class_label, o.class_confidence, false};
  }
}

void applyClassLabels(const DetectedObjectArray& objects,
                      const std::vector<core::ObjectClassLabel>& labels, DetectedObjectArray* out) {
  out->header = objects.header;
  out->detector = objects.detector;
  out->objects.clear();
  out->objects.reserve(objects.objects.size());
  for (std::size_t k = 0; k < objects.objects.size(); ++k) {
    if (k < labels.size() && labels[k].vetoed) continue;
    out->objects.push_back(objects.objects[k]);
    if (k >= labels.size()) continue;
    out->objects.back().class_label = labels[k].class_label;
    out->objects.back().class_confidence = labels[k].class_confidence;
  }
}

void CameraMasks::setInfo(const sensor_msgs::CameraInfo::ConstPtr& info) {
  std::lock_guard<std::mutex> lock(info_mutex_);
  info_ = info;
}

bool CameraMasks::segment(const sensor_msgs::Image& image, std::string* error,
                          std::string* warning) {
  warning->clear();
  sensor_msgs::CameraInfo::ConstPtr info;
  {
    std::lock_guard<std::mutex> lock(info_mutex_);
    info = info_;
  }
  if (!info) {
    *error = kNoCameraInfo;
    return false;
  }
  auto mask = std::make_shared<Mask>();
  mask->header = image.header;
  try {
    if (!imageToBgr(image, &scratch_, &bgr_, error) ||
        !cameraFromInfo(*info, &mask->camera, error) || !network_->run(bgr_, &scores_, error))
      return false;
  } catch (const std::exception& e) {  // OpenCV
    *error = e.what();
    return false;
  }
  if (mask->camera.width_px != bgr_.cols || mask->camera.height_px != bgr_.rows) {
    *warning = "camera_info is " + std::to_string(mask->camera.width_px) + "x" +
               std::to_string(mask->camera.height_px) + " but the image " +
               std::to_string(bgr_.cols) + "x" + std::to_string(bgr_.rows) +
               "; projecting with camera_info's size";
  }
  scores_.reduceTo(&mask->scores);
  history_.push(image.header.stamp.toSec(), std::move(mask));
  return true;
}

void loadCameraStage(const ros::NodeHandle& pnh, core::CameraStageParams* params,
                     core::CameraModel* model) {
  loadFields(pnh, params);
  std::string error;
  if (!core::loadCameraModel(params->model, params->fusion.mode != core::FusionMode::kLidar, model,
                             &error))
    throw ParamError("in " + pnh.getNamespace() + ": " + error);
  params->transfer.kept_classes = model->kept_classes;
}

ObjectLabelling::ObjectLabelling(const core::CameraStageParams& params,
                                 const core::CameraModel& model, const CameraMasks& masks,
                                 const tf2_ros::Buffer& tf)
    : params_(params),
      labeller_(params.fusion, params.transfer, model.names, model.class_map),
      masks_(masks),
      tf_(tf) {}

bool ObjectLabelling::label(const DetectedObjectArray& objects, const LabeledCloud& points,
                            DetectedObjectArray* out, std::string* why_not) {
  why_not->clear();
  std::shared_ptr<const CameraMasks::Mask> mask;
  if (params_.fusion.mode != core::FusionMode::kLidar)
    mask = masks_.newestWithin(objects.header.stamp, params_.max_mask_gap_s);
  Eigen::Isometry3d camera_from_lidar;
  if (mask && !lookupCameraFromCloud(tf_, mask->header, objects.header, params_.fixed_frame,
                                     params_.tf_timeout_s, &camera_from_lidar, why_not))
    mask.reset();
  if (!mask) {
    *out = objects;  // LiDAR classes, unchanged
    return false;
  }
  toClassLabels(objects, &labels_);
  labeller_.label(points, camera_from_lidar, mask->camera, mask->scores, &labels_);
  applyClassLabels(objects, labels_, out);
  return true;
}

}  // namespace ros_conv
}  // namespace urban_detection
