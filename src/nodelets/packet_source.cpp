// urban_detection/PacketSource: HDL-64E packets from a live UDP socket or a pcap replay,
// published as one urban_detection/VelodyneScan per whole revolution on `velodyne_packets`
// (the partial revolutions at the start and the end of a stream are dropped). With ~decode,
// also `velodyne_points` (CloudXYZIRT), decoded packet by packet as they arrive and published
// one packet after the revolution's last (the live chain's low-latency path; PacketToCloud
// then is not needed), and every ~sector_packets packets the open revolution's new points on
// `velodyne_points/sectors` (GridSegmentation bins them while the revolution arrives). The
// outputs are lazy. The reading thread is PacketSourceWorker
// (ros/packet_source_worker.h); this file wires it to ROS.
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "urban_detection/ros/cloud_serialization.h"

#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/packet_source_worker.h"
#include "urban_detection/ros/stage_diagnostics.h"

namespace urban_detection {
namespace ros_conv {

class PacketSourceNodelet : public nodelet::Nodelet {
 public:
  ~PacketSourceNodelet() override { worker_.reset(); }  // joins the thread before the rest goes

 private:
  void onInit() override {
    PacketSourceParams params;
    try {
      params = loadPacketSourceParams(getPrivateNodeHandle());
    } catch (const std::exception& e) {  // ParamError
      refusal_ =
          ros_conv::RefusalDiagnostics::report(getNodeHandle(), getPrivateNodeHandle(), getName(),
                                               "PacketSource inactive: " + std::string(e.what()));
      return;
    }
    diagnostics_ = std::make_unique<ros_conv::StageDiagnostics>(
        getNodeHandle(), getPrivateNodeHandle(), getName(), "packets", "packets");
    diagnostics_->setExpectedRate(params.expectedRevolutionRateHz());
    pub_ = getNodeHandle().advertise<VelodyneScan>("velodyne_packets", params.queue_size);
    if (params.decode) {
      cloud_pub_ = getNodeHandle().advertise<CloudXYZIRT>("velodyne_points", params.queue_size);
      if (params.sector_packets > 0) {
        sector_pub_ = getNodeHandle().advertise<CloudXYZIRT>("velodyne_points/sectors", 64);
      }
    }
    try {
      worker_ = std::make_unique<PacketSourceWorker>(
          params, diagnostics_.get(), [this](const VelodyneScan::Ptr& scan) { pub_.publish(scan); },
          [this] { return pub_.getNumSubscribers() > 0; },
          [this](const boost::shared_ptr<CloudXYZIRT>& cloud) {
            cloud_pub_.publish(boost::shared_ptr<const CloudXYZIRT>(cloud));
          },
          [this] { return cloud_pub_ && cloud_pub_.getNumSubscribers() > 0; });
    } catch (const std::exception& e) {  // socket, file or calibration errors
      diagnostics_.reset();              // no OK status beside the refusal's ERROR
      refusal_ =
          ros_conv::RefusalDiagnostics::report(getNodeHandle(), getPrivateNodeHandle(), getName(),
                                               "PacketSource inactive: " + std::string(e.what()));
      return;
    }
    worker_->setSectorOutput(
        [this](const boost::shared_ptr<CloudXYZIRT>& sector) {
          sector_pub_.publish(boost::shared_ptr<const CloudXYZIRT>(sector));
        },
        [this] { return sector_pub_ && sector_pub_.getNumSubscribers() > 0; });
    diagnostics_->setHardwareId(worker_->describe());
    const std::string decoding = params.decode ? "; streaming decoding, calibration " +
                                                     worker_->decoder()->calibration().source
                                               : "";
    NODELET_INFO(
        "PacketSource: %s, %.0f rpm (%.1f revolutions/s expected), stamped with the "
        "%s packet of a revolution%s",
        worker_->describe().c_str(), params.rpm, params.expectedRevolutionRateHz(),
        params.timestamp_first_packet ? "first" : "last", decoding.c_str());
    if (!worker_->warning().empty()) NODELET_WARN("PacketSource: %s", worker_->warning().c_str());
    worker_->start();
  }

  std::unique_ptr<ros_conv::StageDiagnostics> diagnostics_;
  std::unique_ptr<ros_conv::RefusalDiagnostics> refusal_;  // set when it refused to start
  ros::Publisher pub_, cloud_pub_, sector_pub_;
  std::unique_ptr<PacketSourceWorker> worker_;
};

}  // namespace ros_conv
}  // namespace urban_detection

PLUGINLIB_EXPORT_CLASS(urban_detection::ros_conv::PacketSourceNodelet, nodelet::Nodelet)
