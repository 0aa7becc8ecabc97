// ROS glue of the image -> object label transfer: image and CameraInfo conversions, the objects'
// classes out of and into DetectedObjectArray, class names and colours on the markers. No ROS
// master.
#include <gtest/gtest.h>

#include <cmath>

#include "urban_detection/ros/image_label_transfer_ros.h"
#include "urban_detection/ros/object_markers.h"

namespace urban_detection {
namespace {

sensor_msgs::Image makeImage(const std::string& encoding, int channels) {
  sensor_msgs::Image m;
  m.encoding = encoding;
  m.width = 3;
  m.height = 2;
  m.step = 3 * channels + 2;  // padded rows
  m.data.assign(m.step * m.height, 0);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      for (int c = 0; c < channels; ++c)
        m.data[y * m.step + x * channels + c] = 10 * (y * 3 + x) + c;
  return m;
}

TEST(ImageToBgr, EncodingsAndPaddedRows) {
  cv::Mat scratch, bgr;
  std::string error;
  const auto bgr8 = makeImage("bgr8", 3);
  ASSERT_TRUE(ros_conv::imageToBgr(bgr8, &scratch, &bgr, &error)) << error;
  EXPECT_EQ(bgr.data, bgr8.data.data());  // wrapped, not copied
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 2), cv::Vec3b(50, 51, 52));
  const auto rgb8 = makeImage("rgb8", 3);
  ASSERT_TRUE(ros_conv::imageToBgr(rgb8, &scratch, &bgr, &error));
  EXPECT_EQ(bgr.at<cv::Vec3b>(1, 2), cv::Vec3b(52, 51, 50));  // channels swapped
  const auto rgba8 = makeImage("rgba8", 4);
  ASSERT_TRUE(ros_conv::imageToBgr(rgba8, &scratch, &bgr, &error));
  EXPECT_EQ(bgr.channels(), 3);
  EXPECT_EQ(bgr.at<cv::Vec3b>(0, 1), cv::Vec3b(12, 11, 10));
  const auto mono = makeImage("mono8", 1);
  ASSERT_TRUE(ros_conv::imageToBgr(mono, &scratch, &bgr, &error));
  EXPECT_EQ(bgr.at<std::uint8_t>(1, 1), 40);
}

TEST(ImageToBgr, RejectsBadImages) {
  cv::Mat scratch, bgr;
  std::string error;
  auto m = makeImage("bgr8", 3);
  m.data.resize(m.data.size() - 1);  // truncated
  EXPECT_FALSE(ros_conv::imageToBgr(m, &scratch, &bgr, &error));
  EXPECT_NE(error.find("data bytes"), std::string::npos) << error;
  m = makeImage("bgr8", 3);
  m.step = 5;  // shorter than a row
  EXPECT_FALSE(ros_conv::imageToBgr(m, &scratch, &bgr, &error));
  m = makeImage("bgr8", 3);
  m.encoding = "16UC1";
  EXPECT_FALSE(ros_conv::imageToBgr(m, &scratch, &bgr, &error));
  EXPECT_NE(error.find("16UC1"), std::string::npos);
  m.encoding = "bgr8";
  m.width = 0;
  EXPECT_FALSE(ros_conv::imageToBgr(m, &scratch, &bgr, &error));
}

TEST(CameraFromInfo, UsesPThenK) {
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  info.K = {500, 0, 320, 0, 505, 240, 0, 0, 1};
  core::PinholeCamera cam;
  std::string error;
  ASSERT_TRUE(ros_conv::cameraFromInfo(info, &cam, &error)) << error;
  EXPECT_DOUBLE_EQ(cam.projection(1, 1), 505.0);
  EXPECT_DOUBLE_EQ(cam.projection(0, 3), 0.0);
  info.P = {400, 0, 300, -40, 0, 400, 200, 0, 0, 0, 1, 0};
  ASSERT_TRUE(ros_conv::cameraFromInfo(info, &cam, &error));
  EXPECT_DOUBLE_EQ(cam.projection(0, 0), 400.0);
  EXPECT_DOUBLE_EQ(cam.projection(0, 3), -40.0);
  EXPECT_EQ(cam.width_px, 640);
  // A point 10 m ahead, 1 m right: u = (400 * 1 + 300 * 10 - 40) / 10 = 336.
  double u = 0, v = 0;
  ASSERT_TRUE(cam.project({1, 0, 10}, 0.1, &u, &v));
  EXPECT_DOUBLE_EQ(u, 336.0);
  EXPECT_DOUBLE_EQ(v, 200.0);
  info.width = 0;
  EXPECT_FALSE(ros_conv::cameraFromInfo(info, &cam, &error));
  info.width = 640;
  info.P[0] = std::nan("");
  EXPECT_FALSE(ros_conv::cameraFromInfo(info, &cam, &error));
}

