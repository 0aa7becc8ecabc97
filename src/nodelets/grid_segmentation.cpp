// urban_detection/GridSegmentation: velodyne_points (CloudXYZIRT) -> segmentation/labeled_points
// and segmentation/foreground (paper Sec. 3.1). Thin wrapper around core::GridSegmenter;
// thresholds tunable through dynamic_reconfigure (cfg/GridSegmentation.cfg). Subscribes with
// the publisher's C++ type, so inside one manager the cloud of PacketSource / PacketToCloud
// arrives as a pointer, never serialised; a PointCloud2 from another process is deserialised
// with its sizes checked (cloud_serialization.h) and refused with an ERROR when malformed.
// Runs its callback on a thread of its own (StageThread), never behind another stage. With
// ~stream_sectors (default true) it also bins PacketSource's velodyne_points/sectors into the
// grid while a revolution arrives, so at the revolution's cloud only its last sector is left
// to bin (the labels are those of the whole cloud: GridSegmenter::addPoints).
#include "urban_detection/core/common/point_types.h"

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <boost/make_shared.hpp>
#include <pluginlib/class_list_macros.hpp>
#include "urban_detection/ros/cloud_serialization.h"

#include "urban_detection/GridSegmentationConfig.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/ros/lazy_outputs.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"
#include "urban_detection/ros/stage_thread.h"
#include "urban_detection/ros/tunable_fields.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {
namespace ros_conv {

class GridSegmentationNodelet : public nodelet::Nodelet {
 public:
  ~GridSegmentationNodelet() override {
    if (thread_) thread_->stop();  // no callback runs on the members below any more
  }

 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    core::GridSegmenterParams params;
    std::string error;
    try {
      loadFields(pnh, &nodelet_params_);
    } catch (const ParamError& e) {
      error = e.what();
    }
    if (error.empty()) {
      try {
        loadFields(pnh, &params);
      } catch (const ParamError& e) {
        error = e.what();
      }
    }
    if (!error.empty()) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), getPrivateNodeHandle(), getName(),
          "GridSegmentation: " + error + "; the nodelet stays idle");
      return;
    }
    segmenter_.reset(new core::GridSegmenter(params));
    reconfigure_ = std::make_unique<Reconfigure>(
        pnh, ros_conv::toConfig<GridSegmentationConfig>(params),
        [this, pnh](const GridSegmentationConfig& c) {
          std::lock_guard<std::mutex> lock(segment_mutex_);  // between two revolutions
          const core::GridSegmenterParams p = ros_conv::fromConfig(c, segmenter_->params());
          const std::string why = checkFields(pnh, p);
          if (!why.empty()) return why;
          segmenter_->setParams(p);
          return std::string();
        });
    diagnostics_.reset(new ros_conv::StageDiagnostics(nh, pnh, getName(), "segmentation"));
    thread_ = std::make_unique<ros_conv::StageThread>();
    diagnostics_->setActive(false);
    // Lazy: subscribe upstream only while someone listens to an output. Input queue_size:
    // the newest revolutions win when we are slow.
    lazy_ = std::make_unique<ros_conv::LazyOutputs>([this](bool wanted) {
      diagnostics_->setActive(wanted);
      if (!wanted) {
        sector_sub_.shutdown();
        return sub_.shutdown();
      }
      sub_ = thread_->handle(getNodeHandle())
                 .subscribe("velodyne_points", nodelet_params_.queue_size,
                            &GridSegmentationNodelet::cloudCb, this);
      // Same thread, so a revolution's sectors are binned before its cloud arrives.
      if (nodelet_params_.stream_sectors) {
        sector_sub_ =
            thread_->handle(getNodeHandle())
                .subscribe("velodyne_points/sectors", 64, &GridSegmentationNodelet::sectorCb, this);
      }
    });
    labeled_pub_ = lazy_->advertise<LabeledCloud>(nh, "segmentation/labeled_points", 2);
    foreground_pub_ = lazy_->advertise<LabeledCloud>(nh, "segmentation/foreground", 2);
  }

  // The open revolution's points so far (PacketSource's sectors): binned into the grid now, so
  // that only the last sector is left when the revolution's cloud arrives.
  void sectorCb(const boost::shared_ptr<const CloudXYZIRT>& sector) {
    if (!cloudRefusal(*sector).empty()) return;  // the whole cloud is checked (and binned) anyway
    std::lock_guard<std::mutex> segment_lock(segment_mutex_);
    segmenter_->addPoints(sector->header.seq, sector->points.data(), sector->size());
    sectors_seen_ = true;
  }

  void cloudCb(const ros::MessageEvent<const CloudXYZIRT>& event) {  // zero copy
    const ros::WallTime start = ros::WallTime::now();
    const boost::shared_ptr<const CloudXYZIRT>& cloud = event.getConstMessage();
    diagnostics_->input(cloud->header.seq, event.getPublisherName());
    const std::string refusal = cloudRefusal(*cloud);
    if (!refusal.empty()) {  // a malformed cloud from another process (or a bad one in ours)
      if (diagnostics_->refuse(refusal)) {
        NODELET_ERROR("GridSegmentation: refusing a cloud on velodyne_points: %s", refusal.c_str());
      }
      return;
    }
    std::lock_guard<std::mutex> segment_lock(segment_mutex_);  // vs. reconfigure
    // The foreground only when someone listens (core::segmentForeground, the chain's first two
    // stages with this nodelet's streaming segmenter).
    boost::shared_ptr<LabeledCloud> foreground;
    if (foreground_pub_.getNumSubscribers() > 0) foreground = boost::make_shared<LabeledCloud>();
    core::segmentForeground(*segmenter_, *cloud, &labels_, foreground.get());
    // The detector waits for the foreground: published before the labelled cloud is built.
    if (foreground) foreground_pub_.publish(boost::shared_ptr<const LabeledCloud>(foreground));
    // Kept at their index and labelled unknown; counted by the segmenter while binning.
    diagnostics_->count("non_finite_points", segmenter_->stats().points_non_finite, false);
    if (segmenter_->lastUsedStream()) {
      diagnostics_->count("revolutions binned as they arrived", 1, false);
      NODELET_INFO_ONCE("GridSegmentation: binning velodyne_points/sectors as revolutions arrive");
    } else if (sectors_seen_) {
      diagnostics_->count("revolutions binned whole (sectors missing)", 1, false);
    }
    if (labeled_pub_.getNumSubscribers() > 0) {
      auto labeled = boost::make_shared<LabeledCloud>();
      core::buildLabeledCloud(*cloud, labels_, labeled.get());
      labeled_pub_.publish(boost::shared_ptr<const LabeledCloud>(labeled));
    }
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
    diagnostics_->output();
  }

  using Reconfigure = ros_conv::ValidatedReconfigure<GridSegmentationConfig>;
  std::unique_ptr<core::GridSegmenter> segmenter_;
  std::mutex segment_mutex_;  // segmenter_ between frames and reconfigure
  GridSegmentationNodeletParams nodelet_params_;
  bool sectors_seen_ = false;  // a sector arrived (PacketSource publishes them)
  std::unique_ptr<Reconfigure> reconfigure_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  std::vector<core::SegmentClass> labels_;                 // scratch: per-point classes
  std::unique_ptr<ros_conv::StageThread> thread_;          // runs cloudCb
  std::unique_ptr<ros_conv::LazyOutputs> lazy_;
  ros::Publisher labeled_pub_, foreground_pub_;
  ros::Subscriber sub_, sector_sub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::GridSegmentationNodelet, nodelet::Nodelet)
