// ImageLabelTransfer nodelet: refusal without a model (launched by the real launch file), then a
// second instance loaded into this process with nodelet::Loader, configured from
// config/image_label_transfer.yaml (loaded by the .test file) and the colour network of
// test/spark_colour_model.py built here. A synthetic camera (static tf from the LiDAR frame)
// sees a red and a green region; objects projecting there must come back as car / vegetation.
// Then fusion: fused confirms, vetoes and keeps unseen objects; bad encodings and a
// missing tf leave the LiDAR classes and the stage running.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <gtest/gtest.h>
#include <nodelet/NodeletList.h>
#include <nodelet/loader.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <unistd.h>
#include <visualization_msgs/MarkerArray.h>
#include "urban_detection/ros/cloud_serialization.h"

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <mutex>
#include <thread>

#include "rostest_util.h"
#include "urban_detection/DetectedObjectArray.h"

namespace urban_detection {
namespace {

using rostest_util::waitFor;

TEST(ImageLabelTransferNodelet, LaunchFileWithoutModelRefusesToStart) {
  ros::NodeHandle nh;
  DetectedObjectArray::ConstPtr got;
  ros::Subscriber sub = nh.subscribe<DetectedObjectArray>(
      "objects/classified", 1,
      boost::function<void(const DetectedObjectArray::ConstPtr&)>(
          [&](const DetectedObjectArray::ConstPtr& m) { got = m; }));
  ros::Subscriber markers = nh.subscribe<visualization_msgs::MarkerArray>(
      "objects/classified/markers", 1,
      boost::function<void(const visualization_msgs::MarkerArray::ConstPtr&)>(
          [](const visualization_msgs::MarkerArray::ConstPtr&) {}));
  // The marker nodelet of the same launch file comes up; the transfer nodelet never advertises.
  EXPECT_TRUE(waitFor([&] { return markers.getNumPublishers() > 0; }, 20.0));
  // The transfer nodelet is loaded in the manager (onInit ran and refused), it just never
  // advertises its output.
  nodelet::NodeletList list;
  EXPECT_TRUE(waitFor(
      [&] {
        if (!ros::service::call("/urban_detection_manager/list", list)) return false;
        for (const auto& n : list.response.nodelets)
          if (n == "/image_label_transfer") return true;
        return false;
      },
      20.0));
  ros::Duration(1.0).sleep();
  EXPECT_EQ(sub.getNumPublishers(), 0u);
  EXPECT_EQ(got, nullptr);
}

struct Scene {
  explicit Scene(const std::string& ns = "ilt") : nh(ns) {}
  ros::NodeHandle nh;
  std::string encoding = "rgb8", camera_frame = "camera_optical", lidar_class = "unknown";
  float lidar_confidence = 0.0f;
  ros::Publisher image, info, objects, points;
  std::mutex mutex;
  std::vector<DetectedObjectArray::ConstPtr> received;

  // objects/classified into `received`.
  ros::Subscriber collect() {
    return nh.subscribe<DetectedObjectArray>(
        "objects/classified", 5,
        boost::function<void(const DetectedObjectArray::ConstPtr&)>(
            [this](const DetectedObjectArray::ConstPtr& m) {
              std::lock_guard<std::mutex> lock(mutex);
              received.push_back(m);
            }));
  }

  void advertise() {
    image = nh.advertise<sensor_msgs::Image>("image", 2);
    info = nh.advertise<sensor_msgs::CameraInfo>("camera_info", 2);
    objects = nh.advertise<DetectedObjectArray>("objects", 2);
    points = nh.advertise<LabeledCloud>("objects/points", 2);
  }

