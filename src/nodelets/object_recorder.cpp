// urban_detection/ObjectRecorder: saves the detections of a live or bag run, per revolution,
// in files other tools read (ros/object_recording.h): ~output_dir/NNNNNN.label (one uint32
// per point of velodyne_points: the object holding it, 0 = none; scored by
// `urban_detection_eval --detections`), ~output_dir/kitti/NNNNNN.txt (KITTI label lines) and
// ~output_dir/objects.csv (a line per object). Revolutions are numbered in arrival order from
// ~first_index. Subscribes objects and velodyne_points (to know each revolution's point count)
// while loaded: a sink, not lazy. A missing output_dir refuses to start, naming it.
#include "urban_detection/core/common/point_types.h"

#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>

#include "urban_detection/DetectedObjectArray.h"
#include "urban_detection/ros/cloud_serialization.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/object_recording.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/stage_diagnostics.h"

namespace urban_detection {
namespace ros_conv {

class ObjectRecorderNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    try {
      loadFields(pnh, &params_);
      if (params_.output_dir.empty())
        throw ParamError("parameter '" + pnh.resolveName("output_dir") +
                         "' must name a folder to write into");
      std::error_code ec;
      std::filesystem::create_directories(params_.output_dir + "/kitti", ec);
      if (ec) {
        throw ParamError("parameter '" + pnh.resolveName("output_dir") +
                         "' = " + params_.output_dir + ": cannot create it (" + ec.message() + ")");
      }
    } catch (const ParamError& e) {
      refusal_ = ros_conv::RefusalDiagnostics::report(
          getNodeHandle(), pnh, getName(),
          "ObjectRecorder: " + std::string(e.what()) + "; the nodelet stays idle");
      return;
    }
    next_ = static_cast<std::uint64_t>(params_.first_index);
    csv_.open(params_.output_dir + "/objects.csv");
    csv_ << csvHeader() << '\n';
    diagnostics_ =
        std::make_unique<ros_conv::StageDiagnostics>(getNodeHandle(), pnh, getName(), "recorder");
    ros::NodeHandle& nh = getNodeHandle();
    cloud_sub_ = nh.subscribe("velodyne_points", 10, &ObjectRecorderNodelet::cloudCb, this);
    objects_sub_ =
        nh.subscribe("objects", params_.queue_size, &ObjectRecorderNodelet::objectsCb, this);
    NODELET_INFO("ObjectRecorder: writing revolutions into %s", params_.output_dir.c_str());
  }

  void cloudCb(const ros::MessageEvent<const CloudXYZIRT>& event) {  // zero copy
    const auto& cloud = event.getConstMessage();
    std::lock_guard<std::mutex> lock(mutex_);
    sizes_.emplace_back(cloud->header.stamp, cloud->size());  // PCL stamp [us]
    while (sizes_.size() > 50) sizes_.pop_front();
  }

  void objectsCb(const DetectedObjectArray::ConstPtr& msg) {
    const ros::WallTime start = ros::WallTime::now();
    diagnostics_->input(msg->header.seq);
    std::size_t cloud_size = 0;
    bool found = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const std::uint64_t stamp_us = msg->header.stamp.toNSec() / 1000u;
      for (const auto& s : sizes_) {
        if (s.first == stamp_us) {
          cloud_size = s.second;
          found = true;
        }
      }
    }
    std::vector<std::uint32_t> labels;
    if (!found || !instanceLabels(*msg, cloud_size, &labels)) {
      const std::string text = !found ? "objects without their cloud on velodyne_points (stamp " +
                                            std::to_string(msg->header.stamp.toSec()) + ")"
                                      : "objects whose point indices exceed their cloud";
      if (diagnostics_->error("unmatched_objects", text, 1)) {
        NODELET_ERROR("ObjectRecorder: %s: revolution not written", text.c_str());
      }
      return;
    }
    char name[32];
    std::snprintf(name, sizeof name, "%06llu", static_cast<unsigned long long>(next_));
    std::ofstream bin(params_.output_dir + "/" + name + ".label", std::ios::binary);
    bin.write(reinterpret_cast<const char*>(labels.data()),
              static_cast<std::streamsize>(labels.size() * sizeof(std::uint32_t)));
    std::ofstream kitti(params_.output_dir + "/kitti/" + name + ".txt");
    for (const DetectedObject& o : msg->objects) {
      kitti << kittiLabelLine(o) << '\n';
      csv_ << csvLine(next_, msg->header, o) << '\n';
    }
    csv_.flush();
    if (!bin || !kitti || !csv_) {
      if (diagnostics_->error("write_errors", "cannot write into " + params_.output_dir, 1)) {
        NODELET_ERROR("ObjectRecorder: cannot write revolution %s into %s", name,
                      params_.output_dir.c_str());
      }
    }
    ++next_;
    diagnostics_->frame((ros::WallTime::now() - start).toSec());
    diagnostics_->output();
  }

  ObjectRecorderParams params_;
  std::uint64_t next_ = 0;  // number of the next revolution written
  std::ofstream csv_;
  std::mutex mutex_;                                         // sizes_
  std::deque<std::pair<std::uint64_t, std::size_t>> sizes_;  // cloud stamp [us] -> points
  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;
  ros::Subscriber cloud_sub_, objects_sub_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::ObjectRecorderNodelet, nodelet::Nodelet)
