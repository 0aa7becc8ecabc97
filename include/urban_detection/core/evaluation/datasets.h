/// \file datasets.h
/// Labelled datasets the evaluation scores on (urban_detection_eval, _train_classifier): KITTI
/// object frames, SemanticKITTI scans and simulated drives as (cloud, per-point ground truth)
/// frames, read in order (ground-truth rules in eval_datasets.h); what a detection is made of;
/// and the unlabelled sweeps of the benchmarks (KITTI .bin or PCD files). ROS-free.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/sensor/kitti_io.h"

namespace urban_detection {
namespace core {

/// One labelled frame.
struct Frame {
  std::string id;
  CloudXYZIRT cloud;
  EvalFrame gt;
  std::vector<std::uint16_t> point_class;  ///< dataset class per point, for diagnostics
};

/// A labelled dataset. Frames are read in order (a simulated drive is a stream).
class Dataset {
 public:
  enum class Status { kFrame, kSkipped, kEnd };
  virtual ~Dataset() = default;
  virtual std::string name() const = 0;
  /// The next frame into `f`; kSkipped (with `*error`) for a frame that cannot be read.
  virtual Status next(Frame* f, std::string* error) = 0;
  /// Name of a dataset class of Frame::point_class.
  virtual std::string className(std::uint16_t c) const = 0;
};

/// Datasets of files, frame i by index.
class IndexedDataset : public Dataset {
 public:
  Status next(Frame* f, std::string* error) override;
  virtual std::size_t size() const = 0;
  virtual bool load(std::size_t i, Frame* f, std::string* error) = 0;

 private:
  std::size_t next_ = 0;
};

/// KITTI object: velodyne/*.bin, calib/, label_2/, image_2/ (image size only).
class KittiObjectDataset : public IndexedDataset {
 public:
  /// Point classes for diagnostics.
  enum : std::uint16_t {
    kBackground = 0,
    kOutOfView = 1,
    kDontCareBox = 2,
    kExcluded = 3,
    kInBox = 4
  };
  KittiObjectDataset(const std::string& dir, const KittiGroundTruthParams& p);
  std::string name() const override { return "kitti_object"; }
  std::size_t size() const override { return bins_.size(); }
  bool load(std::size_t i, Frame* f, std::string* error) override;
  std::string className(std::uint16_t c) const override;

 private:
  std::string dir_;
  KittiGroundTruthParams params_;
  std::vector<std::string> bins_;
};

/// SemanticKITTI: a sequence folder (velodyne/, labels/) or the dataset root (sequences/NN/);
/// frame ids are "SEQ/NNNNNN".
class SemanticKittiDataset : public IndexedDataset {
 public:
  SemanticKittiDataset(const std::string& dir, const SemanticKittiGroundTruthParams& p);
  std::string name() const override { return "semantic_kitti"; }
  std::size_t size() const override { return frames_.size(); }
  bool load(std::size_t i, Frame* f, std::string* error) override;
  std::string className(std::uint16_t c) const override { return semanticKittiClassName(c); }

 private:
  struct Item {
    std::string bin, label, id;
  };
  SemanticKittiGroundTruthParams params_;
  std::vector<Item> frames_;
  std::vector<std::uint32_t> labels_;
};

/// A simulated drive: the pcap and its ground-truth file, cut into revolutions.
class SimulatedDriveDataset : public Dataset {
 public:
  SimulatedDriveDataset(const std::string& gt, const std::string& pcap, const Calibration& cal,
                        double cut_angle_deg, const SimulatedGroundTruthParams& p);
  std::string name() const override { return "sim"; }
  /// At the end, a reader error is printed on stderr as a warning.
  Status next(Frame* f, std::string* error) override;
  std::string className(std::uint16_t c) const override;

 private:
  SimulatedDriveReader reader_;
  SimulatedGroundTruthParams params_;
  GroundTruthFrame frame_;
};

/// The key with the largest count ("?" when empty; the first such key on ties).
/// Where the frames of an evaluation come from: exactly one of a KITTI object folder, a
/// SemanticKITTI folder, or a simulated drive (its ground-truth file and pcap, the calibration
/// it was simulated with (empty: nominal) and the revolution cut).
struct EvalDatasetSource {
  std::string kitti_object_dir, semantic_kitti_dir, sim_gt, sim_pcap, calibration_path;
  double cut_angle_deg = 0.0;
  /// The folder or pcap the reports name.
  const std::string& path() const;
};

/// The dataset of `source` with every labelled object kept (ground-truth min_points 1: the
/// evaluator applies its own small-object rule). Throws std::runtime_error when the
/// calibration cannot be loaded.
std::unique_ptr<Dataset> openEvalDataset(const EvalDatasetSource& source);

std::string mostCommon(const std::map<std::string, std::size_t>& counts);

/// The dataset class most of a detection's points carry ("part_of_<label>" for GT points).
std::string detectionContent(const Frame& f, const Dataset& ds, const DetectedObject& d);

/// The sequence of a frame id "SEQ/NNNNNN" (SemanticKITTI), else the dataset name.
std::string frameGroup(const std::string& frame_id, const std::string& dataset);

/// Sorted .bin and .pcd files directly in `dir` (a single file is returned as is).
std::vector<std::string> listSweeps(const std::string& dir);

/// Reads a KITTI .bin or a PCD sweep.
bool readSweep(const std::string& path, CloudXYZIRT* cloud, std::string* error);

}  // namespace core
}  // namespace urban_detection
