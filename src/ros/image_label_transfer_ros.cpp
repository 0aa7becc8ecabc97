#include "urban_detection/ros/image_label_transfer_ros.h"

#include <tf2_eigen/tf2_eigen.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "urban_detection/ros/object_conversions.h"
#include "urban_detection/ros/param_loading.h"

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

void applyVotes(const DetectedObjectArray& objects, const std::vector<core::ObjectClassVote>& votes,
                const std::vector<std::string>& names, DetectedObjectArray* out) {
  *out = objects;
  for (DetectedObject& o : out->objects) {
    o.class_label = kUnknownClass;
    o.class_confidence = 0.0f;
    const auto it = std::lower_bound(
        votes.begin(), votes.end(), o.id,
        [](const core::ObjectClassVote& v, std::uint32_t id) { return v.object_id < id; });
    if (it == votes.end() || it->object_id != o.id || it->class_id < 0) continue;
    const auto id = static_cast<std::size_t>(it->class_id);
    o.class_label =
        id < names.size() && !names[id].empty() ? names[id] : "class_" + std::to_string(id);
    o.class_confidence = it->confidence;
  }
}

void applyFusedClasses(const DetectedObjectArray& objects,
                       const std::vector<core::FusedClass>& fused, DetectedObjectArray* out) {
  out->header = objects.header;
  out->detector = objects.detector;
  out->objects.clear();
  out->objects.reserve(objects.objects.size());
  for (std::size_t k = 0; k < objects.objects.size(); ++k) {
    if (k < fused.size() && fused[k].vetoed) continue;
    out->objects.push_back(objects.objects[k]);
    if (k >= fused.size() || !fused[k].camera_used) continue;  // unseen: label kept verbatim
    DetectedObject& o = out->objects.back();
    o.class_label = core::toString(fused[k].category);
    o.class_confidence =
        fused[k].category == core::ObjectCategory::kUnknown ? 0.0f : fused[k].confidence;
  }
}

core::ObjectCategory lidarCategory(const DetectedObject& o) {
  core::ObjectCategory c = core::ObjectCategory::kUnknown;
  if (!core::parseObjectCategory(o.class_label, &c)) return core::ObjectCategory::kUnknown;
  return c;
}

namespace {

std::vector<std::string> loadStringList(const ros::NodeHandle& nh, const std::string& name) {
  std::vector<std::string> list;
  if (nh.hasParam(name) && !nh.getParam(name, list)) {
    throw ParamError("parameter '" + nh.resolveName(name) +
                     "' must be a list of class names (strings)");
  }
  return list;
}

void loadTriple(const ros::NodeHandle& nh, const std::string& name, std::array<double, 3>* v,
                bool nonzero) {
  if (!nh.hasParam(name)) return;
  std::vector<double> list;
  if (!nh.getParam(name, list) || list.size() != 3) {
    throw ParamError("parameter '" + nh.resolveName(name) + "' must be a list of 3 numbers");
  }
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(list[c]) || (nonzero && list[c] == 0.0)) {
      throw ParamError("parameter '" + nh.resolveName(name) + "' must hold finite" +
                       (nonzero ? " non-zero" : "") + " numbers");
    }
    (*v)[c] = list[c];
  }
}

}  // namespace

void loadImageLabelTransferParams(const ros::NodeHandle& pnh, ImageLabelTransferRosParams* p) {
  const ros::NodeHandle model(pnh, "model");
  loadParam(model, "path", &p->model.model_path);
  loadParam(model, "input_width_px", &p->model.input_width_px, 8, 8192, "px");
  loadParam(model, "input_height_px", &p->model.input_height_px, 8, 8192, "px");
  loadParam(model, "input_rgb", &p->model.input_rgb);
  loadTriple(model, "mean", &p->model.mean, false);
  loadTriple(model, "scale", &p->model.scale, true);
  loadParam(model, "output_softmax", &p->model.output_softmax);
  loadParam(model, "config_file", &p->model.config_path);
  loadParam(model, "dir", &p->model_dir);
  loadParam(model, "class_names_file", &p->class_names_file);
  if (model.hasParam("keep_classes")) p->keep_classes = loadStringList(model, "keep_classes");
  p->vehicle_classes = loadStringList(model, "vehicle_classes");
  p->pedestrian_classes = loadStringList(model, "pedestrian_classes");
  p->cyclist_classes = loadStringList(model, "cyclist_classes");
  p->other_object_classes = loadStringList(model, "other_object_classes");
  p->background_classes = loadStringList(model, "background_classes");
  loadParam(model, "inference_threads", &p->inference_threads, 0, 64);
  loadParam(model, "inference_nice", &p->inference_nice, 0, 19);
  // Relative files are found in model/dir (the launch file's model_dir argument), so a preset
  // names the files of a network and the folder holding them is given where it is run.
  if (!p->model_dir.empty()) {
    for (std::string* f : {&p->model.model_path, &p->model.config_path, &p->class_names_file})
      if (!f->empty() && (*f)[0] != '/') *f = p->model_dir + "/" + *f;
  }
  std::string mode = core::toString(p->fusion.mode);
  loadParam(pnh, "fusion", &mode);
  if (!core::parseFusionMode(mode, &p->fusion.mode)) {
    throw ParamError("parameter '" + pnh.resolveName("fusion") + "' is '" + mode +
                     "'; accepted: lidar, camera, fused");
  }
  const ros::NodeHandle rule(pnh, "fusion_rule");
  loadFields(rule, &p->fusion);
  const ros::NodeHandle t(pnh, "transfer");
  loadFields(t, &p->transfer);
  loadParam(t, "queue_size", &p->queue_size, 1, 100);
  loadParam(t, "max_sync_interval_s", &p->max_sync_interval_s, 0.0, 1.0, "s");
  loadParam(t, "max_mask_gap_s", &p->max_mask_gap_s, 0.0, 10.0, "s");
  loadParam(t, "fixed_frame", &p->fixed_frame);
  loadParam(t, "tf_timeout_s", &p->tf_timeout_s, 0.0, 1.0, "s");
}

}  // namespace ros_conv
}  // namespace urban_detection
