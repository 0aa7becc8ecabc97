#include "urban_detection/core/evaluation/external_detections.h"

#include <filesystem>
#include <fstream>
#include <map>

namespace urban_detection {
namespace core {

namespace fs = std::filesystem;

bool ExternalDetections::load(const Frame& f, std::string* error) {
  std::vector<std::string> candidates = {dir_ + "/" + f.id + ".label"};
  const auto slash = f.id.find('/');
  if (slash != std::string::npos) {
    candidates.push_back(dir_ + "/sequences/" + f.id.substr(0, slash) + "/predictions/" +
                         f.id.substr(slash + 1) + ".label");
  }
  for (const std::string& path : candidates) {
    if (!fs::is_regular_file(path)) continue;
    std::ifstream in(path, std::ios::binary);
    labels_.assign(f.cloud.size(), 0u);
    in.read(reinterpret_cast<char*>(labels_.data()),
            static_cast<std::streamsize>(labels_.size() * sizeof(std::uint32_t)));
    const bool exact = in.gcount() == static_cast<std::streamsize>(labels_.size() * 4) &&
                       in.peek() == std::char_traits<char>::eof();
    if (!exact) {
      *error = path + ": not one uint32 per point of the frame (" + std::to_string(f.cloud.size()) +
               " points)";
      return false;
    }
    cloud_ = &f.cloud;
    return true;
  }
  *error = "no label file for frame " + f.id + " (tried " + candidates[0] + ")";
  return false;
}

void ExternalDetections::detect(const LabeledCloud& /*foreground*/,
                                std::vector<DetectedObject>* objects) {
  objects->clear();
  std::map<std::uint32_t, std::size_t> object_of_label;
  for (std::size_t i = 0; i < labels_.size(); ++i) {
    if (labels_[i] == 0) continue;
    const auto it = object_of_label.emplace(labels_[i], objects->size()).first;
    if (it->second == objects->size()) objects->emplace_back();
    (*objects)[it->second].indices.push_back(static_cast<std::uint32_t>(i));
  }
  for (std::size_t k = 0; k < objects->size(); ++k) {
    DetectedObject& o = (*objects)[k];
    o.id = static_cast<std::uint32_t>(k + 1);
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    o.min_pt = Eigen::Vector3f::Constant(1e30f);
    o.max_pt = Eigen::Vector3f::Constant(-1e30f);
    for (const std::uint32_t i : o.indices) {
      const Eigen::Vector3f p((*cloud_)[i].x, (*cloud_)[i].y, (*cloud_)[i].z);
      sum += p;
      o.min_pt = o.min_pt.cwiseMin(p);
      o.max_pt = o.max_pt.cwiseMax(p);
    }
    o.centroid = sum / static_cast<float>(o.indices.size());
    o.obb_center = 0.5f * (o.min_pt + o.max_pt);
    o.obb_size = o.max_pt - o.min_pt;
  }
}

}  // namespace core
}  // namespace urban_detection
