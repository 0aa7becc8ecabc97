// Labelled datasets of the evaluation tools (urban_detection_eval, _train_classifier): KITTI
// object frames, SemanticKITTI scans and simulated drives as (cloud, per-point ground truth)
// frames, read in order; and what a detection is made of. Not a tool itself (only
// src/tools/*.cpp are executables).
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace tools {

namespace core = urban_detection::core;
namespace fs = std::filesystem;

// ------------------------------------------------------------------------------------------
// Datasets

struct Frame {
  std::string id;
  urban_detection::CloudXYZIRT cloud;
  core::EvalFrame gt;
  std::vector<std::uint16_t> point_class;  // dataset class per point, for diagnostics
};

// Frames are read in order (a simulated drive is a stream).
class Dataset {
 public:
  enum class Status { kFrame, kSkipped, kEnd };
  virtual ~Dataset() = default;
  virtual std::string name() const = 0;
  virtual Status next(Frame* f, std::string* error) = 0;
  virtual std::string className(std::uint16_t c) const = 0;
};

// Datasets of files, frame i by index.
class IndexedDataset : public Dataset {
 public:
  Status next(Frame* f, std::string* error) override {
    if (next_ >= size()) return Status::kEnd;
    return load(next_++, f, error) ? Status::kFrame : Status::kSkipped;
  }
  virtual std::size_t size() const = 0;
  virtual bool load(std::size_t i, Frame* f, std::string* error) = 0;

 private:
  std::size_t next_ = 0;
};

class KittiObjectDataset : public IndexedDataset {
 public:
  // Point classes for diagnostics.
  enum : std::uint16_t {
    kBackground = 0,
    kOutOfView = 1,
    kDontCareBox = 2,
    kExcluded = 3,
    kInBox = 4
  };
  KittiObjectDataset(const std::string& dir, const core::KittiGroundTruthParams& p)
      : dir_(dir), params_(p), bins_(core::listFiles(dir + "/velodyne", ".bin")) {}
  std::string name() const override { return "kitti_object"; }
  std::size_t size() const override { return bins_.size(); }
  bool load(std::size_t i, Frame* f, std::string* error) override {
    const std::string stem = fs::path(bins_[i]).stem().string();
    f->id = stem;
    if (!core::readKittiBin(bins_[i], &f->cloud, error)) return false;
    core::KittiCalibration calib;
    if (!core::readKittiCalibration(dir_ + "/calib/" + stem + ".txt", &calib, error)) {
      return false;
    }
    std::vector<core::KittiLabel> labels;
    if (!core::readKittiLabels(dir_ + "/label_2/" + stem + ".txt", &labels, error)) return false;
    int w = params_.image_width_px, h = params_.image_height_px;
    core::readPngSize(dir_ + "/image_2/" + stem + ".png", &w, &h);  // keeps defaults if absent
    core::buildKittiGroundTruth(f->cloud, labels, calib, params_, w, h, &f->gt);
    f->point_class.resize(f->cloud.size());
    for (std::size_t k = 0; k < f->cloud.size(); ++k) {
      std::uint16_t c = kBackground;
      if (f->gt.object_of_point[k] >= 0) {
        c = kInBox;
      } else if (f->gt.role[k] == core::PointRole::kExcluded) {
        c = kExcluded;
      } else if (f->gt.role[k] == core::PointRole::kDontCare) {
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
  std::string className(std::uint16_t c) const override {
    static const char* names[] = {"unlabelled_in_view", "out_of_camera_view", "dontcare_box",
                                  "ground_under_box", "labelled_box"};
    return c < 5 ? names[c] : "?";
  }

 private:
  std::string dir_;
  core::KittiGroundTruthParams params_;
  std::vector<std::string> bins_;
};

class SemanticKittiDataset : public IndexedDataset {
 public:
  SemanticKittiDataset(const std::string& dir, const core::SemanticKittiGroundTruthParams& p)
      : params_(p) {
    // DIR is a sequence folder (velodyne/, labels/) or the dataset root (sequences/NN/).
    std::vector<std::string> seqs;
    if (fs::is_directory(dir + "/velodyne")) {
      seqs.push_back(dir);
    } else {
      for (const auto& s : core::listFiles(dir + "/sequences", "")) {
        if (fs::is_directory(s + "/velodyne")) seqs.push_back(s);
      }
    }
    for (const auto& s : seqs) {
      for (const auto& b : core::listFiles(s + "/velodyne", ".bin")) {
        const std::string stem = fs::path(b).stem().string();
        const std::string l = s + "/labels/" + stem + ".label";
        if (fs::exists(l)) {
          frames_.push_back({b, l, fs::path(s).filename().string() + "/" + stem});
        }
      }
    }
  }
  std::string name() const override { return "semantic_kitti"; }
  std::size_t size() const override { return frames_.size(); }
  bool load(std::size_t i, Frame* f, std::string* error) override {
    f->id = frames_[i].id;
    if (!core::readKittiBin(frames_[i].bin, &f->cloud, error)) return false;
    if (!core::readSemanticKittiLabels(frames_[i].label, &labels_, error)) return false;
    if (labels_.size() != f->cloud.size()) {
      *error = frames_[i].label + ": " + std::to_string(labels_.size()) + " labels for " +
               std::to_string(f->cloud.size()) + " points";
      return false;
    }
    core::buildSemanticKittiGroundTruth(labels_, params_, &f->gt);
    f->point_class.resize(labels_.size());
    for (std::size_t k = 0; k < labels_.size(); ++k) {
      f->point_class[k] = core::semanticKittiClass(labels_[k]);
    }
    return true;
  }
  std::string className(std::uint16_t c) const override { return core::semanticKittiClassName(c); }

 private:
  struct Item {
    std::string bin, label, id;
  };
  core::SemanticKittiGroundTruthParams params_;
  std::vector<Item> frames_;
  std::vector<std::uint32_t> labels_;
};

class SimulatedDriveDataset : public Dataset {
 public:
  SimulatedDriveDataset(const std::string& gt, const std::string& pcap,
                        const core::Calibration& cal, double cut_angle_deg,
                        const core::SimulatedGroundTruthParams& p)
      : reader_(pcap, gt, cal, cut_angle_deg), params_(p) {}
  std::string name() const override { return "sim"; }
  Status next(Frame* f, std::string* error) override {
    switch (reader_.next(&f->cloud, &frame_, error)) {
      case core::SimulatedDriveReader::Result::kEnd:
        if (!error->empty()) std::fprintf(stderr, "warning: %s\n", error->c_str());
        return Status::kEnd;
      case core::SimulatedDriveReader::Result::kSkipped:
        return Status::kSkipped;
      case core::SimulatedDriveReader::Result::kFrame:
        break;
    }
    f->id = "rev" + std::to_string(frame_.revolution);
    core::buildSimulatedGroundTruth(frame_, params_, &f->gt);
    f->point_class.assign(frame_.classes.begin(), frame_.classes.end());
    return Status::kFrame;
  }
  std::string className(std::uint16_t c) const override {
    return core::toString(static_cast<core::ObjectClass>(c));
  }

 private:
  core::SimulatedDriveReader reader_;
  core::SimulatedGroundTruthParams params_;
  core::GroundTruthFrame frame_;
};

// The key with the largest count ("?" when empty; the first such key on ties).
inline std::string mostCommon(const std::map<std::string, std::size_t>& counts) {
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

// The dataset class most of a detection's points carry ("part_of_<label>" for GT points).
inline std::string detectionContent(const Frame& f, const Dataset& ds,
                                    const core::DetectedObject& d) {
  const std::size_t n = f.cloud.size();
  std::map<std::string, std::size_t> content;
  for (std::uint32_t i : d.indices) {
    if (i >= n) continue;
    const std::int32_t og = f.gt.object_of_point[i];
    content[og >= 0 ? "part_of_" + f.gt.objects[og].label : ds.className(f.point_class[i])]++;
  }
  return mostCommon(content);
}

/// The sequence of a frame id "SEQ/NNNNNN" (SemanticKITTI), else the dataset name.
inline std::string frameGroup(const std::string& frame_id, const std::string& dataset) {
  const auto slash = frame_id.find('/');
  return slash == std::string::npos ? dataset : frame_id.substr(0, slash);
}

}  // namespace tools
}  // namespace urban_detection
