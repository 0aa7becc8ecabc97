// urban_detection_udp_replay: sends the HDL-64E packets of a pcap as UDP datagrams to a port on
// this machine at the recorded pace, as the sensor does (the input of `scripts/run latency`).
// Pacing is by absolute deadlines on the monotonic clock, so a late packet does not shift the
// ones after it; with --loop the capture restarts one nominal packet gap after its last packet.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>
#include <csignal>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "urban_detection/core/sensor/pcap_io.h"

#include "tool_common.h"

namespace ud = urban_detection;

namespace {

void usage() {
  std::printf(
      "usage: urban_detection_udp_replay --pcap FILE [options]\n"
      "  --port N        destination UDP port on 127.0.0.1 (default 2368)\n"
      "  --host ADDR     destination IPv4 address (default 127.0.0.1)\n"
      "  --rate F        pace factor, 1 = recorded pace (default 1)\n"
      "  --duration S    stop after S seconds (default: one pass, or for ever with --loop)\n"
      "  --loop          restart the capture at its end\n"
      "  --start-delay S wait S seconds before the first packet (default 0)\n"
      "Prints one JSON line on stderr at the end (also when stopped by SIGINT or SIGTERM):\n"
      "packets sent, send errors, packets more than 1 ms behind their deadline, and the worst\n"
      "lateness.\n");
}

volatile std::sig_atomic_t g_stop = 0;
void onStopSignal(int) {
  g_stop = 1;
}

std::int64_t nowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

void sleepUntilNs(std::int64_t deadline) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline / 1000000000LL);
  ts.tv_nsec = static_cast<long>(deadline % 1000000000LL);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR && !g_stop) {
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string pcap_path, host = "127.0.0.1";
  long port = 2368;
  double rate = 1.0, duration_s = -1.0, start_delay_s = 0.0;
  bool loop = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--pcap")
      pcap_path = ud::tools::optionValue(argc, argv, &i, "--pcap");
    else if (a == "--host")
      host = ud::tools::optionValue(argc, argv, &i, "--host");
    else if (a == "--port")
      port = ud::tools::optionCount(argc, argv, &i, "--port");
    else if (a == "--rate")
      rate = ud::tools::optionNumber(argc, argv, &i, "--rate");
    else if (a == "--duration")
      duration_s = ud::tools::optionNumber(argc, argv, &i, "--duration");
    else if (a == "--start-delay")
      start_delay_s = ud::tools::optionNumber(argc, argv, &i, "--start-delay");
    else if (a == "--loop")
      loop = true;
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "error: unknown option %s\n", a.c_str());
      usage();
      return 2;
    }
  }
  if (pcap_path.empty() || port < 1 || port > 65535 || !(rate > 0.0) || start_delay_s < 0.0) {
    std::fprintf(stderr,
                 "error: needs --pcap, a port in 1..65535, --rate > 0, --start-delay >= 0\n");
    return 2;
  }
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, host.c_str(), &to.sin_addr) != 1) {
    std::fprintf(stderr, "error: --host '%s' is not an IPv4 address\n", host.c_str());
    return 2;
  }
  struct sigaction stop_action {};
  stop_action.sa_handler = onStopSignal;  // no SA_RESTART: the pacing sleep returns at once
  sigaction(SIGINT, &stop_action, nullptr);
  sigaction(SIGTERM, &stop_action, nullptr);
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) {
    std::fprintf(stderr, "error: socket: %s\n", std::strerror(errno));
    return 1;
  }
  try {
    ud::core::PcapReader reader(pcap_path, 2368);
    ud::core::PcapPacket packet;
    constexpr double kNominalGapS = 1.0 / 3472.0;  // HDL-64E: 3472 packets/s (datasheet)
    const std::int64_t start = nowNs() + static_cast<std::int64_t>(start_delay_s * 1e9);
    const std::int64_t stop =
        duration_s >= 0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : INT64_MAX;
    double first_s = 0, last_s = 0, pass_shift_s = 0;
    bool have_first = false;
    std::size_t sent = 0, errors = 0, late = 0, in_pass = 0;
    std::int64_t worst_late_ns = 0;
    while (!g_stop) {
      const ud::core::PcapReader::Result r = reader.next(&packet);
      if (r != ud::core::PcapReader::Result::kPacket) {
        if (r == ud::core::PcapReader::Result::kTruncated) {
          std::fprintf(stderr, "warning: %s is truncated; replaying what precedes it\n",
                       pcap_path.c_str());
        }
        if (!loop || in_pass == 0) break;
        pass_shift_s += (last_s - first_s) + kNominalGapS;
        reader.rewind();
        in_pass = 0;
        continue;
      }
      if (!have_first) {
        first_s = packet.stamp_s;
        have_first = true;
      }
      ++in_pass;
      last_s = packet.stamp_s;
      const double offset_s = (packet.stamp_s - first_s + pass_shift_s) / rate;
      const std::int64_t deadline = start + static_cast<std::int64_t>(offset_s * 1e9);
      if (deadline >= stop) break;
      sleepUntilNs(deadline);
      if (g_stop) break;
      const std::int64_t lateness = nowNs() - deadline;
      if (lateness > 1000000) ++late;
      if (lateness > worst_late_ns) worst_late_ns = lateness;
      if (sendto(fd, packet.data.data(), packet.data.size(), 0,
                 reinterpret_cast<const sockaddr*>(&to),
                 sizeof(to)) != static_cast<ssize_t>(packet.data.size())) {
        ++errors;
      } else {
        ++sent;
      }
    }
    close(fd);
    std::fprintf(stderr,
                 "{\"packets_sent\": %zu, \"send_errors\": %zu, \"late_over_1ms\": %zu, "
                 "\"worst_lateness_ms\": %.3f}\n",
                 sent, errors, late, static_cast<double>(worst_late_ns) * 1e-6);
    return sent > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    close(fd);
    return 1;
  }
}
