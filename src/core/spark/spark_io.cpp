#include "urban_detection/core/spark/spark_io.h"

#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace core {

bool readSparkCloud(const std::string& path, CloudXYZIRT* cloud, std::vector<cv::Vec3b>* rgb,
                    std::string* error) {
  rgb->clear();
  if (std::filesystem::path(path).extension() == ".bin") return readKittiBin(path, cloud, error);
  pcl::PCLPointCloud2 blob;
  if (pcl::io::loadPCDFile(path, blob) != 0) {
    *error = "cannot read PCD file '" + path + "'";
    return false;
  }
  bool has_rgb = false, has_intensity = false;
  for (const auto& f : blob.fields) {
    has_rgb |= f.name == "rgb" || f.name == "rgba";
    has_intensity |= f.name == "intensity";
  }
  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  cloud->clear();
  cloud->reserve(xyz.size());
  for (const auto& p : xyz) cloud->push_back(makePoint(p.x, p.y, p.z));
  if (has_intensity) {
    pcl::PointCloud<pcl::PointXYZI> xyzi;
    pcl::fromPCLPointCloud2(blob, xyzi);
    for (std::size_t i = 0; i < xyzi.size() && i < cloud->size(); ++i)
      (*cloud)[i].intensity = xyzi[i].intensity;
  }
  if (has_rgb) {
    pcl::PointCloud<pcl::PointXYZRGB> c;
    pcl::fromPCLPointCloud2(blob, c);
    rgb->reserve(c.size());
    for (const auto& p : c) rgb->emplace_back(p.b, p.g, p.r);
  }
  return true;
}

bool writeColouredCloud(const std::string& path, const CloudXYZIRT& cloud,
                        const std::vector<cv::Vec3b>& rgb,
                        const std::vector<std::uint32_t>& indices) {
  pcl::PointCloud<pcl::PointXYZRGB> out;
  out.reserve(indices.size());
  for (const std::uint32_t i : indices) {
    pcl::PointXYZRGB p;
    p.x = cloud[i].x;
    p.y = cloud[i].y;
    p.z = cloud[i].z;
    const cv::Vec3b c = i < rgb.size() ? rgb[i] : cv::Vec3b(128, 128, 128);
    p.b = c[0];
    p.g = c[1];
    p.r = c[2];
    out.push_back(p);
  }
  out.width = static_cast<std::uint32_t>(out.size());
  out.height = 1;
  return out.empty() ? pcl::io::savePCDFileASCII(path, out) == 0
                     : pcl::io::savePCDFileBinary(path, out) == 0;
}

bool classColours(const std::string& colours_file, std::vector<cv::Vec3b>* colours,
                  std::string* error) {
  colours->clear();
  if (!colours_file.empty()) {
    std::ifstream in(colours_file);
    if (!in) {
      *error = "cannot read colours file " + colours_file;
      return false;
    }
    std::string line;
    while (std::getline(in, line)) {  // "r g b" or "r,g,b"
      std::replace(line.begin(), line.end(), ',', ' ');
      int r = 0, g = 0, b = 0;
      if (std::sscanf(line.c_str(), "%d %d %d", &r, &g, &b) != 3) continue;
      colours->emplace_back(static_cast<uchar>(b), static_cast<uchar>(g), static_cast<uchar>(r));
    }
  }
  for (int c = static_cast<int>(colours->size()); c < 256; ++c)
    colours->emplace_back(static_cast<uchar>((c * 67) % 256), static_cast<uchar>((c * 151) % 256),
                          static_cast<uchar>((c * 37 + 80) % 256));
  (*colours)[255] = cv::Vec3b(0, 0, 0);
  return true;
}

cv::Mat colourMask(const cv::Mat& labels, const std::vector<cv::Vec3b>& colours) {
  cv::Mat out(labels.size(), CV_8UC3);
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) out.at<cv::Vec3b>(y, x) = colours[labels.at<uchar>(y, x)];
  return out;
}

std::string sparkClassName(const std::vector<std::string>& names, int id) {
  if (id >= 0 && static_cast<std::size_t>(id) < names.size() && !names[id].empty())
    return names[id];
  return id < 0 ? "unknown" : "class_" + std::to_string(id);
}

int applyCameraModelOption(const std::string& a, const std::function<std::string()>& value,
                           CameraStageParams* stage, std::string* colours_file,
                           std::string* error) {
  CameraModelParams& mp = stage->model;
  auto triple = [&](std::array<double, 3>* dst) {
    const std::vector<std::string> v = splitCommaList(value());
    std::array<double, 3> x{};
    for (std::size_t c = 0; c < 3 && v.size() == 3; ++c) {
      char* end = nullptr;
      x[c] = std::strtod(v[c].c_str(), &end);
      if (end == v[c].c_str() || *end != '\0') return -1;
    }
    if (v.size() != 3) return -1;
    *dst = x;
    return 1;
  };
  int result = 1;
  if (a == "--model")
    mp.network.model_path = value();
  else if (a == "--model-config")
    value();  // read before the other options
  else if (a == "--model-dir")
    mp.dir = value();
  else if (a == "--colours")
    *colours_file = value();
  else if (a == "--classes")
    mp.class_names_file = value();
  else if (a == "--keep")
    mp.keep_classes = splitCommaList(value());
  else if (a == "--input-size") {
    int w = 0, h = 0;
    if (std::sscanf(value().c_str(), "%dx%d", &w, &h) != 2) {
      *error = "--input-size WxH";
      return -1;
    }
    mp.network.input_width_px = w;
    mp.network.input_height_px = h;
  } else if (a == "--mean" || a == "--scale") {
    result = triple(a == "--mean" ? &mp.network.mean : &mp.network.scale);
    if (result < 0) *error = a + " needs three comma-separated numbers";
  } else if (a == "--bgr")
    mp.network.input_rgb = false;
  else if (a == "--probabilities")
    mp.network.output_softmax = false;
  else
    result = 0;
  return result;
}

std::vector<std::string> splitCommaList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace core
}  // namespace urban_detection