  // 100 x 80 camera, f = 50 px, principal point (50, 40): LiDAR (x, y, z) -> u = 50 - 50 y / x,
  // v = 40 - 50 z / x. Left half red (car), right half green (vegetation).
  void publish(const ros::Time& stamp) {
    auto img = boost::make_shared<sensor_msgs::Image>();
    img->header.stamp = stamp;
    img->header.frame_id = camera_frame;
    img->width = 100;
    img->height = 80;
    img->encoding = encoding;
    img->step = 300;
    img->data.assign(300 * 80, 0);
    for (int y = 0; y < 80; ++y)
      for (int x = 0; x < 100; ++x) img->data[y * 300 + x * 3 + (x < 50 ? 0 : 1)] = 255;
    auto ci = boost::make_shared<sensor_msgs::CameraInfo>();
    ci->header = img->header;
    ci->width = 100;
    ci->height = 80;
    ci->P = {50, 0, 50, 0, 0, 50, 40, 0, 0, 0, 1, 0};
    auto objs = boost::make_shared<DetectedObjectArray>();
    objs->header.stamp = stamp;
    objs->header.frame_id = "velodyne";
    objs->detector = "hierarchical_grid";
    auto cloud = boost::make_shared<LabeledCloud>();
    cloud->header.frame_id = "velodyne";
    cloud->header.stamp = pcl_conversions::toPCL(stamp);
    const float ys[3] = {2.0f, -2.0f, 0.0f};
    const float xs[3] = {10.0f, 10.0f, -5.0f};  // object 3 is behind the camera
    for (std::uint32_t id = 1; id <= 3; ++id) {
      DetectedObject o;
      o.id = id;
      o.class_label = lidar_class;
      o.class_confidence = lidar_confidence;
      for (int k = 0; k < 8; ++k) {
        o.indices.push_back(static_cast<std::uint32_t>(cloud->size()));
        cloud->push_back(makeLabeledPoint(xs[id - 1], ys[id - 1] + 0.05f * k, 0.1f * (k % 3), id,
                                          o.indices.back(), 10.0f));
      }
      o.point_count = 8;
      objs->objects.push_back(o);
    }
    image.publish(img);
    info.publish(ci);
    objects.publish(objs);
    points.publish(cloud);
  }
};

// The test network (test/spark_colour_model.py, 100 x 80 input, colour -> class) in a
// temporary folder removed at the end; setParams() points the nodelet under `ns` at it.
struct ColourModel {
  explicit ColourModel(const std::string& tag)
      : dir(std::filesystem::temp_directory_path() / (tag + "_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(dir);
    command = "/usr/bin/python3 " UD_SOURCE_DIR "/test/spark_colour_model.py " + model() +
              " 100 80 " + names();
    built = std::system(command.c_str()) == 0;
  }
  ~ColourModel() { std::filesystem::remove_all(dir); }
  std::string model() const { return (dir / "colour.onnx").string(); }
  std::string names() const { return (dir / "classes.txt").string(); }
  void setParams(const std::string& ns) const {
    ros::param::set(ns + "model/path", model());
    ros::param::set(ns + "model/class_names_file", names());
    ros::param::set(ns + "model/input_width_px", 100);
    ros::param::set(ns + "model/input_height_px", 80);
  }
  std::filesystem::path dir;
  std::string command;
  bool built = false;
};

bool haveOnnx() {
  return std::system("/usr/bin/python3 -c 'import onnx' >/dev/null 2>&1") == 0;
}

// The camera `frame` (optical: z forward, x right, y down) at the LiDAR origin looking along
// the LiDAR's x axis.
void sendCameraTf(tf2_ros::StaticTransformBroadcaster* tf, const std::string& frame) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "velodyne";
  t.child_frame_id = frame;
  Eigen::Matrix3d optical_from_lidar;
  optical_from_lidar << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  const Eigen::Quaterniond q(optical_from_lidar.transpose());  // camera pose in the LiDAR frame
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  tf->sendTransform(t);
}

TEST(ImageLabelTransferNodelet, ClassifiesObjectsSeenBySyntheticCamera) {
  if (!haveOnnx()) GTEST_SKIP() << "python3-onnx is not installed (apt-get install python3-onnx)";
  const ColourModel net("ud_ilt");
  ASSERT_TRUE(net.built) << net.command;
  const std::string ns = "/ilt/image_label_transfer/";
  ASSERT_TRUE(ros::param::has(ns + "transfer/min_confidence"))
      << "config/image_label_transfer.yaml not loaded by the .test file";
  net.setParams(ns);
  ros::param::set(ns + "model/mean", std::vector<double>{0.0, 0.0, 0.0});
  ros::param::set(ns + "model/scale", std::vector<double>{1 / 255.0, 1 / 255.0, 1 / 255.0});
  ros::param::set(ns + "model/keep_classes", std::vector<std::string>{"car", "vegetation", "pole"});

  tf2_ros::StaticTransformBroadcaster tf;
  sendCameraTf(&tf, "camera_optical");

  nodelet::Loader manager(false);
  ASSERT_TRUE(
      manager.load("/ilt/image_label_transfer", "urban_detection/ImageLabelTransfer", {}, {}));
  Scene scene;
  scene.advertise();
  ros::Duration(0.5).sleep();
  // Lazy: no subscriber on the inputs while nobody listens to the output.
  EXPECT_EQ(scene.image.getNumSubscribers(), 0u);
  ros::Subscriber sub = scene.collect();
  ASSERT_TRUE(waitFor(
      [&] { return scene.points.getNumSubscribers() > 0 && scene.image.getNumSubscribers() > 0; },
      10.0));
  // The network runs on its own thread and the objects never wait for it: revolutions that
  // arrive before the first mask (or before tf) pass with their LiDAR classes ("unknown" here).
  const bool got = waitFor(
      [&] {
        scene.publish(ros::Time::now());
        std::lock_guard<std::mutex> lock(scene.mutex);
        for (const auto& m : scene.received)
          if (!m->objects.empty() && m->objects[0].class_label != "unknown") return true;
        return false;
      },
      20.0);
  ASSERT_TRUE(got) << "no objects/classified with camera classes";
  DetectedObjectArray::ConstPtr out;
  {
    std::lock_guard<std::mutex> lock(scene.mutex);
    ASSERT_FALSE(scene.received.empty());
    for (const auto& m : scene.received) {
      EXPECT_EQ(m->objects.size(), 3u);  // every revolution is published, mask or not
      if (!out && !m->objects.empty() && m->objects[0].class_label != "unknown") out = m;
    }
  }
  ASSERT_EQ(out->objects.size(), 3u);
  EXPECT_EQ(out->header.frame_id, "velodyne");
  EXPECT_EQ(out->objects[0].class_label, "car");
  // Pure red: logits 4 * relu(0.5, 2, -1, -1) = (2, 8, 0, 0) -> p(car) = e^8 / (e^8 + e^2 + 2).
  EXPECT_NEAR(out->objects[0].class_confidence,
              std::exp(8.0) / (std::exp(8.0) + std::exp(2.0) + 2.0), 1e-3);
  EXPECT_EQ(out->objects[1].class_label, "vegetation");
  EXPECT_EQ(out->objects[2].class_label, "unknown");  // behind the camera
  EXPECT_FLOAT_EQ(out->objects[2].class_confidence, 0.0f);
  EXPECT_EQ(out->objects[1].indices.size(), 8u);  // the rest of the message is kept
}

// Bad input never stops the stage or the manager: images in an unsupported encoding, then images
// from a camera frame tf does not know. Every revolution still goes out, with its LiDAR classes.
TEST(ImageLabelTransferNodelet, BadEncodingAndMissingTfKeepLidarClasses) {
  if (!haveOnnx()) GTEST_SKIP() << "python3-onnx is not installed (apt-get install python3-onnx)";
  const ColourModel net("ud_ilt_bad");
  ASSERT_TRUE(net.built) << net.command;
  const std::string ns = "/ilt_bad/image_label_transfer/";
  ros::param::set(ns + "fusion", std::string("camera"));
  net.setParams(ns);
  nodelet::Loader manager(false);
  ASSERT_TRUE(
      manager.load("/ilt_bad/image_label_transfer", "urban_detection/ImageLabelTransfer", {}, {}));
  Scene scene("ilt_bad");
  scene.encoding = "yuv422";
  scene.camera_frame = "camera_nowhere";
  scene.lidar_class = "vehicle";
  scene.lidar_confidence = 0.7f;
  scene.advertise();
  ros::Subscriber sub = scene.collect();
  ASSERT_TRUE(waitFor([&] { return scene.points.getNumSubscribers() > 0; }, 10.0));
  for (const char* encoding : {"yuv422", "rgb8"}) {  // rgb8: a good image, but no tf
    SCOPED_TRACE(encoding);
    scene.encoding = encoding;
    {
      std::lock_guard<std::mutex> lock(scene.mutex);
      scene.received.clear();
    }
    ASSERT_TRUE(waitFor(
        [&] {
          scene.publish(ros::Time::now());
          std::lock_guard<std::mutex> lock(scene.mutex);
          return scene.received.size() >= 5;
        },
        20.0));
    std::lock_guard<std::mutex> lock(scene.mutex);
    for (const auto& m : scene.received) {
      ASSERT_EQ(m->objects.size(), 3u);
      for (const auto& o : m->objects) {
        EXPECT_EQ(o.class_label, "vehicle");
        EXPECT_FLOAT_EQ(o.class_confidence, 0.7f);
      }
    }
  }
  // The nodelet is still there and working.
  EXPECT_GT(scene.points.getNumSubscribers(), 0u);
}

// fusion: fused through the nodelet. All three objects come with the LiDAR class vehicle (0.6):
// the one on car pixels is confirmed (noisy-or confidence), the one on vegetation pixels is
// vetoed (left out), the one behind the camera keeps its LiDAR class.
TEST(ImageLabelTransferNodelet, FusedConfirmsVetoesAndKeepsUnseen) {
  if (!haveOnnx()) GTEST_SKIP() << "python3-onnx is not installed (apt-get install python3-onnx)";
  const ColourModel net("ud_ilt_fused");
  ASSERT_TRUE(net.built) << net.command;
  const std::string ns = "/ilt_fused/image_label_transfer/";
  ros::param::set(ns + "fusion", std::string("fused"));
  net.setParams(ns);
  ros::param::set(ns + "model/mean", std::vector<double>{0.0, 0.0, 0.0});
  ros::param::set(ns + "model/scale", std::vector<double>{1 / 255.0, 1 / 255.0, 1 / 255.0});
  ros::param::set(ns + "model/vehicle_classes", std::vector<std::string>{"car"});
  ros::param::set(ns + "model/background_classes", std::vector<std::string>{"vegetation"});

  tf2_ros::StaticTransformBroadcaster tf;
  sendCameraTf(&tf, "camera_fused");

  nodelet::Loader manager(false);
  ASSERT_TRUE(manager.load("/ilt_fused/image_label_transfer", "urban_detection/ImageLabelTransfer",
                           {}, {}));
  Scene scene("ilt_fused");
  scene.camera_frame = "camera_fused";
  scene.lidar_class = "vehicle";
  scene.lidar_confidence = 0.6f;
  scene.advertise();
  ros::Subscriber sub = scene.collect();
  ASSERT_TRUE(waitFor([&] { return scene.points.getNumSubscribers() > 0; }, 10.0));
  DetectedObjectArray::ConstPtr out;
  ASSERT_TRUE(waitFor(
      [&] {
        scene.publish(ros::Time::now());
        std::lock_guard<std::mutex> lock(scene.mutex);
        for (const auto& m : scene.received)
          if (m->objects.size() == 2u) out = m;  // a revolution that met a mask and tf
        return out != nullptr;
      },
      20.0))
      << "no fused objects/classified";
  EXPECT_EQ(out->objects[0].id, 1u);
  EXPECT_EQ(out->objects[0].class_label, "vehicle");
  const double p_car = std::exp(8.0) / (std::exp(8.0) + std::exp(2.0) + 2.0);
  EXPECT_NEAR(out->objects[0].class_confidence, 1.0 - 0.4 * (1.0 - p_car), 1e-3);
  EXPECT_EQ(out->objects[1].id, 3u);  // object 2 (vegetation pixels) vetoed
  EXPECT_EQ(out->objects[1].class_label, "vehicle");
  EXPECT_FLOAT_EQ(out->objects[1].class_confidence, 0.6f);
}

}  // namespace
}  // namespace urban_detection

int main(int argc, char** argv) {
  return urban_detection::rostest_util::runRostests(argc, argv, "test_image_label_transfer");
}
