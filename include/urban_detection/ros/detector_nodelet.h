/// \file detector_nodelet.h
/// The code shared by the detector nodelets (HierarchicalGridDetector, KdTreeDetector):
/// segmentation/foreground -> objects (DetectedObjectArray) and objects/points (LabeledCloud,
/// label = object id). Lazy (subscribes upstream only while an output has subscribers) and
/// zero copy (fresh boost::shared_ptr per frame, never touched after publishing), input queue
/// of ~queue_size revolutions (the newest win), StageDiagnostics on /diagnostics with the
/// latency from header.stamp to `objects`. Detection runs on the stage's own thread
/// (StageThread, niceness ~thread_nice; ~thread_idle: SCHED_IDLE, the CPU only when no other
/// thread wants it), so a slow detector never holds up another stage; ~best_effort (a baseline
/// beside the live chain): its rate reported as what it is, not as falling behind. A derived
/// nodelet builds its core::ObjectDetector from its parameters and may serve
/// dynamic_reconfigure, swapping in a new detector between two revolutions. The chain after the
/// segmentation is core::Pipeline::detect(): the detector, then core::ObjectClassifier
/// (params ~classifier/*: enabled, model, min_object_probability, reject_non_objects) gives
/// each object its class (class_label, class_confidence); non-objects (vegetation, terrain,
/// structure) are left out of `objects` by default and published on `objects/rejected`
/// (lazy). A missing, corrupt or mismatched model file makes the nodelet refuse to start with
/// one FATAL naming the file; the manager keeps running. min_object_probability and
/// reject_non_objects are dynamic_reconfigure parameters in ~classifier (config/
/// ObjectClassifier.cfg), applied from the next revolution.
///
/// Early objects (~early_objects, default false; docs/design.md "Early objects"): a second
/// chain, on a thread of its own, takes PacketSource's velodyne_points/sectors and the
/// revolution's velodyne_points (core::Pipeline::addSector / finishRevolution, segmentation
/// parameters in ~segmentation/*, ~early/* for core::EarlyObjectsParams) and publishes on
/// objects/early one DetectedObjectArray per object, stamped at the object's own last point:
/// an object as soon as it is final, the others when the revolution's cloud closes the seam.
/// Per revolution objects/early holds exactly the objects of `objects`. Lazy as the rest.
#pragma once

#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <boost/shared_ptr.hpp>

#include "urban_detection/ObjectClassifierConfig.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/stage_thread.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {
namespace ros_conv {

class DetectorNodelet : public nodelet::Nodelet {
 public:
  ~DetectorNodelet() override;

 protected:
  /// Loads the parameters from `pnh` and builds the detector; throws (ParamError,
  /// std::invalid_argument) with a message naming the bad parameter.
  virtual std::unique_ptr<core::ObjectDetector> createDetector(const ros::NodeHandle& pnh) = 0;
  /// Called once after createDetector() succeeded; serves dynamic_reconfigure if the detector
  /// has tunable parameters.
  virtual void startReconfigure(const ros::NodeHandle& /*pnh*/) {}
  /// Replaces the detector; takes effect between two revolutions, never during one.
  void replaceDetector(std::unique_ptr<core::ObjectDetector> detector);
  /// The same with a second instance for the early-objects chain (used when it runs).
  void replaceDetector(std::unique_ptr<core::ObjectDetector> detector,
                       std::unique_ptr<core::ObjectDetector> early);

 private:
  void onInit() final;
  void foregroundCb(const ros::MessageEvent<const LabeledCloud>& event);  // zero copy
  // Early objects: one sector of the open revolution, and the revolution's whole cloud.
  void startEarly(const ros::NodeHandle& pnh);
  void sectorCb(const boost::shared_ptr<const CloudXYZIRT>& sector);
  void revolutionCb(const boost::shared_ptr<const CloudXYZIRT>& cloud);
  // Publishes `object` alone on objects/early at `stamp`.
  void publishEarly(const core::DetectedObject& object, const std::string& frame_id,
                    const ros::Time& stamp);

  std::mutex detector_mutex_;  // pipeline_ between revolutions and reconfigure
  // detector -> classifier -> whole-object boxes; holds the objects between frames
  std::unique_ptr<core::Pipeline> pipeline_;
  // ~classifier: threshold and rejection, while the classifier is enabled.
  std::unique_ptr<ros_conv::ValidatedReconfigure<ObjectClassifierConfig>> classifier_reconfigure_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  int queue_size_ = 2;
  int thread_nice_ = 0;
  bool thread_idle_ = false;  // SCHED_IDLE stage thread
  bool best_effort_ = false;  // diagnostics: best-effort rate, newest revolution only
  std::unique_ptr<ros_conv::StageThread> thread_;  // runs foregroundCb
  std::unordered_map<std::uint32_t, std::uint32_t> id_of_index_;
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher objects_pub_, points_pub_, rejected_pub_;
  ros::Subscriber sub_;
  // Early objects (~early_objects).
  bool early_objects_ = false;
  std::mutex early_mutex_;  // early_pipeline_ between sectors and reconfigure
  std::unique_ptr<core::Pipeline> early_pipeline_;  // its own chain, segmentation included
  std::unique_ptr<ros_conv::StageThread> early_thread_;
  std::unique_ptr<ros_conv::LazyOutputs> early_lazy_;
  ros::Publisher early_pub_;
  ros::Subscriber early_sector_sub_, early_cloud_sub_;
  std::size_t early_mismatches_ = 0;
};

}  // namespace ros_conv
}  // namespace urban_detection
