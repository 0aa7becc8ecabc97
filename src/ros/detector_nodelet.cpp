#include "urban_detection/ros/detector_nodelet.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <pcl_conversions/pcl_conversions.h>
#include <boost/make_shared.hpp>
#include "urban_detection/ros/cloud_serialization.h"

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/ros/detection_params.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/object_conversions.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/tunable_fields.h"

namespace urban_detection {
namespace ros_conv {

void DetectorNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  try {
    DetectorNodeletParams settings;  // the nodelet's own settings (nodelet_params.h)
    loadFields(getPrivateNodeHandle(), &settings);
    queue_size_ = settings.queue_size;
    thread_nice_ = settings.thread_nice;
    thread_idle_ = settings.thread_idle;
    best_effort_ = settings.best_effort;
    early_objects_ = settings.early_objects;
    std::unique_ptr<core::ObjectDetector> detector = createDetector(getPrivateNodeHandle());
    core::PipelineParams params;  // the chain after the segmentation (its own nodelet)
    params.detector = detector->name();
    ros_conv::loadObjectClassifierParams(ros::NodeHandle(getPrivateNodeHandle(), "classifier"),
                                         &params.classifier);
    loadFields(ros::NodeHandle(getPrivateNodeHandle(), "box_fitting"), &params.box_fitting);
    pipeline_ = std::make_unique<core::Pipeline>(params, std::move(detector));
    if (early_objects_) startEarly(getPrivateNodeHandle());
  } catch (const std::exception& e) {
    refusal_ = ros_conv::RefusalDiagnostics::report(
        getNodeHandle(), getPrivateNodeHandle(), getName(),
        getName() + ": " + e.what() + "; the nodelet stays idle");
    return;
  }
  startReconfigure(getPrivateNodeHandle());
  core::ObjectClassifier& classifier = pipeline_->classifier();
  if (classifier.params().enabled) {
    const ros::NodeHandle classifier_nh(getPrivateNodeHandle(), "classifier");
    const ObjectClassifierConfig initial =
        ros_conv::toConfig<ObjectClassifierConfig>(classifier.params());
    auto apply = [this, classifier_nh](const ObjectClassifierConfig& c) -> std::string {
      core::ObjectClassifier& classifier = pipeline_->classifier();
      const core::ObjectClassifierParams p = ros_conv::fromConfig(c, classifier.params());
      const std::string error = checkFields(classifier_nh, p);
      if (!error.empty()) return error;
      std::lock_guard<std::mutex> lock(detector_mutex_);  // between two revolutions
      classifier.setDecision(p.min_object_probability, p.reject_non_objects, p.keep_uncertain);
      if (early_pipeline_) {
        std::lock_guard<std::mutex> early_lock(early_mutex_);
        early_pipeline_->classifier().setDecision(p.min_object_probability, p.reject_non_objects,
                                                  p.keep_uncertain);
      }
      return "";
    };
    classifier_reconfigure_ =
        std::make_unique<ros_conv::ValidatedReconfigure<ObjectClassifierConfig>>(classifier_nh,
                                                                                 initial, apply);
  }
  diagnostics_ = std::make_unique<ros_conv::StageDiagnostics>(nh, getPrivateNodeHandle(), getName(),
                                                              "detection");
  diagnostics_->setActive(false);
  diagnostics_->setBestEffort(best_effort_);
  thread_ = std::make_unique<ros_conv::StageThread>(thread_nice_, thread_idle_);
  lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
    diagnostics_->setActive(wanted);
    if (!wanted) return sub_.shutdown();
    sub_ = thread_->handle(getNodeHandle())
               .subscribe("segmentation/foreground", queue_size_, &DetectorNodelet::foregroundCb,
                          this);
  });
  objects_pub_ = lazy_->advertise<DetectedObjectArray>(nh, "objects", 2);
  points_pub_ = lazy_->advertise<LabeledCloud>(nh, "objects/points", 2);
  rejected_pub_ = lazy_->advertise<DetectedObjectArray>(nh, "objects/rejected", 2);
  if (classifier.params().enabled) {
    if (!thread_->niceError().empty()) {
      NODELET_WARN("%s: thread_nice %d / thread_idle %s not applied: %s", getName().c_str(),
                   thread_nice_, thread_idle_ ? "true" : "false", thread_->niceError().c_str());
    }
    NODELET_INFO("%s: %s detector ready, classifier %s (P(object) >= %.2f)", getName().c_str(),
                 pipeline_->detector().name().c_str(), classifier.params().model_path.c_str(),
                 classifier.threshold());
  } else {
    NODELET_INFO("%s: %s detector ready, classifier off", getName().c_str(),
                 pipeline_->detector().name().c_str());
  }
}

