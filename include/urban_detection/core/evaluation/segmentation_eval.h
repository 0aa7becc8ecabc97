/// \file segmentation_eval.h
/// Accuracy of the grid segmentation (paper Sec. 3.1) with and without the Hough wall
/// refinement (urban_detection_seg_eval): every point of a labelled frame falls into a group
/// (ground, wall, car, person, ...); the figures are ground precision / recall / F1 against the
/// points the segmenter calls ground, the share of wall points kept out of the foreground, the
/// share of each object group in the foreground (short), and a 5 x 5 confusion of groups
/// against SegmentClass. ROS-free. Unreadable frames are skipped with a message on stderr.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace core {

/// What a point of either dataset is, for these figures.
enum class SegGroup : std::uint8_t {
  kIgnore,  ///< unlabeled / outlier
  kGround,  ///< SemanticKITTI road, sidewalk, parking, other-ground, terrain, lane-marking;
            ///< simulated road, curb, sidewalk, terrain
  kWall,    ///< building + fence; simulated facades
  kCar,
  kPerson,
  kCyclist,       ///< bicyclist + motorcyclist; simulated cyclists with their bicycle
  kOtherVehicle,  ///< truck, other-vehicle, bicycle, motorcycle; simulated vans
  kVegPole,       ///< vegetation, trunk, pole, traffic sign (for information)
  kStreetObject,  ///< simulated bins and benches (short street objects)
  kOther,
};

/// The group of a SemanticKITTI label (semantic class in the low 16 bits).
SegGroup semanticKittiGroup(std::uint32_t label);
/// The group of a simulated point class (ObjectClass).
SegGroup simulatedGroup(std::uint8_t object_class);

/// Points of one group, and how many of them the segmenter put in the foreground (short).
struct SegShare {
  long total = 0, fg = 0;
};

/// The accumulated figures of one segmenter.
struct SegCounts {
  long ground_tp = 0, ground_fp = 0, ground_fn = 0;
  SegShare group[static_cast<int>(SegGroup::kOther) + 1];
  long confusion[5][5] = {};  ///< [ground, wall, car, person+cyclist, other][SegmentClass]
  double ms_total = 0.0;      ///< segmentation wall time over the frames
  int frames = 0;
  const SegShare& of(SegGroup g) const { return group[static_cast<int>(g)]; }
};

/// a / b, 0 when b is 0.
double segRatio(long a, long b);
/// Adds one frame: `gt` and `pred` per point (kIgnore points are skipped).
void accumulate(const std::vector<SegGroup>& gt, const std::vector<SegmentClass>& pred,
                SegCounts* c);
double groundPrecision(const SegCounts& c);
double groundRecall(const SegCounts& c);
double groundF1(const SegCounts& c);
/// Share of a group's points outside the foreground.
double notForeground(const SegShare& s);
/// Share of a group's points in the foreground.
double foreground(const SegShare& s);

/// Segments every frame with Hough on and off and accumulates both against the frame's groups.
class SegmentationEvaluator {
 public:
  explicit SegmentationEvaluator(const GridSegmenterParams& params);

  /// `dump` (when not empty) is the path prefix of per-point "x y z group class" text files.
  void frame(const CloudXYZIRT& cloud, const std::vector<SegGroup>& groups,
             const std::string& dump);
  const SegCounts& on() const { return on_; }
  const SegCounts& off() const { return off_; }
  /// The segmenters (Hough on, off) after the last frame.
  const GridSegmenter& segmenterOn() const { return seg_on_; }
  const GridSegmenter& segmenterOff() const { return seg_off_; }

 private:
  GridSegmenter seg_on_, seg_off_;
  SegCounts on_, off_;
  std::vector<SegmentClass> labels_;
};

/// SemanticKITTI scans DIR/velodyne/*.bin with DIR/labels/*.label into `ev`; false when none
/// was read. `dump_dir`: see SegmentationEvaluator::frame.
bool evaluateSemanticKittiSegmentation(const std::string& dir, const std::string& dump_dir,
                                       SegmentationEvaluator* ev);

/// A simulated drive: the revolutions of PCAP against the per-point classes of GT_PATH (matched
/// by stamp), the first `max_frames` (< 0: all). False with `*error` when the files cannot be
/// read or hold no frame.
bool evaluateSimulatedSegmentation(const std::string& gt_path, const std::string& pcap_path,
                                   const std::string& calibration_path, long max_frames,
                                   const std::string& dump_dir, SegmentationEvaluator* ev,
                                   std::string* error);

/// KITTI object frames: points of labelled objects (inside their 3-D boxes, above the ground
/// band, rules of eval_datasets.h) and how many of them end up in the foreground, per class.
struct KittiObjectSegmentation {
  int frames = 0;
  /// Per KITTI class: points, in the foreground with Hough, without.
  std::map<std::string, std::array<long, 3>> per_class;
  /// The Hough-on segmenter after the last frame.
  std::shared_ptr<GridSegmenter> segmenter_on;
};
/// False when DIR/velodyne holds no frame.
bool evaluateKittiObjectSegmentation(const std::string& dir, const GridSegmenterParams& params,
                                     KittiObjectSegmentation* out);

/// The figures as JSON (keys: dataset, path, frames, hough_on / hough_off with
/// ground_precision, ground_recall, ground_f1, wall_not_foreground, car_foreground,
/// person_foreground, cyclist_foreground, other_vehicle_foreground, street_object_foreground
/// and point counts). False when the file cannot be written.
bool writeSegmentationJson(const std::string& path, const std::string& dataset,
                           const std::string& source, const SegCounts& on, const SegCounts& off);

/// The cell classes of the segmenter's last frame within `half_m` of the sensor, one text row
/// per grid row (+x right, +y up), after a title line: '.' ground, 'T' tall, 's' short,
/// ',' clutter, 'S' the sensor.
std::string cellClassesAscii(const GridSegmenter& seg, double half_m);

}  // namespace core
}  // namespace urban_detection
