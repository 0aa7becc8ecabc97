// urban_detection_camera_replay: a camera for the camera stage without a camera. It
// publishes one KITTI object frame's left colour image (image_2) over and over, stamped now,
// with its CameraInfo (P = P2) and the static tf camera <- LiDAR of its calibration
// (R0_rect * Tr_velo_to_cam), so ImageLabelTransfer runs its network on real images at a camera
// rate next to the LiDAR chain (scripts/latency.sh --camera measures the chain with it).
//
//   urban_detection_camera_replay --kitti DIR [--frame 000000] [--rate 10] [--lidar-frame velodyne]
//                                 [--camera-frame camera_optical] [--duration S]
// Topics: camera/image_rect_color (bgr8), camera/camera_info.
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <Eigen/Geometry>
#include <boost/make_shared.hpp>
#include <cstdio>
#include <string>

#include "tool_common.h"
#include "urban_detection/core/spark/kitti_spark_eval.h"

namespace ud = urban_detection;

int main(int argc, char** argv) {
  ros::init(argc, argv, "camera_replay", ros::init_options::AnonymousName);
  std::string dir, frame = "000000", lidar_frame = "velodyne", camera_frame = "camera_optical";
  double rate_hz = 10.0, duration_s = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--kitti")
      dir = ud::tools::optionValue(argc, argv, &i, "--kitti");
    else if (a == "--frame")
      frame = ud::tools::optionValue(argc, argv, &i, "--frame");
    else if (a == "--rate")
      rate_hz = ud::tools::optionNumber(argc, argv, &i, "--rate");
    else if (a == "--duration")
      duration_s = ud::tools::optionNumber(argc, argv, &i, "--duration");
    else if (a == "--lidar-frame")
      lidar_frame = ud::tools::optionValue(argc, argv, &i, "--lidar-frame");
    else if (a == "--camera-frame")
      camera_frame = ud::tools::optionValue(argc, argv, &i, "--camera-frame");
    else {
      std::fprintf(stderr,
                   "usage: urban_detection_camera_replay --kitti DIR [--frame 000000] [--rate 10] "
                   "[--lidar-frame velodyne] [--camera-frame camera_optical] [--duration S]\n");
      return 2;
    }
  }
  if (dir.empty() || !(rate_hz > 0.0 && rate_hz <= 100.0)) {
    std::fprintf(stderr, "error: --kitti DIR is required and --rate must be in (0, 100] Hz\n");
    return 2;
  }
  ud::core::KittiSparkFrame f;
  std::string error;
  if (!ud::core::loadKittiSparkFrame(dir, frame, true, &f, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  ros::NodeHandle nh;
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("camera/image_rect_color", 1);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("camera/camera_info", 1);
  tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped t;  // the camera's pose in the LiDAR frame
  t.header.stamp = ros::Time::now();
  t.header.frame_id = lidar_frame;
  t.child_frame_id = camera_frame;
  const Eigen::Isometry3d velo_from_camera = f.camera_from_velo.inverse();
  const Eigen::Quaterniond q(velo_from_camera.linear());
  t.transform.translation.x = velo_from_camera.translation().x();
  t.transform.translation.y = velo_from_camera.translation().y();
  t.transform.translation.z = velo_from_camera.translation().z();
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  tf.sendTransform(t);

  sensor_msgs::Image image;
  image.header.frame_id = camera_frame;
  image.width = static_cast<std::uint32_t>(f.image.cols);
  image.height = static_cast<std::uint32_t>(f.image.rows);
  image.encoding = "bgr8";
  image.step = image.width * 3;
  image.data.resize(static_cast<std::size_t>(image.step) * image.height);
  for (int y = 0; y < f.image.rows; ++y)
    std::copy(f.image.ptr<std::uint8_t>(y), f.image.ptr<std::uint8_t>(y) + image.step,
              image.data.begin() + static_cast<long>(y) * image.step);
  sensor_msgs::CameraInfo info;
  info.header.frame_id = camera_frame;
  info.width = image.width;
  info.height = image.height;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) info.P[r * 4 + c] = f.calib.p2(r, c);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) info.K[r * 3 + c] = f.calib.p2(r, c);
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};

  ros::Rate rate(rate_hz);
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(duration_s);
  while (ros::ok() && (duration_s <= 0.0 || ros::WallTime::now() < end)) {
    auto img = boost::make_shared<sensor_msgs::Image>(image);
    auto ci = boost::make_shared<sensor_msgs::CameraInfo>(info);
    img->header.stamp = ci->header.stamp = ros::Time::now();
    info_pub.publish(ci);
    image_pub.publish(img);
    ros::spinOnce();
    rate.sleep();
  }
  return 0;
}
