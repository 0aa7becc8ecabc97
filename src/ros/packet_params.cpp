#include "urban_detection/ros/packet_params.h"

#include <arpa/inet.h>

#include <cmath>

namespace urban_detection {
namespace ros_conv {

PacketSourceParams loadPacketSourceParams(const ros::NodeHandle& nh) {
  PacketSourceParams p;
  loadParam(nh, "port", &p.port, 1, 65535);
  loadParam(nh, "device_ip", &p.device_ip);
  in_addr addr{};
  if (!p.device_ip.empty() && inet_pton(AF_INET, p.device_ip.c_str(), &addr) != 1) {
    throw ParamError("parameter '" + nh.resolveName("device_ip") + "' = '" + p.device_ip +
                     "' is not an IPv4 address (or empty for any sender)");
  }
  loadParam(nh, "rcvbuf_bytes", &p.rcvbuf_bytes, 64 * 1024, 512 * 1024 * 1024, "bytes");
  loadParam(nh, "pcap", &p.pcap);
  loadParam(nh, "rate", &p.rate, 0.0, 1000.0, "(0 = as fast as possible)");
  loadParam(nh, "loop", &p.loop);
  loadParam(nh, "use_pcap_time", &p.use_pcap_time);
  loadParam(nh, "cut_angle", &p.cut_angle_deg, 0.0, 360.0, "deg");
  loadParam(nh, "rpm", &p.rpm, 300.0, 1200.0, "rev/min");
  loadParam(nh, "frame_id", &p.frame_id);
  if (p.frame_id.empty())
    throw ParamError("parameter '" + nh.resolveName("frame_id") + "' must not be empty");
  loadParam(nh, "queue_size", &p.queue_size, 1, 1000);
  loadParam(nh, "timestamp_first_packet", &p.timestamp_first_packet);
  loadParam(nh, "decode", &p.decode);
  if (p.decode) loadDecoderParams(nh, &p.calibration, &p.decoder);
  loadParam(nh, "sector_packets", &p.sector_packets, 0, 10000, "packets (0 = off)");
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

void loadDecoderParams(const ros::NodeHandle& nh, std::string* calibration,
                       core::DecoderParams* decoder) {
  loadParam(nh, "calibration", calibration);
  loadParam(nh, "min_range", &decoder->min_range_m, 0.0, 250.0, "m");
  loadParam(nh, "max_range", &decoder->max_range_m, 0.1, 250.0, "m");
  if (decoder->min_range_m >= decoder->max_range_m) {
    std::ostringstream msg;
    msg << "parameters '" << nh.resolveName("min_range") << "' = " << decoder->min_range_m
        << " and '" << nh.resolveName("max_range") << "' = " << decoder->max_range_m
        << ": accepted min_range < max_range";
    throw ParamError(msg.str());
  }
}

PacketToCloudParams loadPacketToCloudParams(const ros::NodeHandle& nh) {
  PacketToCloudParams p;
  loadDecoderParams(nh, &p.calibration, &p.decoder);
  loadParam(nh, "fixed_frame", &p.fixed_frame);
  loadParam(nh, "target_frame", &p.target_frame);
  loadParam(nh, "tf_timeout", &p.tf_timeout_s, 0.0, 10.0, "s");
  loadParam(nh, "queue_size", &p.queue_size, 1, 100);
  loadParam(nh, "max_packets_per_scan", &p.max_packets_per_scan, 1, 1000000, "packets");
  return p;
}

}  // namespace ros_conv
}  // namespace urban_detection
