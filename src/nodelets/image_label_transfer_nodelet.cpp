// urban_detection/ImageLabelTransfer (issue 9): labels the detector's objects with the classes of
// a 2-D semantic segmentation network (ONNX through OpenCV DNN). Inputs, time-synchronised:
// image + camera_info (rectified camera), objects (DetectedObjectArray) and objects/points
// (LabeledCloud, label = object id). Output: objects/classified (the objects with class_label
// and class_confidence filled). Lazy. Without model/path the nodelet refuses to start.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <pcl_ros/point_cloud.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <boost/make_shared.hpp>
#include <chrono>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/ros/image_label_transfer_ros.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/lazy_outputs.h"

namespace urban_detection {

class ImageLabelTransferNodelet : public nodelet::Nodelet {
  using Policy =
      message_filters::sync_policies::ApproximateTime<sensor_msgs::Image, sensor_msgs::CameraInfo,
                                                      DetectedObjectArray, LabeledCloud>;

 private:
  void onInit() override {
    ros_conv::ImageLabelTransferRosParams p;
    std::string error;
    try {
      ros_conv::loadImageLabelTransferParams(getPrivateNodeHandle(), &p);
    } catch (const ParamError& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "ImageLabelTransfer: " + std::string(e.what()) + "; the nodelet stays idle");
      return;
    }
    if (!model_.load(p.model, &error)) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "ImageLabelTransfer refuses to start: " + error + " (parameter '" +
          getPrivateNodeHandle().resolveName("model/path") + "'). Export a semantic "
          "segmentation network (e.g. DeepLabv3 on Cityscapes) to ONNX (opset <= 13) "
          "and set it; the nodelet stays idle");
      return;
    }
    if (!p.class_names_file.empty() && !core::readClassNames(p.class_names_file, &names_, &error)) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "ImageLabelTransfer: " + error + " (parameter model/class_names_file); idle");
      return;
    }
    // Without a names file, ids up to 65535 may be kept (the network's class count is only
    // known after its first run; ids it never outputs simply never vote).
    const int bound = names_.empty() ? 65536 : static_cast<int>(names_.size());
    if (!core::resolveKeptClasses(p.keep_classes, names_, bound, &p.transfer.kept_classes,
                                  &error)) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "ImageLabelTransfer: parameter model/keep_classes: " + error + "; idle");
      return;
    }
    if (p.keep_classes.empty()) p.transfer.kept_classes.clear();
    params_ = p;
    transfer_.setParams(p.transfer);
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
    diagnostics_ = std::make_unique<ros_conv::StageDiagnostics>(
        getNodeHandle(), getPrivateNodeHandle(), getName(), "image label transfer");
    sync_ = std::make_unique<message_filters::Synchronizer<Policy>>(
        Policy(p.queue_size), image_sub_, info_sub_, objects_sub_, points_sub_);
    sync_->getPolicy()->setMaxIntervalDuration(ros::Duration(p.max_sync_interval_s));
    sync_->registerCallback(&ImageLabelTransferNodelet::callback, this);
    lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) {
        image_sub_.unsubscribe();
        info_sub_.unsubscribe();
        objects_sub_.unsubscribe();
        points_sub_.unsubscribe();
        return;
      }
      ros::NodeHandle nh = getNodeHandle();
      const uint32_t q = static_cast<uint32_t>(params_.queue_size);
      image_sub_.subscribe(nh, "image", q);
      info_sub_.subscribe(nh, "camera_info", q);
      objects_sub_.subscribe(nh, "objects", q);
      points_sub_.subscribe(nh, "objects/points", q);
    });
    pub_ = lazy_->advertise<DetectedObjectArray>(getNodeHandle(), "objects/classified", 2);
  }

  void callback(const sensor_msgs::Image::ConstPtr& image,
                const sensor_msgs::CameraInfo::ConstPtr& info,
                const DetectedObjectArray::ConstPtr& objects,
                const boost::shared_ptr<const LabeledCloud>& points) {
    const auto t0 = std::chrono::steady_clock::now();
    std::string error;
    core::PinholeCamera camera;
    if (!ros_conv::imageToBgr(*image, &scratch_, &bgr_, &error) ||
        !ros_conv::cameraFromInfo(*info, &camera, &error)) {
      return reject(error);
    }
    Eigen::Isometry3d cam_from_lidar;
    if (!ros_conv::lookupCameraFromCloud(*tf_buffer_, image->header, objects->header,
                                         params_.fixed_frame, params_.tf_timeout_s, &cam_from_lidar,
                                         &error)) {
      return reject(error);
    }
    if (!model_.run(bgr_, &scores_, &error)) return reject(error);
    const auto t_net = std::chrono::steady_clock::now();
    transfer_.transfer(*points, cam_from_lidar, camera, scores_, &votes_);
    auto out = boost::make_shared<DetectedObjectArray>();
    ros_conv::applyVotes(*objects, votes_, names_, out.get());
    pub_.publish(boost::shared_ptr<const DetectedObjectArray>(out));
    const auto t1 = std::chrono::steady_clock::now();
    const double net_ms = model_.stats().preprocess_ms + model_.stats().inference_ms;
    NODELET_DEBUG_THROTTLE(
        5.0, "ImageLabelTransfer: network %.1f ms, transfer %.2f ms, %zu objects", net_ms,
        std::chrono::duration<double, std::milli>(t1 - t_net).count(), out->objects.size());
    diagnostics_->frame(std::chrono::duration<double>(t1 - t0).count());
  }

  void reject(const std::string& why) {
    NODELET_WARN_THROTTLE(5.0, "ImageLabelTransfer: frame skipped: %s", why.c_str());
    diagnostics_->rejected();
  }

  ros_conv::ImageLabelTransferRosParams params_;
  core::SegmentationModel model_;
  core::SegmentationScores scores_;
  core::ImageLabelTransfer transfer_;
  std::vector<core::ObjectClassVote> votes_;
  std::vector<std::string> names_;
  cv::Mat scratch_, bgr_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  message_filters::Subscriber<sensor_msgs::Image> image_sub_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> info_sub_;
  message_filters::Subscriber<DetectedObjectArray> objects_sub_;
  message_filters::Subscriber<LabeledCloud> points_sub_;
  std::unique_ptr<message_filters::Synchronizer<Policy>> sync_;
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher pub_;
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ImageLabelTransferNodelet, nodelet::Nodelet)
