// urban_detection/ImageLabelTransfer: labels the detector's objects with the
// classes of a 2-D semantic segmentation network (any file cv::dnn::readNet reads). The network
// runs on its own thread on the newest image (older ones are dropped); the objects callback
// never waits for it: each revolution's objects take the newest mask within max_mask_gap_s of
// their stamp, projected with tf (camera <- LiDAR), and `fusion` (lidar | camera | fused)
// decides what their class becomes. Objects the camera does not see keep their LiDAR class.
// Inputs: image + camera_info (rectified), objects + objects/points. Output: objects/classified.
// Lazy. Without a usable model the nodelet refuses to start (one FATAL) and stays idle.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include "urban_detection/ros/cloud_serialization.h"

#include <atomic>
#include <boost/make_shared.hpp>
#include <chrono>
#include <memory>
#include <mutex>
#include <opencv2/core/utility.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <thread>

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/latest_slot.h"
#include "urban_detection/ros/image_label_transfer_ros.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"

namespace urban_detection {
namespace ros_conv {

class ImageLabelTransferNodelet : public nodelet::Nodelet {
  using Policy = message_filters::sync_policies::ApproximateTime<DetectedObjectArray, LabeledCloud>;
  struct Frame {  // one image waiting for the network
    sensor_msgs::Image::ConstPtr image;
    sensor_msgs::CameraInfo::ConstPtr info;
  };
  struct Mask {  // one segmented image, owned (outlives the network's next run)
    std_msgs::Header header;
    core::PinholeCamera camera;
    core::SegmentationScores scores;
  };

