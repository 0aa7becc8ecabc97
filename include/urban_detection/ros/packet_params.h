/// \file packet_params.h
/// Parameters of the PacketSource and PacketToCloud nodelets and their loaders.
///
/// config/packet_source.yaml and config/packet_to_cloud.yaml mirror these structs field by field
/// (parameter name = field name without the unit suffix where noted).
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "urban_detection/core/common/param_fields.h"

#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/ros/param_loading.h"

namespace urban_detection {
namespace ros_conv {

/// urban_detection/PacketSource: live UDP socket or pcap replay -> VelodyneScan per revolution.
struct PacketSourceParams {
  int port = 2368;                     // [1..65535] UDP port of the sensor's data packets
  std::string device_ip;               // IPv4 sender to accept; empty = any sender
  int rcvbuf_bytes = 8 * 1024 * 1024;  // [bytes] socket receive buffer (bursts, slow readers)
  std::string pcap;                    // replay this capture instead of the socket (param `pcap`)
  double rate = 1.0;                   // [-] replay speed factor; 0 = as fast as possible
  bool loop = false;                   // replay the capture forever
  bool use_pcap_time = false;          // stamp with capture time instead of "now"-based time
  double cut_angle_deg = 0.0;         // [deg] azimuth where one revolution ends (param `cut_angle`)
  double rpm = 600.0;                 // [rev/min] 300..1200 spin rate: expected revolution rate
                                      //     and size (revolutions are still cut by azimuth)
  std::string frame_id = "velodyne";  // header.frame_id of the scans
  int queue_size = 10;                // [messages] publisher queue
  bool timestamp_first_packet = false;  // header.stamp = first packet's stamp (velodyne_driver's
                                        //     parameter); false: the last packet's
  // Streaming decoding (`velodyne_points` published by this nodelet, lazily): each packet is
  // decoded as it arrives, so a revolution's cloud is out one packet after its last packet.
  bool decode = false;          // advertise velodyne_points and decode while listened
  std::string calibration;      // YAML or db.xml calibration; empty = nominal HDL-64E S2
  core::DecoderParams decoder;  // params `min_range`, `max_range` [m]
  // [packets] 0 = off; with decode, the points of the open revolution are also published on
  // velodyne_points/sectors every this many packets (lazily): the segmentation bins them into
  // its grid while the revolution arrives (36 packets: about 1/16 revolution at 600 rpm).
  int sector_packets = 36;

  /// Revolutions per second the sensor (or the replay at `rate`) should deliver [Hz].
  double expectedRevolutionRateHz() const;
  /// Packets in one revolution at `rpm` (one packet per 288 us whatever the spin rate).
  std::size_t expectedPacketsPerRevolution() const;
};

/// urban_detection/PacketToCloud: VelodyneScan -> CloudXYZIRT.
struct PacketToCloudParams {
  std::string calibration;      // YAML or db.xml calibration file; empty = nominal HDL-64E S2
  core::DecoderParams decoder;  // params `min_range`, `max_range` [m]
  std::string fixed_frame;      // if set, per-packet motion compensation through this frame
  std::string target_frame;     // output frame; empty = the scan's frame
  double tf_timeout_s = 0.1;    // [s] how long to wait for the transforms of a revolution
  int queue_size = 2;           // [messages] input queue; small so the newest revolution wins
  // [packets] larger VelodyneScans are refused undecoded (default: three revolutions at 300 rpm)
  int max_packets_per_scan = static_cast<int>(core::RevolutionBoundary::kMaxPacketsPerRevolution);
};

/// "" when valid: the table's ranges, then device_ip (IPv4 or empty), frame_id (not empty) and
/// min_range < max_range.
std::string validate(const PacketSourceParams& params);
/// "" when valid: the table's ranges, then min_range < max_range.
std::string validate(const PacketToCloudParams& params);

/// Read the private parameters (loadFields: every field of the table below); throw ParamError
/// naming the parameter and its accepted range.
PacketSourceParams loadPacketSourceParams(const ros::NodeHandle& private_nh);
PacketToCloudParams loadPacketToCloudParams(const ros::NodeHandle& private_nh);

}  // namespace ros_conv
}  // namespace urban_detection

/// PacketSourceParams' field table (core/common/param_fields.h); config/packet_source.yaml.
template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::PacketSourceParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"port", "", 1, 65535, "UDP port of the sensor's data packets"}, p.port);
    f({"device_ip", "accept only this IPv4 sender; empty: any sender"}, p.device_ip);
    f({"rcvbuf_bytes", "bytes", 64 * 1024, 512 * 1024 * 1024,
       "socket receive buffer (the kernel caps it at net.core.rmem_max)"},
      p.rcvbuf_bytes);
    f({"pcap", "replay this capture instead of the live socket"}, p.pcap);
    f({"rate", "", 0.0, 1000.0, "replay speed factor; 0: as fast as possible"}, p.rate);
    f({"loop", "replay the capture forever"}, p.loop);
    f({"use_pcap_time", "stamps are the capture times (false: shifted to start now)"},
      p.use_pcap_time);
    f({"cut_angle", "deg", 0.0, 360.0, "azimuth where a revolution ends"}, p.cut_angle_deg);
    f({"rpm", "rev/min", 300.0, 1200.0, "spin rate: expected revolution rate and size"}, p.rpm);
    f({"frame_id", "header.frame_id of the scans (not empty)"}, p.frame_id);
    f({"queue_size", "messages", 1, 1000, "publisher queue"}, p.queue_size);
    f({"timestamp_first_packet", "header.stamp of a revolution: its first packet's (false: last)"},
      p.timestamp_first_packet);
    f({"decode", "advertise velodyne_points, decoded packet by packet while listened"}, p.decode);
    f({"calibration", "YAML or db.xml calibration (with decode); empty: nominal HDL-64E S2"},
      p.calibration);
    ParamFields<DecoderParams>::visit(p.decoder, f);
    f({"sector_packets", "packets", 0, 10000,
       "with decode: the open revolution's new points on velodyne_points/sectors every this "
       "many packets (0: off)"},
      p.sector_packets);
  }
};

/// PacketToCloudParams' field table (core/common/param_fields.h); config/packet_to_cloud.yaml.
template <>
struct urban_detection::core::ParamFields<urban_detection::ros_conv::PacketToCloudParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"calibration", "YAML or db.xml calibration; empty: nominal HDL-64E S2"}, p.calibration);
    ParamFields<DecoderParams>::visit(p.decoder, f);
    f({"fixed_frame", "set (e.g. odom): per-packet motion compensation through it"}, p.fixed_frame);
    f({"target_frame", "output frame; empty: the scan's frame"}, p.target_frame);
    f({"tf_timeout", "s", 0.0, 10.0, "wait for the transforms of one revolution"}, p.tf_timeout_s);
    f({"queue_size", "messages", 1, 100, "input queue; small so the newest revolution wins"},
      p.queue_size);
    f({"max_packets_per_scan", "packets", 1, 1000000, "larger VelodyneScans are refused undecoded"},
      p.max_packets_per_scan);
  }
};