DetectorNodelet::~DetectorNodelet() {
  if (thread_) thread_->stop();  // no callback runs on the members below any more
  if (early_thread_) early_thread_->stop();
}

void DetectorNodelet::startEarly(const ros::NodeHandle& pnh) {
  // The whole chain from the points: the segmentation with the segmentation nodelet's
  // parameters (the launch file loads them into ~segmentation), the same detector, classifier
  // and box fitting as the classic chain.
  core::PipelineParams params = pipeline_->params();
  loadFields(ros::NodeHandle(pnh, "segmentation"), &params.segmentation);
  loadFields(ros::NodeHandle(pnh, "early"), &params.early);
  early_pipeline_ = std::make_unique<core::Pipeline>(params, createDetector(pnh));
  early_thread_ = std::make_unique<ros_conv::StageThread>(thread_nice_);
  ros::NodeHandle& nh = getNodeHandle();
  early_lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
    if (!wanted) {
      early_sector_sub_.shutdown();
      early_cloud_sub_.shutdown();
      return;
    }
    ros::NodeHandle h = early_thread_->handle(getNodeHandle());
    early_sector_sub_ = h.subscribe("velodyne_points/sectors", 64, &DetectorNodelet::sectorCb, this,
                                    ros::TransportHints().tcpNoDelay());
    early_cloud_sub_ = h.subscribe("velodyne_points", 2, &DetectorNodelet::revolutionCb, this,
                                   ros::TransportHints().tcpNoDelay());
  });
  early_pub_ = early_lazy_->advertise<DetectedObjectArray>(nh, "objects/early", 64);
  NODELET_INFO("%s: early objects on objects/early", getName().c_str());
}

void DetectorNodelet::publishEarly(const core::DetectedObject& object, const std::string& frame_id,
                                   const ros::Time& stamp) {
  std_msgs::Header header;
  header.frame_id = frame_id;
  header.stamp = stamp;
  auto msg = boost::make_shared<DetectedObjectArray>();
  ros_conv::toMsg(std::vector<core::DetectedObject>{object}, pipeline_->detector().name(), header,
                  msg.get());
  early_pub_.publish(boost::shared_ptr<const DetectedObjectArray>(msg));
}

namespace {

// The stamp of a point swept `behind_s` before the point that stamps `stamp` (clamped at 0).
ros::Time before(const ros::Time& stamp, double behind_s) {
  const double s = stamp.toSec() - std::max(0.0, behind_s);
  return s > 0.0 ? ros::Time(s) : stamp;
}

}  // namespace

void DetectorNodelet::sectorCb(const boost::shared_ptr<const CloudXYZIRT>& sector) {
  if (sector->empty() || !cloudRefusal(*sector).empty()) return;  // the seam gives them all
  std::lock_guard<std::mutex> lock(early_mutex_);
  const core::EarlySectorResult& r =
      early_pipeline_->addSector(sector->header.seq, sector->points.data(), sector->size());
  std_msgs::Header header;
  pcl_conversions::fromPCL(sector->header, header);
  const float last = sector->points.back().time;
  for (std::size_t k = 0; k < r.objects.size(); ++k) {
    publishEarly(r.objects[k], header.frame_id,
                 before(header.stamp, static_cast<double>(last - r.last_point_time_s[k])));
  }
}

