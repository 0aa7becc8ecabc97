#include "urban_detection/ros/packet_params.h"

#include <arpa/inet.h>

#include <cmath>

namespace urban_detection {
namespace ros_conv {

std::string validate(const PacketSourceParams& p) {
  std::string error = core::checkFieldRanges(p);
  in_addr addr{};
  if (error.empty() && !p.device_ip.empty() && inet_pton(AF_INET, p.device_ip.c_str(), &addr) != 1)
    error = "parameter 'device_ip' = '" + p.device_ip +
            "' is not an IPv4 address (or empty for any sender)";
  if (error.empty() && p.frame_id.empty()) error = "parameter 'frame_id' must not be empty";
  return error.empty() ? core::validate(p.decoder) : error;
}

std::string validate(const PacketToCloudParams& p) {
  const std::string error = core::checkFieldRanges(p);
  return error.empty() ? core::validate(p.decoder) : error;
}

PacketSourceParams loadPacketSourceParams(const ros::NodeHandle& nh) {
  PacketSourceParams p;
  loadFields(nh, &p);
  return p;
}

PacketToCloudParams loadPacketToCloudParams(const ros::NodeHandle& nh) {
  PacketToCloudParams p;
  loadFields(nh, &p);
  return p;
}

double PacketSourceParams::expectedRevolutionRateHz() const {
  const double sensor_hz = rpm / 60.0;
  if (pcap.empty()) return sensor_hz;
  return rate > 0.0 ? sensor_hz * rate : 0.0;  // as fast as possible: no expectation
}

std::size_t PacketSourceParams::expectedPacketsPerRevolution() const {
  const double packet_period_s = core::kBlocksPerPacket / 2 * core::kFiringPeriodS;
  return static_cast<std::size_t>(std::lround(60.0 / rpm / packet_period_s));
}

}  // namespace ros_conv
}  // namespace urban_detection
