// urban_detection/ImageLabelTransfer: labels the detector's objects with the classes of a 2-D
// semantic segmentation network. The network runs on the stage's own thread (StageThread at
// nice model/inference_nice) on the newest image (queue 1: older ones are dropped); the objects
// callback never waits for it: each revolution's objects take the newest mask within
// transfer/max_mask_gap_s of their stamp, projected with tf (camera <- LiDAR), and
// core::CameraLabeller gives them their classes under `fusion` (lidar | camera | fused).
// Inputs: image + camera_info (rectified), objects + objects/points. Output: objects/classified.
// Lazy. Parameters: config/image_label_transfer.yaml (core::CameraStageParams); without a usable
// model the nodelet refuses to start (one FATAL) and stays idle.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_ros/transform_listener.h>
#include <boost/make_shared.hpp>
#include <chrono>
#include <opencv2/core/utility.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/ros/cloud_serialization.h"
#include "urban_detection/ros/image_label_transfer_ros.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/stage_thread.h"

namespace urban_detection {
namespace ros_conv {

class ImageLabelTransferNodelet : public nodelet::Nodelet {
  using Policy = message_filters::sync_policies::ApproximateTime<DetectedObjectArray, LabeledCloud>;

 public:
  ~ImageLabelTransferNodelet() override {
    if (thread_) thread_->stop();  // before the state imageCb uses goes
  }

 private:
  void onInit() override {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    try {
      loadCameraStage(pnh, &p_, &model_);
    } catch (const ParamError& e) {
      refusal_ = RefusalDiagnostics::report(
          getNodeHandle(), pnh, getName(),
          "ImageLabelTransfer: " + std::string(e.what()) + "; the nodelet stays idle");
      return;
    }
    masks_ = std::make_unique<CameraMasks>(&model_.network);
    labelling_ = std::make_unique<ObjectLabelling>(p_, model_, *masks_, tf_buffer_);
    if (p_.model.inference_threads > 0) cv::setNumThreads(p_.model.inference_threads);
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_);
    diagnostics_ =
        std::make_unique<StageDiagnostics>(getNodeHandle(), pnh, getName(), "image label transfer");
    thread_ = std::make_unique<StageThread>(p_.model.inference_nice);
    if (!thread_->niceError().empty())
      NODELET_WARN("ImageLabelTransfer: inference thread: %s", thread_->niceError().c_str());
    sync_ = std::make_unique<message_filters::Synchronizer<Policy>>(Policy(p_.queue_size),
                                                                    objects_sub_, points_sub_);
    sync_->getPolicy()->setMaxIntervalDuration(ros::Duration(p_.max_sync_interval_s));
    sync_->registerCallback(&ImageLabelTransferNodelet::objectsCb, this);
    lazy_ = std::make_unique<LazyOutputs>([this](bool wanted) { subscribe(wanted); });
    pub_ = lazy_->advertise<DetectedObjectArray>(getNodeHandle(), "objects/classified", 2);
  }

  void subscribe(bool wanted) {
    diagnostics_->setActive(wanted);
    image_sub_ = info_sub_ = ros::Subscriber();
    objects_sub_.unsubscribe();
    points_sub_.unsubscribe();
    if (!wanted) return;
    ros::NodeHandle nh = getNodeHandle();
    if (p_.fusion.mode != core::FusionMode::kLidar) {  // queue 1: the newest image only
      image_sub_ =
          thread_->handle(nh).subscribe("image", 1, &ImageLabelTransferNodelet::imageCb, this);
      info_sub_ = nh.subscribe("camera_info", 1, &CameraMasks::setInfo, masks_.get());
    }
    objects_sub_.subscribe(nh, "objects", static_cast<uint32_t>(p_.queue_size));
    points_sub_.subscribe(nh, "objects/points", static_cast<uint32_t>(p_.queue_size));
  }

  void imageCb(const sensor_msgs::Image::ConstPtr& image) {  // on the stage thread
    std::string error, warning;
    if (!masks_->segment(*image, &error, &warning)) {
      if (error == CameraMasks::kNoCameraInfo)
        NODELET_WARN_THROTTLE(5.0, "ImageLabelTransfer: image skipped: %s", error.c_str());
      else if (diagnostics_->error("images_skipped", "image skipped: " + error))
        NODELET_ERROR("ImageLabelTransfer: image skipped: %s", error.c_str());
      return;
    }
    if (!warning.empty()) NODELET_WARN_THROTTLE(5.0, "ImageLabelTransfer: %s", warning.c_str());
    diagnostics_->count("images_segmented", 1, false);
    diagnostics_->count("images_dropped", image_gaps_.add(image->header.seq), false);
    NODELET_DEBUG_THROTTLE(
        5.0, "ImageLabelTransfer: network %.1f ms",
        model_.network.stats().preprocess_ms + model_.network.stats().inference_ms);
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& objects,
                 const boost::shared_ptr<const LabeledCloud>& points) {
    const auto t0 = std::chrono::steady_clock::now();
    diagnostics_->input(objects->header.seq);
    const std::string refusal = cloudRefusal(*points);
    if (!refusal.empty()) {  // a malformed cloud from another process
      if (diagnostics_->refuse(refusal))
        NODELET_ERROR("ImageLabelTransfer: refusing a cloud on objects/points: %s",
                      refusal.c_str());
      return;
    }
    auto out = boost::make_shared<DetectedObjectArray>();
    std::string why_not;
    const bool with_mask = labelling_->label(*objects, *points, out.get(), &why_not);
    if (!why_not.empty())
      NODELET_WARN_THROTTLE(5.0, "ImageLabelTransfer: LiDAR classes kept: %s", why_not.c_str());
    diagnostics_->count(with_mask ? "revolutions_with_mask" : "revolutions_without_mask", 1, false);
    pub_.publish(boost::shared_ptr<const DetectedObjectArray>(out));
    diagnostics_->frame(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    diagnostics_->output();
  }

  core::CameraStageParams p_;
  core::CameraModel model_;  // its network is used on the stage thread only
  std::unique_ptr<CameraMasks> masks_;
  std::unique_ptr<ObjectLabelling> labelling_;
  SeqGapCounter image_gaps_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<StageDiagnostics> diagnostics_;
  std::unique_ptr<RefusalDiagnostics> refusal_;  // set when it refused to start
  std::unique_ptr<StageThread> thread_;          // runs imageCb
  ros::Subscriber image_sub_, info_sub_;
  message_filters::Subscriber<DetectedObjectArray> objects_sub_;
  message_filters::Subscriber<LabeledCloud> points_sub_;
  std::unique_ptr<message_filters::Synchronizer<Policy>> sync_;
  std::unique_ptr<LazyOutputs> lazy_;
  ros::Publisher pub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ImageLabelTransferNodelet, nodelet::Nodelet)
