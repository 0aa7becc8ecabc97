/// \file packet_params.h
/// Parameters of the PacketSource and PacketToCloud nodelets and their loaders.
///
/// config/packet_source.yaml and config/packet_to_cloud.yaml mirror these structs field by field
/// (parameter name = field name without the unit suffix where noted).
#pragma once

#include <ros/node_handle.h>

#include <string>

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

/// The decoder's parameters shared by PacketSource (decode: true) and PacketToCloud:
/// `calibration`, `min_range`, `max_range`; throws ParamError.
void loadDecoderParams(const ros::NodeHandle& private_nh, std::string* calibration,
                       core::DecoderParams* decoder);

/// Read the private parameters; throw ParamError naming the parameter and its accepted range.
PacketSourceParams loadPacketSourceParams(const ros::NodeHandle& private_nh);
PacketToCloudParams loadPacketToCloudParams(const ros::NodeHandle& private_nh);

}  // namespace ros_conv
}  // namespace urban_detection
