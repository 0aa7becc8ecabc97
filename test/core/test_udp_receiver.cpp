// UdpReceiver on 127.0.0.1: whole packets, wrong sizes, sender filter, bounded timeouts.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "urban_detection/core/sensor/udp_receiver.h"

namespace urban_detection {
namespace core {
namespace {

using Result = UdpReceiver::Result;

// Sends datagrams to 127.0.0.1:port from a socket bound to `from_ip` (any 127/8 address works on
// Linux loopback, which lets the sender filter be tested without a second host).
class Sender {
 public:
  explicit Sender(const char* from_ip = "127.0.0.1") {
    fd_ = socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    inet_pton(AF_INET, from_ip, &local.sin_addr);
    bind(fd_, reinterpret_cast<sockaddr*>(&local), sizeof(local));
  }
  ~Sender() { close(fd_); }
  void send(int port, const std::vector<std::uint8_t>& bytes) {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    ASSERT_EQ(
        sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)),
        static_cast<ssize_t>(bytes.size()));
  }

 private:
  int fd_;
};

std::vector<std::uint8_t> pattern(std::size_t size) {
  std::vector<std::uint8_t> bytes(size);
  for (std::size_t i = 0; i < size; ++i) bytes[i] = static_cast<std::uint8_t>(i * 7 + 3);
  return bytes;
}

TEST(UdpReceiver, DeliversWholePacketsAndRejectsOtherSizes) {
  UdpReceiver receiver(UdpReceiverParams{0, "", 1 << 20});
  ASSERT_GT(receiver.port(), 0);
  EXPECT_GE(receiver.rcvbufBytes(), 64 * 1024);
  Sender sender;
  sender.send(receiver.port(), pattern(100));
  sender.send(receiver.port(), pattern(kPacketSize));
  sender.send(receiver.port(), pattern(1300));
  sender.send(receiver.port(), pattern(kPacketSize - 1));

  RawPacket packet{};
  std::size_t size = 0;
  EXPECT_EQ(receiver.receive(&packet, 1000, &size), Result::kWrongSize);
  EXPECT_EQ(size, 100u);
  ASSERT_EQ(receiver.receive(&packet, 1000, &size), Result::kPacket);
  EXPECT_EQ(size, kPacketSize);
  const std::vector<std::uint8_t> expected = pattern(kPacketSize);
  EXPECT_TRUE(std::equal(packet.begin(), packet.end(), expected.begin()));
  EXPECT_EQ(receiver.receive(&packet, 1000, &size), Result::kWrongSize);
  EXPECT_EQ(size, 1300u);  // true length reported although only 1207 bytes were read
  EXPECT_EQ(receiver.receive(&packet, 1000, &size), Result::kWrongSize);
  EXPECT_EQ(size, kPacketSize - 1);
}

// Linux grants twice the requested size; without CAP_NET_ADMIN the request is capped at
// net.core.rmem_max first, with it (SO_RCVBUFFORCE) it is not.
TEST(UdpReceiver, ReceiveBufferIsSizedForBursts) {
  std::ifstream file("/proc/sys/net/core/rmem_max");
  long rmem_max = 0;
  if (!(file >> rmem_max)) GTEST_SKIP() << "no /proc/sys/net/core/rmem_max";
  const int request = 8 * 1024 * 1024;
  UdpReceiver receiver(UdpReceiverParams{0, "", request});
  // Unprivileged: exactly the capped size; with CAP_NET_ADMIN: the full request.
  const long capped = 2 * std::min<long>(request, rmem_max);
  EXPECT_TRUE(receiver.rcvbufBytes() == capped || receiver.rcvbufBytes() == 2L * request)
      << receiver.rcvbufBytes() << " bytes, rmem_max " << rmem_max;
  EXPECT_GE(receiver.rcvbufBytes(), capped);
}

TEST(UdpReceiver, TimesOutWithinTheBound) {
  UdpReceiver receiver(UdpReceiverParams{0, "", 1 << 20});
  RawPacket packet{};
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(receiver.receive(&packet, 50), Result::kTimeout);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(elapsed_s, 0.04);
  EXPECT_LT(elapsed_s, 1.0);
}

TEST(UdpReceiver, FiltersBySenderAddress) {
  UdpReceiver receiver(UdpReceiverParams{0, "127.0.0.2", 1 << 20});
  Sender stranger("127.0.0.1"), device("127.0.0.2");
  stranger.send(receiver.port(), pattern(kPacketSize));
  device.send(receiver.port(), pattern(kPacketSize));
  RawPacket packet{};
  EXPECT_EQ(receiver.receive(&packet, 1000), Result::kOtherSender);
  EXPECT_EQ(receiver.receive(&packet, 1000), Result::kPacket);
}

// A flood into a small receive buffer that nobody reads: every datagram is either delivered
// or counted as a kernel drop, exactly (loopback loses nothing else). The count travels with
// the next datagram queued after the drops, hence the one extra packet.
TEST(UdpReceiver, CountsKernelDropsOfAFlood) {
  UdpReceiver receiver(UdpReceiverParams{0, "", 64 * 1024});
  Sender sender;
  const int sent = 2000;  // ~2.4 MB of payload into a buffer of ~128 kB
  for (int i = 0; i < sent; ++i) sender.send(receiver.port(), pattern(kPacketSize));
  RawPacket packet{};
  int delivered = 0;
  while (receiver.receive(&packet, 100) == Result::kPacket) ++delivered;
  ASSERT_GT(delivered, 0);
  ASSERT_LT(delivered, sent) << "the buffer was expected to overflow";
  EXPECT_EQ(receiver.kernelDrops(), 0u) << "drops are only known from a later datagram";
  sender.send(receiver.port(), pattern(kPacketSize));
  ASSERT_EQ(receiver.receive(&packet, 1000), Result::kPacket);
  EXPECT_EQ(receiver.kernelDrops(), static_cast<std::uint64_t>(sent - delivered));
}

TEST(UdpReceiver, RejectsBadConfiguration) {
  EXPECT_THROW(UdpReceiver(UdpReceiverParams{0, "not-an-ip", 1 << 20}), std::invalid_argument);
  EXPECT_THROW(UdpReceiver(UdpReceiverParams{70000, "", 1 << 20}), std::invalid_argument);
  UdpReceiver first(UdpReceiverParams{0, "", 1 << 20});
  // A second receiver on the same port fails with the system's reason rather than silently
  // taking a share of the packets.
  try {
    UdpReceiver second(UdpReceiverParams{first.port(), "", 1 << 20});
    ADD_FAILURE() << "second bind on port " << first.port() << " succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(first.port())), std::string::npos);
  }
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
