// urban_detection/GridSegmentation: velodyne_points -> segmentation/labeled_points and
// segmentation/foreground (paper Sec. 3.1). Thin wrapper around core::GridSegmenter.
#include "urban_detection/core/point_types.h"

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <boost/make_shared.hpp>
#include <dynamic_reconfigure/server.h>
#include <nodelet/nodelet.h>
#include <pcl_ros/point_cloud.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include "urban_detection/GridSegmentationConfig.h"
#include "urban_detection/core/grid_segmenter.h"
#include "urban_detection/ros/pointcloud2_input.h"
#include "urban_detection/ros/segmentation_params.h"
#include "urban_detection/ros/stage_diagnostics.h"

namespace urban_detection {

class GridSegmentation : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    core::GridSegmenterParams params;
    std::string error;
    if (!ros_conv::loadGridSegmenterParams(pnh, &params, &error)) {
      NODELET_FATAL("GridSegmentation: %s; the nodelet stays idle", error.c_str());
      return;
    }
    segmenter_.reset(new core::GridSegmenter(params));
    startReconfigure(params);
    diagnostics_.reset(new ros_conv::StageDiagnostics(nh, pnh, getName(), "segmentation"));
    // Lazy: subscribe upstream only while someone listens to an output.
    ros::SubscriberStatusCallback connect = [this](const ros::SingleSubscriberPublisher&) {
      connectCb();
    };
    std::lock_guard<std::mutex> lock(connect_mutex_);
    labeled_pub_ = nh.advertise<LabeledCloud>("segmentation/labeled_points", 2, connect, connect);
    foreground_pub_ = nh.advertise<LabeledCloud>("segmentation/foreground", 2, connect, connect);
  }

  // dynamic_reconfigure (config/GridSegmentation.cfg), starting from the loaded parameters.
  void startReconfigure(const core::GridSegmenterParams& p) {
    reconfigure_.reset(new ReconfigureServer(reconfigure_mutex_, getPrivateNodeHandle()));
    GridSegmentationConfig c;
    c.sensor_height_m = p.sensor_height_m;
    c.min_points_per_cell = p.min_points_per_cell;
    c.ground_max_range_m = p.ground_max_range_m;
    c.ground_tolerance_m = p.ground_tolerance_m;
    c.ground_max_step_m = p.ground_max_step_m;
    c.tall_min_height_m = p.tall_min_height_m;
    c.tall_min_range_m = p.tall_min_range_m;
    c.hough_enabled = p.hough.enabled;
    c.hough_votes = p.hough.votes;
    c.hough_min_line_length_m = p.hough.min_line_length_m;
    c.hough_max_line_gap_m = p.hough.max_line_gap_m;
    c.hough_min_tall_fraction = p.hough.min_tall_fraction;
    {
      boost::recursive_mutex::scoped_lock lock(reconfigure_mutex_);
      reconfigure_->updateConfig(c);
    }
    reconfigure_->setCallback(
        [this](const GridSegmentationConfig& config, std::uint32_t) { reconfigureCb(config); });
  }

  void reconfigureCb(const GridSegmentationConfig& c) {
    std::lock_guard<std::mutex> lock(segment_mutex_);
    core::GridSegmenterParams p = segmenter_->params();
    p.sensor_height_m = c.sensor_height_m;
    p.min_points_per_cell = c.min_points_per_cell;
    p.ground_max_range_m = c.ground_max_range_m;
    p.ground_tolerance_m = c.ground_tolerance_m;
    p.ground_max_step_m = c.ground_max_step_m;
    p.tall_min_height_m = c.tall_min_height_m;
    p.tall_min_range_m = c.tall_min_range_m;
    p.hough.enabled = c.hough_enabled;
    p.hough.votes = c.hough_votes;
    p.hough.min_line_length_m = c.hough_min_line_length_m;
    p.hough.max_line_gap_m = c.hough_max_line_gap_m;
    p.hough.min_tall_fraction = c.hough_min_tall_fraction;
    segmenter_->setParams(p);  // the cfg's ranges keep every value valid
  }

  void connectCb() {
    std::lock_guard<std::mutex> lock(connect_mutex_);
    const bool wanted =
        labeled_pub_.getNumSubscribers() > 0 || foreground_pub_.getNumSubscribers() > 0;
    diagnostics_->setActive(wanted);
    if (wanted && !sub_) {
      sub_ = getNodeHandle().subscribe("velodyne_points", 2, &GridSegmentation::cloudCb, this);
    } else if (!wanted && sub_) {
      sub_.shutdown();
    }
  }

  void cloudCb(const sensor_msgs::PointCloud2ConstPtr& msg) {
    const ros::WallTime start = ros::WallTime::now();
    ros_conv::PointCloud2InputInfo info;
    std::string error;
    if (!ros_conv::fromPointCloud2(*msg, &cloud_, &info, &error)) {
      NODELET_ERROR_THROTTLE(5.0, "GridSegmentation: dropping velodyne_points: %s",
                             error.c_str());
      diagnostics_->rejected();
      return;
    }
    if (!info.has_ring || !info.has_time) {
      NODELET_INFO_ONCE("GridSegmentation: input has no ring/time fields (e.g. KITTI); "
                        "they are set to 0");
    }
    std::lock_guard<std::mutex> segment_lock(segment_mutex_);  // vs. reconfigureCb
    segmenter_->segment(cloud_, &labels_);
    const core::SegmentationStats& s = segmenter_->stats();
    if (s.points_unknown > 0) {
      NODELET_DEBUG_THROTTLE(5.0, "GridSegmentation: %u non-finite or out-of-range points",
                             s.points_unknown);
    }
    if (labeled_pub_.getNumSubscribers() > 0) {
      auto labeled = boost::make_shared<LabeledCloud>();
      core::buildLabeledCloud(cloud_, labels_, labeled.get());
      labeled_pub_.publish(boost::shared_ptr<const LabeledCloud>(labeled));
    }
    if (foreground_pub_.getNumSubscribers() > 0) {
      auto foreground = boost::make_shared<LabeledCloud>();
      core::extractForeground(cloud_, labels_, foreground.get());
      foreground_pub_.publish(boost::shared_ptr<const LabeledCloud>(foreground));
    }
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
  }

  using ReconfigureServer = dynamic_reconfigure::Server<GridSegmentationConfig>;
  std::unique_ptr<core::GridSegmenter> segmenter_;
  std::mutex segment_mutex_;                   // segmenter_ between frames and reconfigure
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<ReconfigureServer> reconfigure_;
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  CloudXYZIRT cloud_;                     // scratch: converted input
  std::vector<core::SegmentClass> labels_;  // scratch: per-point classes
  std::mutex connect_mutex_;
  ros::Publisher labeled_pub_, foreground_pub_;
  ros::Subscriber sub_;
};

}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::GridSegmentation, nodelet::Nodelet)