// The objects' classes out of and back into the message: labels by position, vetoed objects
// left out with their ids and indices untouched (objects/points still refers to them).
TEST(ClassLabels, RoundTripThroughTheMessage) {
  DetectedObjectArray in;
  in.header.frame_id = "velodyne";
  in.detector = "hierarchical_grid";
  for (std::uint32_t id = 1; id <= 3; ++id) {
    DetectedObject o;
    o.id = id;
    o.class_label = "vehicle";
    o.class_confidence = 0.6f;
    o.indices = {id, id + 10};
    in.objects.push_back(o);
  }
  std::vector<core::ObjectClassLabel> labels;
  ros_conv::toClassLabels(in, &labels);
  ASSERT_EQ(labels.size(), 3u);
  EXPECT_EQ(labels[2].id, 3u);
  EXPECT_EQ(labels[2].class_label, "vehicle");
  EXPECT_FLOAT_EQ(labels[2].class_confidence, 0.6f);
  EXPECT_FALSE(labels[2].vetoed);
  labels[0].class_label = "car";
  labels[0].class_confidence = 0.9f;
  labels[1].vetoed = true;
  DetectedObjectArray out;
  ros_conv::applyClassLabels(in, labels, &out);
  EXPECT_EQ(out.header.frame_id, "velodyne");
  EXPECT_EQ(out.detector, "hierarchical_grid");
  ASSERT_EQ(out.objects.size(), 2u);
  EXPECT_EQ(out.objects[0].class_label, "car");
  EXPECT_FLOAT_EQ(out.objects[0].class_confidence, 0.9f);
  EXPECT_EQ(out.objects[1].id, 3u);
  EXPECT_EQ(out.objects[1].class_label, "vehicle");
  EXPECT_EQ(out.objects[1].indices, (std::vector<std::uint32_t>{3, 13}));
}

TEST(ObjectMarkersClasses, ClassNameConfidenceAndColour) {
  DetectedObjectArray objects;
  DetectedObject a;
  a.id = 3;
  a.class_label = "car";
  a.class_confidence = 0.866f;
  a.obb_pose.orientation.w = 1.0;
  a.obb_dimensions.x = a.obb_dimensions.y = a.obb_dimensions.z = 1.0;
  DetectedObject b = a;
  b.id = 4;
  b.class_label = "unknown";
  objects.objects = {a, b};
  ros_conv::ObjectMarkerParams p;
  p.show_legend = false;
  visualization_msgs::MarkerArray m;
  ros_conv::buildObjectMarkers(objects, p, &m);
  ASSERT_EQ(m.markers.size(), 5u);
  // Cityscapes car colour (0, 0, 142).
  EXPECT_FLOAT_EQ(m.markers[1].color.r, 0.0f);
  EXPECT_FLOAT_EQ(m.markers[1].color.b, static_cast<float>(142 / 255.0));
  EXPECT_FLOAT_EQ(m.markers[1].color.a, static_cast<float>(p.box_alpha));
  EXPECT_EQ(m.markers[2].text, "3 car 0.87");
  const auto id_colour = ros_conv::colourForId(4, p.box_alpha);
  EXPECT_FLOAT_EQ(m.markers[3].color.g, id_colour.g);
  EXPECT_EQ(m.markers[4].text, "4");
  p.colour_by_class = false;
  ros_conv::buildObjectMarkers(objects, p, &m);
  EXPECT_FLOAT_EQ(m.markers[1].color.g, ros_conv::colourForId(3, p.box_alpha).g);
  // Unknown names: stable, and different names differ.
  const auto x1 = ros_conv::colourForClass("fire hydrant", 1.0);
  const auto x2 = ros_conv::colourForClass("Fire Hydrant", 1.0);
  const auto y = ros_conv::colourForClass("mailbox", 1.0);
  EXPECT_EQ(x1.r, x2.r);
  EXPECT_EQ(x1.g, x2.g);
  EXPECT_TRUE(x1.r != y.r || x1.g != y.g || x1.b != y.b);
  EXPECT_FLOAT_EQ(ros_conv::colourForClass("Pedestrian", 1.0).r, 1.0f);  // the LiDAR class's
}

}  // namespace
}  // namespace urban_detection