 public:
  ~ImageLabelTransferNodelet() override {
    slot_.close();
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override {
    ros_conv::ImageLabelTransferRosParams p;
    if (!configure(&p)) return;
    params_ = p;
    transfer_.setParams(p.transfer);
    if (p.inference_threads > 0) cv::setNumThreads(p.inference_threads);
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_);
    diagnostics_ = std::make_unique<ros_conv::StageDiagnostics>(
        getNodeHandle(), getPrivateNodeHandle(), getName(), "image label transfer");
    sync_ = std::make_unique<message_filters::Synchronizer<Policy>>(Policy(p.queue_size),
                                                                    objects_sub_, points_sub_);
    sync_->getPolicy()->setMaxIntervalDuration(ros::Duration(p.max_sync_interval_s));
    sync_->registerCallback(&ImageLabelTransferNodelet::objectsCallback, this);
    worker_ = std::thread([this] { inferenceLoop(); });
    lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) {
        image_sub_.shutdown();
        info_sub_.shutdown();
        objects_sub_.unsubscribe();
        points_sub_.unsubscribe();
        return;
      }
      ros::NodeHandle nh = getNodeHandle();
      const uint32_t q = static_cast<uint32_t>(params_.queue_size);
      if (params_.fusion.mode != core::FusionMode::kLidar) {
        // Queue 1: the network wants only the newest image.
        image_sub_ = nh.subscribe("image", 1, &ImageLabelTransferNodelet::imageCallback, this);
        info_sub_ = nh.subscribe("camera_info", 1, &ImageLabelTransferNodelet::infoCallback, this);
      }
      objects_sub_.subscribe(nh, "objects", q);
      points_sub_.subscribe(nh, "objects/points", q);
    });
    pub_ = lazy_->advertise<DetectedObjectArray>(getNodeHandle(), "objects/classified", 2);
  }

  // Parameters, model, class names and class map; false (after one FATAL) when unusable.
  bool configure(ros_conv::ImageLabelTransferRosParams* p) {
    std::string error;
    auto refuse = [this](const std::string& why) {
      refusal_ = ros_conv::RefusalDiagnostics::report(getNodeHandle(), getPrivateNodeHandle(),
                                                      getName(), "ImageLabelTransfer: " + why);
      return false;
    };
    try {
      ros_conv::loadImageLabelTransferParams(getPrivateNodeHandle(), p);
    } catch (const ParamError& e) {
      return refuse(std::string(e.what()) + "; the nodelet stays idle");
    }
    error = core::validate(p->fusion);
    if (!error.empty()) return refuse(error + "; the nodelet stays idle");
    if (p->fusion.mode != core::FusionMode::kLidar && !model_.load(p->model, &error)) {
      return refuse("refuses to start: " + error + " (parameter '" +
                    getPrivateNodeHandle().resolveName("model/path") +
                    "'). Give a semantic segmentation network cv::dnn::readNet reads (ONNX, "
                    "Torch7, Caffe, TensorFlow), e.g. config/spark_enet_cityscapes.yaml; idle");
    }
    if (!p->class_names_file.empty() && !core::readClassNames(p->class_names_file, &names_, &error))
      return refuse(error + " (parameter model/class_names_file); idle");
    // Without a names file, ids up to 65535 may be kept (the network's class count is only
    // known after its first run; ids it never outputs simply never vote).
    const int bound = names_.empty() ? 65536 : static_cast<int>(names_.size());
    if (!core::resolveKeptClasses(p->keep_classes, names_, bound, &p->transfer.kept_classes,
                                  &error))
      return refuse("parameter model/keep_classes: " + error + "; idle");
    if (p->keep_classes.empty()) p->transfer.kept_classes.clear();
    if (!core::buildCameraClassMap(names_, p->vehicle_classes, p->pedestrian_classes,
                                   p->cyclist_classes, p->other_object_classes,
                                   p->background_classes, &class_map_, &error))
      return refuse("parameters model/*_classes: " + error + "; idle");
    if (p->fusion.mode == core::FusionMode::kFused && names_.empty())
      return refuse("fusion 'fused' needs model/class_names_file and model/*_classes; idle");
    return true;
  }

  void infoCallback(const sensor_msgs::CameraInfo::ConstPtr& info) {
    std::lock_guard<std::mutex> lock(info_mutex_);
    info_ = info;
  }

  void imageCallback(const sensor_msgs::Image::ConstPtr& image) {
    auto frame = std::make_shared<Frame>();
    frame->image = image;
    {
      std::lock_guard<std::mutex> lock(info_mutex_);
      frame->info = info_;
    }
    if (!frame->info) {
      NODELET_WARN_THROTTLE(5.0, "ImageLabelTransfer: image skipped: no camera_info yet");
      return;
    }
    slot_.put(std::move(frame));
  }

  // The inference thread: newest image -> network -> owned mask in the history.
  void inferenceLoop() {
    // Lower this thread's priority (Linux: nice is per thread) so the LiDAR chain's threads
    // take the cores first; the network uses what is left.
    if (params_.inference_nice > 0 &&
        setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), params_.inference_nice) !=
            0)
      NODELET_WARN_ONCE("ImageLabelTransfer: cannot lower the inference thread's priority");
    cv::Mat scratch, bgr;
    core::SegmentationScores scores;
    std::string error;
    while (const std::shared_ptr<const Frame> frame = slot_.take()) {
      try {
        auto mask = std::make_shared<Mask>();
        mask->header = frame->image->header;
        if (!ros_conv::imageToBgr(*frame->image, &scratch, &bgr, &error) ||
            !ros_conv::cameraFromInfo(*frame->info, &mask->camera, &error) ||
            !model_.run(bgr, &scores, &error)) {
          if (diagnostics_->error("images_skipped", "image skipped: " + error)) {
            NODELET_ERROR("ImageLabelTransfer: image skipped: %s", error.c_str());
          }
          continue;
        }
        if (mask->camera.width_px != bgr.cols || mask->camera.height_px != bgr.rows) {
          NODELET_WARN_THROTTLE(5.0,
                                "ImageLabelTransfer: camera_info is %dx%d but the image %dx%d; "
                                "projecting with camera_info's size",
                                mask->camera.width_px, mask->camera.height_px, bgr.cols, bgr.rows);
        }
        scores.reduceTo(&mask->scores);
        const double ms = model_.stats().preprocess_ms + model_.stats().inference_ms;
        {
          std::lock_guard<std::mutex> lock(stats_mutex_);
          inference_ms_sum_ += ms;
        }
        const double stamp_s = mask->header.stamp.toSec();
        history_.push(stamp_s, std::move(mask));
        inferences_.fetch_add(1);
        NODELET_DEBUG_THROTTLE(5.0, "ImageLabelTransfer: network %.1f ms, %llu images dropped", ms,
                               static_cast<unsigned long long>(slot_.dropped()));
      } catch (const std::exception& e) {
        if (diagnostics_->error("images_skipped", std::string("image skipped: ") + e.what())) {
          NODELET_ERROR("ImageLabelTransfer: image skipped: %s", e.what());
        }
      }
    }
  }

  void objectsCallback(const DetectedObjectArray::ConstPtr& objects,
                       const boost::shared_ptr<const LabeledCloud>& points) {
    const auto t0 = std::chrono::steady_clock::now();
    diagnostics_->input(objects->header.seq);
    const std::string refusal = ros_conv::cloudRefusal(*points);
    if (!refusal.empty()) {  // a malformed cloud from another process
      if (diagnostics_->refuse(refusal)) {
        NODELET_ERROR("ImageLabelTransfer: refusing a cloud on objects/points: %s",
                      refusal.c_str());
      }
      return;
    }
    auto out = boost::make_shared<DetectedObjectArray>();
    std::string error;
    std::shared_ptr<const Mask> mask;
    if (params_.fusion.mode != core::FusionMode::kLidar) {
      mask = history_.newestWithin(objects->header.stamp.toSec(), params_.max_mask_gap_s);
      if (!mask)
        NODELET_DEBUG_THROTTLE(5.0, "ImageLabelTransfer: no mask within %.3f s of the objects",
                               params_.max_mask_gap_s);
    }
    Eigen::Isometry3d cam_from_lidar;
    if (mask && !ros_conv::lookupCameraFromCloud(*tf_buffer_, mask->header, objects->header,
                                                 params_.fixed_frame, params_.tf_timeout_s,
                                                 &cam_from_lidar, &error)) {
      NODELET_WARN_THROTTLE(5.0, "ImageLabelTransfer: LiDAR classes kept: %s", error.c_str());
      mask.reset();
    }
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++revolutions_;
      if (mask) {
        ++with_mask_;
        mask_age_sum_s_ += objects->header.stamp.toSec() - mask->header.stamp.toSec();
      }
      const std::uint64_t n = inferences_.load();
      NODELET_INFO_THROTTLE(30.0,
                            "ImageLabelTransfer: %llu images segmented (mean %.0f ms), %llu "
                            "dropped; %llu of %llu revolutions met a mask (mean cloud - image "
                            "stamp %.3f s)",
                            static_cast<unsigned long long>(n), n ? inference_ms_sum_ / n : 0.0,
                            static_cast<unsigned long long>(slot_.dropped()),
                            static_cast<unsigned long long>(with_mask_),
                            static_cast<unsigned long long>(revolutions_),
                            with_mask_ ? mask_age_sum_s_ / with_mask_ : 0.0);
    }
    if (!mask) {
      *out = *objects;  // LiDAR classes, unchanged
    } else {
      transfer_.transfer(*points, cam_from_lidar, mask->camera, mask->scores, &votes_);
      label(*objects, out.get());
    }
    pub_.publish(boost::shared_ptr<const DetectedObjectArray>(out));
    diagnostics_->frame(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    diagnostics_->output();
  }

  // Classes from the votes of the last transfer (objects matched to votes by id).
  void label(const DetectedObjectArray& objects, DetectedObjectArray* out) {
    const auto& fp = params_.fusion;
    if (fp.mode == core::FusionMode::kCamera) {
      ros_conv::applyVotes(objects, votes_, names_, out);
      for (std::size_t k = 0; k < out->objects.size(); ++k) {  // unseen: LiDAR class stays
        const auto* v = voteOf(objects.objects[k].id);
        if (v == nullptr || v->considered < static_cast<std::uint32_t>(fp.min_visible_points)) {
          out->objects[k].class_label = objects.objects[k].class_label;
          out->objects[k].class_confidence = objects.objects[k].class_confidence;
        }
      }
      return;
    }
    fused_.clear();
    for (const DetectedObject& o : objects.objects) {
      const auto* v = voteOf(o.id);
      core::CameraEvidence e;
      if (v != nullptr) {
        e = core::cameraEvidence(transfer_.classScores(static_cast<std::size_t>(v - votes_.data())),
                                 transfer_.classBound(), v->considered, class_map_);
      }
      fused_.push_back(
          core::fuseObjectClass(ros_conv::lidarCategory(o), o.class_confidence, e, fp));
    }
    ros_conv::applyFusedClasses(objects, fused_, out);
  }

  const core::ObjectClassVote* voteOf(std::uint32_t id) const {
    const auto it = std::lower_bound(
        votes_.begin(), votes_.end(), id,
        [](const core::ObjectClassVote& v, std::uint32_t i) { return v.object_id < i; });
    return it != votes_.end() && it->object_id == id ? &*it : nullptr;
  }

  ros_conv::ImageLabelTransferRosParams params_;
  core::SegmentationModel model_;  // used by the inference thread only
  core::ImageLabelTransfer transfer_;
  core::CameraClassMap class_map_;
  std::vector<core::ObjectClassVote> votes_;
  std::vector<core::FusedClass> fused_;
  std::vector<std::string> names_;
  core::LatestSlot<Frame> slot_;
  core::MaskHistory<Mask> history_{4};
  std::atomic<std::uint64_t> inferences_{0};
  std::mutex stats_mutex_;
  double inference_ms_sum_ = 0.0, mask_age_sum_s_ = 0.0;
  std::uint64_t revolutions_ = 0, with_mask_ = 0;
  std::thread worker_;
  std::mutex info_mutex_;
  sensor_msgs::CameraInfo::ConstPtr info_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  ros::Subscriber image_sub_, info_sub_;
  message_filters::Subscriber<DetectedObjectArray> objects_sub_;
  message_filters::Subscriber<LabeledCloud> points_sub_;
  std::unique_ptr<message_filters::Synchronizer<Policy>> sync_;
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher pub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ImageLabelTransferNodelet, nodelet::Nodelet)
