// urban_detection_latency_probe: a ROS node measuring how long after its header.stamp each
// message of the given topics arrives (for the pipeline's outputs: the time from the last
// packet of a revolution, which stamps it, to the subscriber). Writes p50/p95/p99/max, the
// message count and rate per topic as JSON after a warm-up and a measuring window. Used by
// `scripts/run latency`; works on any ROS graph whose stamps are on this machine's clock.
// For object topics also the latency of each object from its own last point: the sensor sweeps
// clockwise (azimuth atan2(-y, x)) from --cut-deg over --revolution-s ending at header.stamp,
// so the object's last point was swept at the azimuth of its axis-aligned box corner swept
// last (an upper bound on its points', so the figure is a lower bound by at most the box's
// angular extent); recorded under "<topic> per object". A --stamped-objects topic (objects/early)
// publishes one object per message stamped at the object's own last point, so there each
// object's latency is its message's: the topic's own figures, no second record.
// Also keeps the last /diagnostics status of every stage reporting a processing time, and writes
// its timing, rate and skip figures under "stages" (where a latency figure comes from).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include "urban_detection/DetectedObjectArray.h"

#include "tool_common.h"

namespace ud = urban_detection;

namespace {

void usage() {
  std::printf(
      "usage: urban_detection_latency_probe [options]\n"
      "  --objects TOPIC   a DetectedObjectArray topic (repeatable; default: objects)\n"
      "  --stamped-objects TOPIC  a DetectedObjectArray topic whose messages are stamped at\n"
      "                    their objects' last point (objects/early; repeatable)\n"
      "  --markers TOPIC   a MarkerArray topic, stamp of its first marker (repeatable;\n"
      "                    default: objects/markers)\n"
      "  --warmup S        seconds ignored after the first message of every topic (default 5)\n"
      "  --duration S      measuring window [s] (default 60)\n"
      "  --out FILE        JSON output (default: stdout)\n"
      "  --revolution-s S  [s] sweep time of a revolution, for the per-object figures\n"
      "                    (default 0.1: 600 rpm)\n"
      "  --cut-deg D       [deg] azimuth where revolutions are cut (default 0)\n"
      "Exit status 1 when a topic delivered nothing in the window.\n");
}

struct TopicRecord {
  std::vector<double> latency_ms;
  std::size_t zero_stamps = 0;
  ros::WallTime first, last;
};

class Probe {
 public:
  Probe(double warmup_s) : warmup_s_(warmup_s) {}

  void record(const std::string& topic, const ros::Time& stamp) {
    const ros::Time now = ros::Time::now();
    const ros::WallTime wall = ros::WallTime::now();
    std::lock_guard<std::mutex> lock(mutex_);
    if (start_.isZero()) start_ = wall;
    if ((wall - start_).toSec() < warmup_s_) return;
    TopicRecord& r = records_[topic];
    if (stamp.isZero()) {
      ++r.zero_stamps;
      return;
    }
    if (r.latency_ms.empty()) r.first = wall;
    r.last = wall;
    r.latency_ms.push_back(
        1e-6 * (static_cast<double>(now.toNSec()) - static_cast<double>(stamp.toNSec())));
  }