namespace urban_detection {
namespace {

TEST(LookupCameraFromCloud, StaticAndMovingPlatform) {
  tf2_ros::Buffer tf;
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "velodyne";
  t.child_frame_id = "camera";
  t.transform.translation.x = 1.0;  // camera 1 m ahead of the LiDAR, same orientation
  t.transform.rotation.w = 1.0;
  ASSERT_TRUE(tf.setTransform(t, "test", true));
  std_msgs::Header image, cloud;
  image.frame_id = "camera";
  image.stamp = ros::Time(100.0);
  cloud.frame_id = "velodyne";
  cloud.stamp = ros::Time(100.05);
  Eigen::Isometry3d m;
  std::string error;
  ASSERT_TRUE(ros_conv::lookupCameraFromCloud(tf, image, cloud, "", 0.0, &m, &error)) << error;
  EXPECT_TRUE((m * Eigen::Vector3d(5, 0, 0)).isApprox(Eigen::Vector3d(4, 0, 0)));
  // Moving platform: odom -> velodyne moves +1 m in x between the cloud and image stamps,
  // so a point fixed in odom seen at the cloud time lies 1 m closer at the image time.
  for (double s : {100.0, 100.05}) {
    geometry_msgs::TransformStamped o;
    o.header.frame_id = "odom";
    o.header.stamp = ros::Time(s);
    o.child_frame_id = "velodyne";
    o.transform.translation.x = s == 100.0 ? 11.0 : 10.0;
    o.transform.rotation.w = 1.0;
    ASSERT_TRUE(tf.setTransform(o, "test"));
  }
  ASSERT_TRUE(ros_conv::lookupCameraFromCloud(tf, image, cloud, "odom", 0.0, &m, &error)) << error;
  // cloud-time velodyne point (5,0,0) = odom (15,0,0) = image-time velodyne (4,0,0) = camera
  // (3,0,0)
  EXPECT_TRUE((m * Eigen::Vector3d(5, 0, 0)).isApprox(Eigen::Vector3d(3, 0, 0), 1e-9))
      << (m * Eigen::Vector3d(5, 0, 0)).transpose();
  image.frame_id = "nowhere";
  EXPECT_FALSE(ros_conv::lookupCameraFromCloud(tf, image, cloud, "", 0.0, &m, &error));
  EXPECT_NE(error.find("camera <- LiDAR"), std::string::npos);
}

// Without a mask within max_mask_gap_s (none segmented yet, or lidar mode) the objects keep their
// LiDAR classes and every object is passed on, vetoes aside.
TEST(ObjectLabelling, LidarClassesWithoutAMask) {
  DetectedObjectArray in;
  in.header.frame_id = "velodyne";
  in.header.stamp = ros::Time(50.0);
  in.detector = "hierarchical_grid";
  for (std::uint32_t id = 1; id <= 2; ++id) {
    DetectedObject o;
    o.id = id;
    o.class_label = id == 1 ? "vehicle" : "pedestrian";
    o.class_confidence = 0.7f;
    in.objects.push_back(o);
  }
  LabeledCloud points;
  points.push_back(LabeledPoint());
  core::CameraModel model;
  ros_conv::CameraMasks masks(&model.network);
  tf2_ros::Buffer tf;
  for (core::FusionMode mode :
       {core::FusionMode::kLidar, core::FusionMode::kCamera, core::FusionMode::kFused}) {
    core::CameraStageParams p;
    p.fusion.mode = mode;
    ros_conv::ObjectLabelling labelling(p, model, masks, tf);
    DetectedObjectArray out;
    std::string why_not = "stale";
    EXPECT_FALSE(labelling.label(in, points, &out, &why_not));
    EXPECT_TRUE(why_not.empty());
    EXPECT_EQ(out.header.frame_id, "velodyne");
    ASSERT_EQ(out.objects.size(), 2u);
    EXPECT_EQ(out.objects[1].class_label, "pedestrian");
    EXPECT_FLOAT_EQ(out.objects[0].class_confidence, 0.7f);
  }
}

}  // namespace
}  // namespace urban_detection
