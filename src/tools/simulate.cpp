// urban_detection_simulate: runs a simulated HDL-64E drive offline and writes a pcap, a bag
// (velodyne_msgs/VelodyneScan + GroundTruth + tf) and/or a ground-truth file, for N revolutions.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include <ros/package.h>
#include <ros/time.h>

#include "urban_detection/core/sensor/pcap_io.h"
#include "urban_detection/core/simulation/ground_truth.h"
#include "urban_detection/core/simulation/simulation_config.h"
#include "urban_detection/ros/simulation_conversions.h"

#include "tool_common.h"

namespace ud = urban_detection;

namespace {

void usage() {
  std::printf(
      "usage: urban_detection_simulate [options]\n"
      "  --config FILE        drive description (default: the package's config/demo_drive.yaml)\n"
      "  --revolutions N      revolutions to simulate (default: the whole drive)\n"
      "  --pcap FILE          write the packets as a pcap (UDP 2368)\n"
      "  --bag FILE           write /velodyne_packets, /ground_truth, /tf, /tf_static\n"
      "  --gt FILE            write the ground-truth file (format: "
      "core/simulation/ground_truth.h)\n"
      "  --calibration FILE   override the config's calibration (velodyne YAML or db.xml)\n"
      "  --seed N             override the scene seed\n"
      "  --rpm R              override the spin rate (300..1200)\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string config_path;
  std::string pcap_path, bag_path, gt_path, calibration_path;
  long revolutions = -1, seed = -1;
  double rpm = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return urban_detection::tools::optionValue(argc, argv, &i, a.c_str()); };
    auto number = [&] { return urban_detection::tools::optionNumber(argc, argv, &i, a.c_str()); };
    auto count = [&] { return urban_detection::tools::optionCount(argc, argv, &i, a.c_str()); };
    if (a == "--config")
      config_path = value();
    else if (a == "--revolutions")
      revolutions = count();
    else if (a == "--pcap")
      pcap_path = value();
    else if (a == "--bag")
      bag_path = value();
    else if (a == "--gt")
      gt_path = value();
    else if (a == "--calibration")
      calibration_path = value();
    else if (a == "--seed")
      seed = count();
    else if (a == "--rpm")
      rpm = number();
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      usage();
      return 2;
    }
  }
  if (pcap_path.empty() && bag_path.empty() && gt_path.empty()) {
    std::fprintf(stderr, "nothing to write: give at least one of --pcap, --bag, --gt\n");
    usage();
    return 2;
  }
  if (config_path.empty()) {
    const std::string pkg = ros::package::getPath("urban_detection");
    if (pkg.empty()) {
      std::fprintf(stderr,
                   "package urban_detection not found (source devel/setup.bash) and no "
                   "--config given\n");
      return 2;
    }
    config_path = pkg + "/config/demo_drive.yaml";
  }
  try {
    ud::core::SimulationConfig c = ud::core::loadSimulationConfig(config_path);
    if (!calibration_path.empty()) c.calibration_file = calibration_path;
    if (seed >= 0) c.scene.seed = static_cast<std::uint64_t>(seed);
    if (rpm > 0.0) c.sensor.rpm = rpm;
    const ud::core::Calibration cal = ud::core::loadCalibration(c.calibration_file);
    ud::core::LidarSimulator sim(ud::core::generateScene(c.scene, c.drive), c.scene, c.drive, cal,
                                 c.sensor);
    const std::size_t n =
        revolutions > 0 ? static_cast<std::size_t>(revolutions) : sim.revolutionsInDrive();
    ros::Time::init();  // rosbag needs ros::Time without a master
    std::unique_ptr<ud::core::PcapWriter> pcap;
    std::unique_ptr<ud::ros_conv::SimulationBagWriter> bag;
    std::unique_ptr<ud::core::GroundTruthWriter> gt;
    if (!pcap_path.empty()) pcap = std::make_unique<ud::core::PcapWriter>(pcap_path);
    if (!bag_path.empty()) bag = std::make_unique<ud::ros_conv::SimulationBagWriter>(bag_path);
    if (!gt_path.empty()) gt = std::make_unique<ud::core::GroundTruthWriter>(gt_path);
    std::printf("simulate: %s, %zu objects, %zu revolutions at %.0f rpm, calibration: %s\n",
                config_path.c_str(), sim.scene().objects.size(), n, c.sensor.rpm,
                cal.source.c_str());
    ud::core::SimRevolution rev;
    ud::core::GroundTruthFrame frame;
    std::size_t packets = 0, points = 0;
    double sim_ms = 0.0;
    for (std::size_t r = 0; r < n; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      sim.simulateNext(&rev);
      sim_ms +=
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      packets += rev.packets.size();
      points += rev.instance_ids.size();
      if (pcap) {
        for (std::size_t i = 0; i < rev.packets.size(); ++i) {
          pcap->write(rev.packets[i], rev.packet_stamps_s[i]);
        }
      }
      if (bag) bag->write(sim, rev);
      if (gt) {
        ud::core::makeGroundTruthFrame(sim, rev, &frame);
        gt->write(frame);
      }
    }
    if (bag) bag->close();
    if (gt) gt->close();
    std::printf(
        "simulate: %zu packets, %zu points (%.0f per revolution), %.1f ms simulation per "
        "revolution\n",
        packets, points, n ? static_cast<double>(points) / n : 0.0, n ? sim_ms / n : 0.0);
    if (pcap) std::printf("  pcap: %s\n", pcap_path.c_str());
    if (bag) std::printf("  bag:  %s\n", bag_path.c_str());
    if (gt) std::printf("  ground truth: %s\n", gt_path.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "urban_detection_simulate: %s\n", e.what());
    return 1;
  }
  return 0;
}