  void diagnostics(const diagnostic_msgs::DiagnosticArray& array) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const diagnostic_msgs::DiagnosticStatus& status : array.status) {
      std::vector<std::pair<std::string, std::string>> kept;
      bool is_stage = false;
      for (const diagnostic_msgs::KeyValue& kv : status.values) {
        is_stage = is_stage || kv.key == "mean processing time [ms]";
        if (kv.key.find("[ms]") != std::string::npos || kv.key.find("[Hz]") != std::string::npos ||
            kv.key == "skipped_revolutions" || kv.key.rfind("revolutions binned", 0) == 0) {
          kept.emplace_back(kv.key, kv.value);
        }
      }
      if (is_stage) stages_[status.name] = kept;
    }
  }

  // Each object's latency from its last point (see the file comment).
  void recordObjects(const std::string& topic, const ud::DetectedObjectArray& m,
                     double revolution_s, double cut_deg) {
    double header_ms = 0.0;
    std::lock_guard<std::mutex> lock(mutex_);
    TopicRecord* record = objectsRecord(topic, m, &header_ms);
    if (!record) return;
    TopicRecord& r = *record;
    for (const auto& o : m.objects) {
      const double cx = o.aabb_pose.position.x, cy = o.aabb_pose.position.y;
      const double hx = 0.5 * o.aabb_dimensions.x, hy = 0.5 * o.aabb_dimensions.y;
      double last = 0.0;  // fraction of the sweep at the box corner swept last
      for (int k = 0; k < 4; ++k) {
        const double x = cx + (k & 1 ? hx : -hx), y = cy + (k & 2 ? hy : -hy);
        double deg = std::atan2(-y, x) * 180.0 / M_PI - cut_deg;
        deg = std::fmod(std::fmod(deg, 360.0) + 360.0, 360.0);
        last = std::max(last, deg / 360.0);
      }
      r.latency_ms.push_back(header_ms + 1e3 * revolution_s * (1.0 - last));
    }
  }

  // Objects of a message stamped at their own last point: each one's latency is the message's.
  // The record of `topic` for an objects message arriving now (its age from its stamp in
  // *header_ms), or null when it is not recorded (warm-up, no stamp, no objects). Under mutex_.
  TopicRecord* objectsRecord(const std::string& topic, const ud::DetectedObjectArray& m,
                             double* header_ms) {
    const ros::Time now = ros::Time::now();
    const ros::WallTime wall = ros::WallTime::now();
    if (m.header.stamp.isZero() || m.objects.empty()) return nullptr;
    if (start_.isZero() || (wall - start_).toSec() < warmup_s_) return nullptr;
    TopicRecord& r = records_[topic];
    if (r.latency_ms.empty()) r.first = wall;
    r.last = wall;
    *header_ms =
        1e-6 * (static_cast<double>(now.toNSec()) - static_cast<double>(m.header.stamp.toNSec()));
    return &r;
  }

  bool started() {
    std::lock_guard<std::mutex> lock(mutex_);
    return !start_.isZero() && (ros::WallTime::now() - start_).toSec() >= warmup_s_;
  }

  // Returns false when a topic has no measurement.
  bool write(const std::vector<std::string>& topics, double duration_s, std::FILE* out) {
    std::lock_guard<std::mutex> lock(mutex_);
    bool all = true;
    std::fprintf(out, "{\"warmup_s\": %.1f, \"duration_s\": %.1f, \"topics\": {", warmup_s_,
                 duration_s);
    for (std::size_t t = 0; t < topics.size(); ++t) {
      TopicRecord& r = records_[topics[t]];
      std::vector<double>& l = r.latency_ms;
      std::sort(l.begin(), l.end());
      auto q = [&l](double p) {
        return l[static_cast<std::size_t>(p * static_cast<double>(l.size() - 1) + 0.5)];
      };
      const double span_s = l.size() > 1 ? (r.last - r.first).toSec() : 0.0;
      std::fprintf(out, "%s\"%s\": {\"messages\": %zu, \"zero_stamps\": %zu", t ? ", " : "",
                   topics[t].c_str(), l.size(), r.zero_stamps);
      if (l.empty()) {
        all = all && topics[t].find(" per object") != std::string::npos;
      } else {
        std::fprintf(out,
                     ", \"rate_hz\": %.3f, \"p50_ms\": %.3f, \"p95_ms\": %.3f, \"p99_ms\": %.3f, "
                     "\"max_ms\": %.3f, \"min_ms\": %.3f",
                     span_s > 0 ? static_cast<double>(l.size() - 1) / span_s : 0.0, q(0.5), q(0.95),
                     q(0.99), l.back(), l.front());
      }
      std::fprintf(out, "}");
    }
    std::fprintf(out, "}, \"stages\": {");
    bool first_stage = true;
    for (const auto& stage : stages_) {
      std::fprintf(out, "%s\"%s\": {", first_stage ? "" : ", ", stage.first.c_str());
      first_stage = false;
      for (std::size_t k = 0; k < stage.second.size(); ++k) {
        char* end = nullptr;
        const double v = std::strtod(stage.second[k].second.c_str(), &end);
        const bool numeric = end && *end == '\0' && !stage.second[k].second.empty();
        std::fprintf(out, numeric ? "%s\"%s\": %.3f" : "%s\"%s\": null", k ? ", " : "",
                     stage.second[k].first.c_str(), numeric ? v : 0.0);
      }
      std::fprintf(out, "}");
    }
    std::fprintf(out, "}}\n");
    return all;
  }

 private:
  double warmup_s_;
  std::mutex mutex_;
  ros::WallTime start_;
  std::map<std::string, TopicRecord> records_;
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> stages_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "latency_probe", ros::init_options::AnonymousName);
  std::vector<std::string> objects, markers, stamped;
  double warmup_s = 5.0, duration_s = 60.0, revolution_s = 0.1, cut_deg = 0.0;
  std::string out_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--objects")
      objects.push_back(ud::tools::optionValue(argc, argv, &i, "--objects"));
    else if (a == "--stamped-objects")
      stamped.push_back(ud::tools::optionValue(argc, argv, &i, "--stamped-objects"));
    else if (a == "--markers")
      markers.push_back(ud::tools::optionValue(argc, argv, &i, "--markers"));
    else if (a == "--warmup")
      warmup_s = ud::tools::optionNumber(argc, argv, &i, "--warmup");
    else if (a == "--duration")
      duration_s = ud::tools::optionNumber(argc, argv, &i, "--duration");
    else if (a == "--revolution-s")
      revolution_s = ud::tools::optionNumber(argc, argv, &i, "--revolution-s");
    else if (a == "--cut-deg")
      cut_deg = ud::tools::optionNumber(argc, argv, &i, "--cut-deg");
    else if (a == "--out")
      out_path = ud::tools::optionValue(argc, argv, &i, "--out");
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "error: unknown option %s\n", a.c_str());
      usage();
      return 2;
    }
  }
  if (warmup_s < 0 || duration_s <= 0) {
    std::fprintf(stderr, "error: --warmup >= 0 and --duration > 0 needed\n");
    return 2;
  }
  if (objects.empty() && markers.empty() && stamped.empty()) {
    objects.push_back("objects");
    markers.push_back("objects/markers");
  }
  ros::NodeHandle nh;
  Probe probe(warmup_s);
  std::vector<ros::Subscriber> subs;
  std::vector<std::string> topics;
  for (const std::string& t : objects) {
    const std::string name = nh.resolveName(t);
    const std::string per_object = name + " per object";
    topics.push_back(name);
    topics.push_back(per_object);
    subs.push_back(nh.subscribe<ud::DetectedObjectArray>(
        t, 10,
        [&probe, name, per_object, revolution_s,
         cut_deg](const ud::DetectedObjectArray::ConstPtr& m) {
          probe.record(name, m->header.stamp);
          probe.recordObjects(per_object, *m, revolution_s, cut_deg);
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
  }
  for (const std::string& t : stamped) {
    const std::string name = nh.resolveName(t);
    topics.push_back(name);
    subs.push_back(nh.subscribe<ud::DetectedObjectArray>(
        t, 256,
        [&probe, name](const ud::DetectedObjectArray::ConstPtr& m) {
          probe.record(name, m->header.stamp);
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
  }
  for (const std::string& t : markers) {
    const std::string name = nh.resolveName(t);
    topics.push_back(name);
    subs.push_back(nh.subscribe<visualization_msgs::MarkerArray>(
        t, 10,
        [&probe, name](const visualization_msgs::MarkerArray::ConstPtr& m) {
          for (const visualization_msgs::Marker& marker : m->markers) {
            if (!marker.header.stamp.isZero()) {
              probe.record(name, marker.header.stamp);
              return;
            }
          }
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
  }
  subs.push_back(nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 50,
      [&probe](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) { probe.diagnostics(*m); }));
  ros::AsyncSpinner spinner(1);
  spinner.start();
  while (ros::ok() && !probe.started()) ros::WallDuration(0.05).sleep();
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(duration_s);
  while (ros::ok() && ros::WallTime::now() < until) ros::WallDuration(0.05).sleep();
  spinner.stop();
  std::FILE* out = out_path.empty() ? stdout : std::fopen(out_path.c_str(), "w");
  if (!out) {
    std::fprintf(stderr, "error: cannot write %s\n", out_path.c_str());
    return 1;
  }
  const bool ok = probe.write(topics, duration_s, out);
  if (out != stdout) std::fclose(out);
  if (!ok) std::fprintf(stderr, "latency_probe: a topic delivered nothing in the window\n");
  return ok ? 0 : 1;
}
