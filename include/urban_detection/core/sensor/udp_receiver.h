/// \file udp_receiver.h
/// Receiving HDL-64E data packets from a UDP socket (POSIX), ROS-free.
///
/// The sensor sends one 1206-byte datagram per packet, about 3,500 per second at any rpm, to
/// port 2368. The receiver binds that port, optionally accepts only one sender address, and
/// waits with a timeout so that the reading thread can be stopped cleanly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "urban_detection/core/sensor/hdl64e_packet.h"

namespace urban_detection {
namespace core {

/// Parameters of UdpReceiver.
struct UdpReceiverParams {
  int port = 2368;                     // [1..65535] local UDP port (0 = any free port)
  std::string device_ip;               // accept only this IPv4 sender; empty = any sender
  int rcvbuf_bytes = 8 * 1024 * 1024;  // [bytes] requested receive buffer (see rcvbufBytes())
};

/// A bound, non-blocking UDP socket delivering whole 1206-byte packets.
class UdpReceiver {
 public:
  /// Opens and binds the socket. Throws std::runtime_error with the system's reason (port in
  /// use, permission) or std::invalid_argument for a malformed device_ip.
  explicit UdpReceiver(const UdpReceiverParams& params);
  ~UdpReceiver();
  UdpReceiver(const UdpReceiver&) = delete;
  UdpReceiver& operator=(const UdpReceiver&) = delete;

  enum class Result {
    kPacket,       // `packet` holds a 1206-byte datagram from an accepted sender
    kTimeout,      // nothing arrived within the timeout
    kWrongSize,    // a datagram of another size arrived (dropped; its size in `size`)
    kOtherSender,  // a datagram from a sender other than device_ip (dropped)
    kError,        // the socket reported an error (errno text in lastError())
  };

  /// Returns the next datagram, waiting at most `timeout_ms` [ms] when none is queued.
  Result receive(RawPacket* packet, int timeout_ms, std::size_t* size = nullptr);

  /// Port actually bound (useful with port 0).
  int port() const { return port_; }
  /// Receive buffer size granted by the kernel [bytes], as Linux reports it: twice the
  /// requested size (the kernel reserves half for bookkeeping), or less when capped by
  /// net.core.rmem_max for an unprivileged process.
  int rcvbufBytes() const { return rcvbuf_bytes_; }
  const std::string& lastError() const { return last_error_; }
  /// Datagrams the kernel dropped because the receive buffer was full (the reader fell behind
  /// the sender, e.g. a flood), as of the last datagram received (SO_RXQ_OVFL). Drops are only
  /// learnt when a later datagram arrives.
  std::uint64_t kernelDrops() const { return kernel_drops_; }

 private:
  int fd_ = -1;
  int port_ = 0;
  int rcvbuf_bytes_ = 0;
  bool filter_sender_ = false;
  std::uint32_t device_addr_ = 0;  // network byte order
  std::string last_error_;
  std::uint64_t kernel_drops_ = 0;
  std::uint32_t last_kernel_drops_ = 0;  // the kernel's 32-bit counter at the last datagram
};

}  // namespace core
}  // namespace urban_detection
