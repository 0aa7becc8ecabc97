#include "urban_detection/core/evaluation/datasets.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace urban_detection {
namespace core {

namespace fs = std::filesystem;

Dataset::Status IndexedDataset::next(Frame* f, std::string* error) {
  if (next_ >= size()) return Status::kEnd;
  return load(next_++, f, error) ? Status::kFrame : Status::kSkipped;
}

KittiObjectDataset::KittiObjectDataset(const std::string& dir, const KittiGroundTruthParams& p)
    : dir_(dir), params_(p), bins_(listFiles(dir + "/velodyne", ".bin")) {}

bool KittiObjectDataset::load(std::size_t i, Frame* f, std::string* error) {
  const std::string stem = fs::path(bins_[i]).stem().string();
  f->id = stem;
  if (!readKittiBin(bins_[i], &f->cloud, error)) return false;
  KittiCalibration calib;
  if (!readKittiCalibration(dir_ + "/calib/" + stem + ".txt", &calib, error)) return false;
  std::vector<KittiLabel> labels;
  if (!readKittiLabels(dir_ + "/label_2/" + stem + ".txt", &labels, error)) return false;
  int w = params_.image_width_px, h = params_.image_height_px;
  readPngSize(dir_ + "/image_2/" + stem + ".png", &w, &h);  // keeps defaults if absent
  buildKittiGroundTruth(f->cloud, labels, calib, params_, w, h, &f->gt);
  f->point_class.resize(f->cloud.size());
  for (std::size_t k = 0; k < f->cloud.size(); ++k) {
    std::uint16_t c = kBackground;
    if (f->gt.object_of_point[k] >= 0) {
      c = kInBox;
    } else if (f->gt.role[k] == PointRole::kExcluded) {
      c = kExcluded;
    } else if (f->gt.role[k] == PointRole::kDontCare) {
      double u, v;
      const auto& p = f->cloud[k];
      c = calib.project({p.x, p.y, p.z}, &u, &v) && u >= 0 && u < w && v >= 0 && v < h
              ? kDontCareBox
              : kOutOfView;
    }
    f->point_class[k] = c;
  }
  return true;
}

std::string KittiObjectDataset::className(std::uint16_t c) const {
  static const char* names[] = {"unlabelled_in_view", "out_of_camera_view", "dontcare_box",
                                "ground_under_box", "labelled_box"};
  return c < 5 ? names[c] : "?";
}

SemanticKittiDataset::SemanticKittiDataset(const std::string& dir,
                                           const SemanticKittiGroundTruthParams& p)
    : params_(p) {
  const std::vector<std::string> seqs = semanticKittiSequences(dir);
  for (const auto& s : seqs) {
    for (const auto& b : listFiles(s + "/velodyne", ".bin")) {
      const std::string stem = fs::path(b).stem().string();
      const std::string l = s + "/labels/" + stem + ".label";
      if (fs::exists(l)) frames_.push_back({b, l, fs::path(s).filename().string() + "/" + stem});
    }
  }
}

bool SemanticKittiDataset::load(std::size_t i, Frame* f, std::string* error) {
  f->id = frames_[i].id;
  if (!readKittiBin(frames_[i].bin, &f->cloud, error)) return false;
  if (!readSemanticKittiLabels(frames_[i].label, &labels_, error)) return false;
  if (labels_.size() != f->cloud.size()) {
    *error = frames_[i].label + ": " + std::to_string(labels_.size()) + " labels for " +
             std::to_string(f->cloud.size()) + " points";
    return false;
  }
  buildSemanticKittiGroundTruth(labels_, params_, &f->gt);
  f->point_class.resize(labels_.size());
  for (std::size_t k = 0; k < labels_.size(); ++k) {
    f->point_class[k] = semanticKittiClass(labels_[k]);
  }
  return true;
}

SimulatedDriveDataset::SimulatedDriveDataset(const std::string& gt, const std::string& pcap,
                                             const Calibration& cal, double cut_angle_deg,
                                             const SimulatedGroundTruthParams& p)
    : reader_(pcap, gt, cal, cut_angle_deg), params_(p) {}

Dataset::Status SimulatedDriveDataset::next(Frame* f, std::string* error) {
  switch (reader_.next(&f->cloud, &frame_, error)) {
    case SimulatedDriveReader::Result::kEnd:
      if (!error->empty()) std::fprintf(stderr, "warning: %s\n", error->c_str());
      return Status::kEnd;
    case SimulatedDriveReader::Result::kSkipped:
      return Status::kSkipped;
    case SimulatedDriveReader::Result::kFrame:
      break;
  }
  f->id = "rev" + std::to_string(frame_.revolution);
  buildSimulatedGroundTruth(frame_, params_, &f->gt);
  f->point_class.assign(frame_.classes.begin(), frame_.classes.end());
  return Status::kFrame;
}

std::string SimulatedDriveDataset::className(std::uint16_t c) const {
  return toString(static_cast<ObjectClass>(c));
}

std::string mostCommon(const std::map<std::string, std::size_t>& counts) {
  std::string what = "?";
  std::size_t most = 0;
  for (const auto& kv : counts) {
    if (kv.second > most) {
      most = kv.second;
      what = kv.first;
    }
  }
  return what;
}

std::string detectionContent(const Frame& f, const Dataset& ds, const DetectedObject& d) {
  const std::size_t n = f.cloud.size();
  std::map<std::string, std::size_t> content;
  for (std::uint32_t i : d.indices) {
    if (i >= n) continue;
    const std::int32_t og = f.gt.object_of_point[i];
    content[og >= 0 ? "part_of_" + f.gt.objects[og].label : ds.className(f.point_class[i])]++;
  }
  return mostCommon(content);
}

std::string frameGroup(const std::string& frame_id, const std::string& dataset) {
  const auto slash = frame_id.find('/');
  return slash == std::string::npos ? dataset : frame_id.substr(0, slash);
}

std::vector<std::string> listSweeps(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  if (fs::is_regular_file(dir, ec)) return {dir};
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && (ext == ".bin" || ext == ".pcd")) files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

bool readSweep(const std::string& path, CloudXYZIRT* cloud, std::string* error) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".bin" ? readKittiBin(path, cloud, error) : readPcdXyzi(path, cloud, error);
}

const std::string& EvalDatasetSource::path() const {
  if (!kitti_object_dir.empty()) return kitti_object_dir;
  return semantic_kitti_dir.empty() ? sim_pcap : semantic_kitti_dir;
}

std::unique_ptr<Dataset> openEvalDataset(const EvalDatasetSource& source) {
  if (!source.kitti_object_dir.empty()) {
    KittiGroundTruthParams p;
    p.min_points = 1;
    return std::make_unique<KittiObjectDataset>(source.kitti_object_dir, p);
  }
  if (!source.semantic_kitti_dir.empty()) {
    SemanticKittiGroundTruthParams p;
    p.min_points = 1;
    return std::make_unique<SemanticKittiDataset>(source.semantic_kitti_dir, p);
  }
  SimulatedGroundTruthParams p;
  p.min_points = 1;
  return std::make_unique<SimulatedDriveDataset>(source.sim_gt, source.sim_pcap,
                                                 loadCalibration(source.calibration_path),
                                                 source.cut_angle_deg, p);
}

}  // namespace core
}  // namespace urban_detection
