// urban_detection_kitti_to_bag: a folder of KITTI velodyne .bin scans or PCD sweeps -> a bag of
// sensor_msgs/PointCloud2 (x y z intensity ring time, as PacketToCloud publishes) on
// velodyne_points at a fixed rate, plus the static transform base_link -> velodyne on
// /tf_static, so that bag.launch plays a real drive through the pipeline exactly like a
// recording of decoded clouds.
//
// KITTI's sweeps are already motion compensated and carry no ring or per-point time: both are
// written as 0. The vehicle's motion is written (odom -> base_link on /tf, one per sweep) only
// when it is known: a SemanticKITTI / KITTI odometry sequence folder (poses.txt, calib.txt,
// times.txt beside velodyne/) gives each scan's pose by its file number. Without poses no
// odom transform is written at all, so nothing downstream mistakes the moving sensor for a
// standing one (the tracker then works in the sensor frame and says so).
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <pcl_conversions/pcl_conversions.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "tool_common.h"
#include "urban_detection/core/evaluation/eval_datasets.h"

namespace ud = urban_detection;

namespace {

void usage() {
  std::printf(
      "usage: urban_detection_kitti_to_bag INPUT OUTPUT.bag [options]\n"
      "  INPUT                a folder of KITTI .bin or .pcd sweeps (sorted by name), or one file\n"
      "  --rate HZ            sweep rate (default 10, KITTI's HDL-64E)\n"
      "  --start SECONDS      stamp of the first sweep (default 1317000000, a KITTI-era epoch)\n"
      "  --repeat N           write the sequence N times back to back (default 1)\n"
      "  --max N              convert at most N sweeps per pass (default: all)\n"
      "  --frame-id NAME      sensor frame of the clouds (default velodyne)\n"
      "  --base-frame NAME    vehicle frame (default base_link)\n"
      "  --odom-frame NAME    fixed frame (default odom)\n"
      "  --sensor-height M    base_link -> sensor z offset [m] (default 1.73, KITTI)\n"
      "  --topic NAME         cloud topic (default velodyne_points)\n"
      "  --poses DIR          a KITTI odometry / SemanticKITTI sequence folder (poses.txt, "
      "calib.txt,\n"
      "                       optional times.txt): write odom -> base_link per scan (scan number "
      "=\n"
      "                       file name); default: INPUT's parent when INPUT is such a velodyne/\n"
      "  --no-poses           write no odom transform even when poses are found\n");
}

struct Pose {
  double t[3] = {0, 0, 0};
  double q[4] = {0, 0, 0, 1};  // x y z w
};

Pose toPose(const Eigen::Isometry3d& m) {
  Pose p;
  const Eigen::Quaterniond q(m.rotation());
  for (int k = 0; k < 3; ++k) p.t[k] = m.translation()[k];
  p.q[0] = q.x();
  p.q[1] = q.y();
  p.q[2] = q.z();
  p.q[3] = q.w();
  return p;
}

// The scan number of a KITTI file name (000042.bin -> 42), -1 when it is not a number.
long scanNumber(const std::string& path) {
  const std::string stem = std::filesystem::path(path).stem().string();
  if (stem.empty() || stem.size() > 9 || stem.find_first_not_of("0123456789") != std::string::npos)
    return -1;
  return std::stol(stem);
}

// times.txt: one time [s] per scan; empty when absent or malformed.
std::vector<double> readTimes(const std::string& path) {
  std::vector<double> times;
  std::ifstream in(path);
  double t;
  while (in >> t) times.push_back(t);
  if (!in.eof()) times.clear();
  return times;
}

geometry_msgs::TransformStamped makeTransform(const ros::Time& stamp, const std::string& parent,
                                              const std::string& child, const Pose& p) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = p.t[0];
  t.transform.translation.y = p.t[1];
  t.transform.translation.z = p.t[2];
  t.transform.rotation.x = p.q[0];
  t.transform.rotation.y = p.q[1];
  t.transform.rotation.z = p.q[2];
  t.transform.rotation.w = p.q[3];
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional;
  double rate_hz = 10.0, start_s = 1317000000.0, sensor_height_m = 1.73;
  long repeat = 1, max_sweeps = -1;
  std::string frame_id = "velodyne", base_frame = "base_link", odom_frame = "odom";
  std::string topic = "velodyne_points", poses_dir;
  bool no_poses = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return urban_detection::tools::optionValue(argc, argv, &i, a.c_str()); };
    auto number = [&] { return urban_detection::tools::optionNumber(argc, argv, &i, a.c_str()); };
    auto count = [&] { return urban_detection::tools::optionCount(argc, argv, &i, a.c_str()); };
    if (a == "--rate")
      rate_hz = number();
    else if (a == "--start")
      start_s = number();
    else if (a == "--repeat")
      repeat = count();
    else if (a == "--max")
      max_sweeps = count();
    else if (a == "--frame-id")
      frame_id = value();
    else if (a == "--base-frame")
      base_frame = value();
    else if (a == "--odom-frame")
      odom_frame = value();
    else if (a == "--sensor-height")
      sensor_height_m = number();
    else if (a == "--topic")
      topic = value();
    else if (a == "--poses")
      poses_dir = value();
    else if (a == "--no-poses")
      no_poses = true;
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      usage();
      return 2;
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() != 2) {
    usage();
    return 2;
  }
  if (!(rate_hz > 0.0 && rate_hz <= 100.0) || !(start_s > 0.0) || repeat < 1 ||
      !std::isfinite(sensor_height_m) || frame_id.empty() || base_frame.empty() ||
      odom_frame.empty() || topic.empty()) {
    std::fprintf(stderr,
                 "invalid option value: --rate in (0, 100] Hz, --start > 0 s, --repeat "
                 ">= 1, finite --sensor-height, non-empty frame names\n");
    return 2;
  }
  if (topic.front() != '/') topic = "/" + topic;  // as a recorder stores it
  std::error_code ec;
  if (!std::filesystem::exists(positional[0], ec)) {
    std::fprintf(stderr, "input not found: %s\n", positional[0].c_str());
    return 1;
  }
  const std::vector<std::string> files = ud::tools::listSweeps(positional[0]);
  if (files.empty()) {
    std::fprintf(stderr, "no .bin or .pcd sweep in %s\n", positional[0].c_str());
    return 1;
  }
  const std::size_t n =
      max_sweeps > 0 ? std::min(files.size(), static_cast<std::size_t>(max_sweeps)) : files.size();

  // Ego poses: an explicit --poses folder must have them; the default is INPUT's parent when
  // that is a sequence folder (SemanticKITTI's sequences/NN/velodyne).
  if (poses_dir.empty() && !no_poses) {
    const std::filesystem::path in = std::filesystem::absolute(positional[0], ec);
    const std::filesystem::path dir = std::filesystem::is_directory(in, ec) ? in : in.parent_path();
    if (dir.filename() == "velodyne" &&
        std::filesystem::is_regular_file(dir.parent_path() / "poses.txt", ec)) {
      poses_dir = dir.parent_path().string();
    }
  }
  std::vector<Eigen::Isometry3d> poses;  // world_T_velodyne per scan number
  std::vector<double> times;             // [s] per scan number (times.txt), may be empty
  std::vector<long> scan(n, -1);
  if (!poses_dir.empty() && !no_poses) {
    bool nominal_tr = false;
    std::string error;
    if (!ud::core::readSemanticKittiPoses(poses_dir, &poses, &nominal_tr, &error)) {
      std::fprintf(stderr, "--poses: %s\n", error.c_str());
      return 1;
    }
    for (std::size_t i = 0; i < n; ++i) {
      scan[i] = scanNumber(files[i]);
      if (scan[i] < 0 || static_cast<std::size_t>(scan[i]) >= poses.size()) {
        std::fprintf(stderr, "%s: no pose in %s/poses.txt (scan number from the file name)\n",
                     files[i].c_str(), poses_dir.c_str());
        return 1;
      }
    }
    times = readTimes(poses_dir + "/times.txt");
    if (times.size() < poses.size()) times.clear();
    std::printf("kitti_to_bag: ego poses from %s/poses.txt (%s; stamps from %s)\n",
                poses_dir.c_str(),
                nominal_tr ? "calib.txt has no Tr: nominal KITTI LiDAR axes" : "calib.txt Tr",
                times.empty() ? "--rate" : "times.txt");
  }
  const bool have_poses = !poses.empty();

  ros::Time::init();
  try {
    rosbag::Bag bag(positional[1], rosbag::bagmode::Write);
    const ros::Time start(start_s);
    Pose mount;
    mount.t[2] = sensor_height_m;
    tf2_msgs::TFMessage statics;
    statics.transforms.push_back(makeTransform(start, base_frame, frame_id, mount));
    bag.write("/tf_static", start, statics);

    // odom is base_link at the first written scan: odom_T_base = M * V0^-1 * Vi * M^-1 with
    // M = base_T_velodyne (the mount) and Vi = world_T_velodyne of scan i.
    Eigen::Isometry3d base_T_velo = Eigen::Isometry3d::Identity();
    base_T_velo.translation().z() = sensor_height_m;
    const Eigen::Isometry3d odom_T_world =
        have_poses ? base_T_velo * poses[static_cast<std::size_t>(scan[0])].inverse()
                   : Eigen::Isometry3d::Identity();
    // Stamp offsets [s] of the slots of one pass, and the length of a pass.
    std::vector<double> offset(n);
    for (std::size_t i = 0; i < n; ++i) {
      offset[i] = times.empty() ? static_cast<double>(i) / rate_hz
                                : times[static_cast<std::size_t>(scan[i])] -
                                      times[static_cast<std::size_t>(scan[0])];
    }
    const double pass_s = offset[n - 1] + 1.0 / rate_hz;

    ud::CloudXYZIRT cloud;
    sensor_msgs::PointCloud2 msg;
    std::size_t written = 0, skipped = 0, points = 0;
    for (long pass = 0; pass < repeat; ++pass) {
      for (std::size_t i = 0; i < n; ++i) {
        std::string error;
        if (!ud::tools::readSweep(files[i], &cloud, &error)) {
          std::fprintf(stderr, "skipping %s: %s\n", files[i].c_str(), error.c_str());
          ++skipped;
          continue;
        }
        // Stamps advance over every slot (also skipped ones) so the rate stays the sensor's.
        const ros::Time stamp(start_s + static_cast<double>(pass) * pass_s + offset[i]);
        cloud.header.frame_id = frame_id;
        cloud.is_dense = false;
        pcl::toROSMsg(cloud, msg);
        msg.header.stamp = stamp;
        msg.header.frame_id = frame_id;
        if (have_poses) {
          const Eigen::Isometry3d odom_T_base =
              odom_T_world * poses[static_cast<std::size_t>(scan[i])] * base_T_velo.inverse();
          tf2_msgs::TFMessage tf;
          tf.transforms.push_back(
              makeTransform(stamp, odom_frame, base_frame, toPose(odom_T_base)));
          bag.write("/tf", stamp, tf);
        }
        bag.write(topic, stamp, msg);
        ++written;
        points += cloud.size();
      }
    }
    bag.close();
    std::printf(
        "kitti_to_bag: %zu sweeps (%zu points, %zu unreadable skipped) at %.1f Hz -> %s "
        "(%s, frame %s; tf %s -> %s%s)\n",
        written, points, skipped, rate_hz, positional[1].c_str(), topic.c_str(), frame_id.c_str(),
        base_frame.c_str(), frame_id.c_str(),
        have_poses ? (", " + odom_frame + " -> " + base_frame + " per sweep").c_str()
                   : "; no ego poses: no odom transform, tracks stay in the sensor frame");
    return written > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "urban_detection_kitti_to_bag: %s\n", e.what());
    return 1;
  }
}
