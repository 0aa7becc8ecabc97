#include "urban_detection/core/sensor/udp_receiver.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace urban_detection {
namespace core {
namespace {

std::string errnoText(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

}  // namespace

UdpReceiver::UdpReceiver(const UdpReceiverParams& params) {
  if (!params.device_ip.empty()) {
    in_addr addr{};
    if (inet_pton(AF_INET, params.device_ip.c_str(), &addr) != 1) {
      throw std::invalid_argument("device_ip '" + params.device_ip + "' is not an IPv4 address");
    }
    filter_sender_ = true;
    device_addr_ = addr.s_addr;
  }
  if (params.port < 0 || params.port > 65535) {
    throw std::invalid_argument("UDP port " + std::to_string(params.port) + " out of [0, 65535]");
  }
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(errnoText("cannot create a UDP socket"));

  // No SO_REUSEADDR: on Linux it lets several UDP sockets bind one port, and only one of them
  // would get each packet. A second receiver on the port must fail loudly instead. (UDP has no
  // TIME_WAIT, so a restarted node rebinds at once without it.)
  // A revolution is ~350 packets (~420 kB of payload, about twice that in kernel accounting) at
  // 600 rpm; a large buffer absorbs scheduling hiccups of the reading thread. SO_RCVBUF is
  // capped at net.core.rmem_max; SO_RCVBUFFORCE is not, but needs CAP_NET_ADMIN (root).
  int rcvbuf = params.rcvbuf_bytes;
  if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof(rcvbuf)) != 0) {
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof(rcvbuf));
  }
  socklen_t len = sizeof(rcvbuf_bytes_);
  getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf_bytes_, &len);
  // The kernel then attaches its count of datagrams dropped for a full receive buffer to each
  // datagram: the only way to know how many packets a flood (or a stalled reader) cost.
  const int on = 1;
  setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on));

  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(static_cast<std::uint16_t>(params.port));
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof(local)) != 0) {
    const std::string reason = errnoText("cannot bind UDP port " + std::to_string(params.port));
    close(fd_);
    throw std::runtime_error(reason);
  }
  sockaddr_in bound{};
  len = sizeof(bound);
  getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  port_ = ntohs(bound.sin_port);
  fcntl(fd_, F_SETFL, fcntl(fd_, F_GETFL) | O_NONBLOCK);
}

UdpReceiver::~UdpReceiver() {
  if (fd_ >= 0) close(fd_);
}

UdpReceiver::Result UdpReceiver::receive(RawPacket* packet, int timeout_ms, std::size_t* size) {
  // One byte more than a packet so that oversized datagrams are recognised (MSG_TRUNC makes
  // recvmsg report their true length).
  std::uint8_t buffer[kPacketSize + 1];
  sockaddr_in sender{};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(std::uint32_t))];
  for (int attempt = 0; attempt < 2; ++attempt) {
    iovec iov{buffer, sizeof(buffer)};
    msghdr msg{};
    msg.msg_name = &sender;
    msg.msg_namelen = sizeof(sender);
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof(control);
    const ssize_t n = recvmsg(fd_, &msg, MSG_TRUNC);
    if (n >= 0) {
      for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
          std::uint32_t dropped = 0;  // cumulative since the socket opened, wraps at 2^32
          std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
          kernel_drops_ += static_cast<std::uint32_t>(dropped - last_kernel_drops_);
          last_kernel_drops_ = dropped;
        }
      }
      if (size) *size = static_cast<std::size_t>(n);
      if (filter_sender_ && sender.sin_addr.s_addr != device_addr_) return Result::kOtherSender;
      if (static_cast<std::size_t>(n) != kPacketSize) return Result::kWrongSize;
      std::memcpy(packet->data(), buffer, kPacketSize);
      return Result::kPacket;
    }
    if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
      last_error_ = errnoText("recvmsg");
      return Result::kError;
    }
    if (attempt == 1) break;
    // Nothing queued: wait for data, bounded so the caller can check for shutdown.
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = poll(&pfd, 1, timeout_ms);
    if (ready == 0) return Result::kTimeout;
    if (ready < 0) {
      if (errno == EINTR) return Result::kTimeout;
      last_error_ = errnoText("poll");
      return Result::kError;
    }
  }
  return Result::kTimeout;
}

}  // namespace core
}  // namespace urban_detection