void DetectorNodelet::revolutionCb(const boost::shared_ptr<const CloudXYZIRT>& cloud) {
  if (cloud->empty() || !cloudRefusal(*cloud).empty()) return;
  std::lock_guard<std::mutex> lock(early_mutex_);
  const core::PipelineResult& r = early_pipeline_->finishRevolution(*cloud);
  std_msgs::Header header;
  pcl_conversions::fromPCL(cloud->header, header);
  float last = 0.0f;
  for (const PointXYZIRT& p : cloud->points) last = std::max(last, p.time);
  for (std::size_t k = 0; k < r.objects.size(); ++k) {
    if (r.given_early[k]) continue;
    publishEarly(r.objects[k], header.frame_id,
                 before(header.stamp, static_cast<double>(last - r.last_point_time_s[k])));
  }
  if (r.early_mismatches > 0) {
    early_mismatches_ += r.early_mismatches;
    NODELET_WARN_THROTTLE(5.0, "%s: %zu early objects not in their revolution (%zu so far)",
                          getName().c_str(), r.early_mismatches, early_mismatches_);
  }
}

void DetectorNodelet::replaceDetector(std::unique_ptr<core::ObjectDetector> detector) {
  std::lock_guard<std::mutex> lock(detector_mutex_);
  pipeline_->setDetector(std::move(detector));
}

void DetectorNodelet::replaceDetector(std::unique_ptr<core::ObjectDetector> detector,
                                      std::unique_ptr<core::ObjectDetector> early) {
  {
    std::lock_guard<std::mutex> lock(detector_mutex_);
    pipeline_->setDetector(std::move(detector));
  }
  if (early_pipeline_) {
    std::lock_guard<std::mutex> lock(early_mutex_);
    early_pipeline_->setDetector(std::move(early));
  }
}

void DetectorNodelet::foregroundCb(const ros::MessageEvent<const LabeledCloud>& event) {
  const ros::WallTime start = ros::WallTime::now();
  const boost::shared_ptr<const LabeledCloud>& foreground = event.getConstMessage();
  diagnostics_->input(foreground->header.seq, event.getPublisherName());
  const std::string refusal = cloudRefusal(*foreground);
  if (!refusal.empty()) {  // a malformed cloud from another process (or a bad one in ours)
    if (diagnostics_->refuse(refusal)) {
      NODELET_ERROR("%s: refusing a cloud on segmentation/foreground: %s", getName().c_str(),
                    refusal.c_str());
    }
    return;
  }
  std::lock_guard<std::mutex> lock(detector_mutex_);  // one parameter set per revolution
  const core::PipelineResult& result = pipeline_->detect(*foreground);
  const core::ObjectClassifierStats& classified = result.classification;
  if (pipeline_->classifier().params().enabled) {
    diagnostics_->count("rejected objects (classifier: non_object)", classified.rejected, false);
    for (int c = 1; c < core::kNumObjectCategories; ++c) {
      diagnostics_->count(
          std::string("objects classified ") + core::toString(static_cast<core::ObjectCategory>(c)),
          classified.by_class[c], false);
    }
  }
  std_msgs::Header header;
  pcl_conversions::fromPCL(foreground->header, header);
  if (objects_pub_.getNumSubscribers() > 0) {
    auto msg = boost::make_shared<DetectedObjectArray>();
    ros_conv::toMsg(result.objects, pipeline_->detector().name(), header, msg.get());
    objects_pub_.publish(boost::shared_ptr<const DetectedObjectArray>(msg));
    diagnostics_->latency(header.stamp, ros::Time::now());
  }
  if (rejected_pub_.getNumSubscribers() > 0) {
    auto msg = boost::make_shared<DetectedObjectArray>();
    ros_conv::toMsg(result.rejected, pipeline_->detector().name(), header, msg.get());
    rejected_pub_.publish(boost::shared_ptr<const DetectedObjectArray>(msg));
  }
  if (points_pub_.getNumSubscribers() > 0) {
    auto points = boost::make_shared<LabeledCloud>();
    ros_conv::buildObjectPoints(*foreground, result.objects, points.get(), &id_of_index_);
    points_pub_.publish(boost::shared_ptr<const LabeledCloud>(points));
  }
  diagnostics_->frame((ros::WallTime::now() - start).toSec());
  diagnostics_->output();
  NODELET_DEBUG_THROTTLE(5.0, "%s: %zu foreground points -> %zu objects", getName().c_str(),
                         foreground->size(), result.objects.size());
}

}  // namespace ros_conv
}  // namespace urban_detection
