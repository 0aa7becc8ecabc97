/// \file packet_params.h
/// Parameters of the PacketSource and PacketToCloud nodelets and their loaders.
///
/// config/packet_source.yaml and config/packet_to_cloud.yaml mirror these structs field by field
/// (parameter name = field name without the unit suffix where noted).
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "urban_detection/core/hdl64e_packet.h"
#include "urban_detection/ros/param_loading.h"

namespace urban_detection {

/// urban_detection/PacketSource: live UDP socket or pcap replay -> VelodyneScan per revolution.
struct PacketSourceParams {
  int port = 2368;                       // [1..65535] UDP port of the sensor's data packets
  std::string device_ip;                 // IPv4 sender to accept; empty = any sender
  int rcvbuf_bytes = 8 * 1024 * 1024;    // [bytes] socket receive buffer (bursts, slow readers)
  std::string pcap;                      // replay this capture instead of the socket (param `pcap`)
  double rate = 1.0;                     // [-] replay speed factor; 0 = as fast as possible
  bool loop = false;                     // replay the capture forever
  bool use_pcap_time = false;            // stamp with capture time instead of "now"-based time
  double cut_angle_deg = 0.0;            // [deg] azimuth where one revolution ends (param `cut_angle`)
  double rpm = 600.0;                    // [rev/min] 300..1200 spin rate: expected revolution rate
                                         //     and size (revolutions are still cut by azimuth)
  std::string frame_id = "velodyne";     // header.frame_id of the scans
  int queue_size = 10;                   // [messages] publisher queue

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
};

/// Read the private parameters; throw ParamError naming the parameter and its accepted range.
PacketSourceParams loadPacketSourceParams(const ros::NodeHandle& private_nh);
PacketToCloudParams loadPacketToCloudParams(const ros::NodeHandle& private_nh);

}  // namespace urban_detection
