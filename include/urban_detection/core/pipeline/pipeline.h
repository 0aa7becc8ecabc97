/// \file pipeline.h
/// The whole detection chain as one object: segmentation (GridSegmenter, Börcs et al. 2014
/// Sec. 3) -> foreground (extractForeground) -> detection (hierarchical grid, Sec. 4, or the
/// kd-tree baseline) -> classification (ObjectClassifier) -> whole-object boxes (BoxFitter),
/// and, where asked, the Tracker after them. The chain is written here once: the detector
/// nodelet, the offline tools, the demo and the tests call Pipeline::process() (or detect() on
/// a foreground made elsewhere, as the detector nodelet gets it from the segmentation nodelet)
/// instead of calling the stages one by one.
///
///   core::PipelineParams params;                   // or loadPipelineConfigYaml(file, &params)
///   core::Pipeline pipeline(params);
///   const core::PipelineResult& r = pipeline.process(cloud);
///   for (const core::DetectedObject& o : r.objects) ...
///
/// The pipeline owns its stages and their scratch buffers, and the result it returns (valid
/// until the next call), so a steady stream of revolutions allocates nothing new. It never
/// prints; stage times are in PipelineResult::timings.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/common/segment_class.h"
#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/pipeline/early_objects.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {

/// Every stage's parameters, nested as the stages run.
struct PipelineParams {
  std::string detector = "hierarchical_grid";  // "hierarchical_grid" or "kdtree" (the baseline)
  bool tracking = false;  // [-] run the Tracker after the chain (PipelineResult::tracks)
  GridSegmenterParams segmentation;
  HierarchicalGridDetectorParams hierarchical_grid;
  KdTreeDetectorParams kdtree;
  ObjectClassifierParams classifier;
  BoxFittingParams box_fitting;
  TrackerParams tracker;
  EarlyObjectsParams early;  // addSector() only (the early-objects mode)
};

/// PipelineParams' field table (core/common/param_fields.h): the stages' tables nested under
/// their names ("segmentation/cell_size_m", "classifier/model", ...).
template <>
struct ParamFields<PipelineParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"detector", "hierarchical_grid or kdtree (the baseline)"}, p.detector);
    f({"tracking", "run the tracker after the chain"}, p.tracking);
    forEachField(p.segmentation, "segmentation", f);
    forEachField(p.hierarchical_grid, "hierarchical_grid", f);
    forEachField(p.kdtree, "kdtree", f);
    forEachField(p.classifier, "classifier", f);
    forEachField(p.box_fitting, "box_fitting", f);
    forEachField(p.tracker, "tracker", f);
    forEachField(p.early, "early", f);
  }
};

/// Empty when valid, else a message naming the first bad field (ranges, the stages' own
/// cross-field rules, an unknown detector name).
std::string validate(const PipelineParams& p);

/// Wall and thread-CPU time of one stage of one revolution.
struct StageTiming {
  const char* name = "";  // "segmentation", "foreground_extraction", "detection",
                          // "classification", "box_fitting", "tracking"
  double wall_ms = 0.0;   // [ms]
  double cpu_ms = 0.0;    // [ms] CPU time of the calling thread
};

/// Everything one revolution gives.
struct PipelineResult {
  std::vector<SegmentClass> labels;            // per input point (process() only)
  LabeledCloud foreground;                     // the detector's input (process() only)
  std::vector<DetectedObject> objects;         // kept objects, classified, with fitted boxes
  std::vector<DetectedObject> rejected;        // the classifier's non-objects
  ObjectClassifierStats classification;        // the classifier's counts of this revolution
  std::vector<StageTiming> timings;            // the stages that ran, in order
  const std::vector<Track>* tracks = nullptr;  // the tracker's tracks (params.tracking), else null
  // finishRevolution() only (early-objects mode), per entry of `objects`: 1 when addSector()
  // already gave it (same points, class and box), and the time field of its last point [s].
  std::vector<std::uint8_t> given_early;
  std::vector<float> last_point_time_s;
  std::size_t early_mismatches = 0;  // objects given early that the revolution does not hold

  /// The time of the stage `name` (0 when it did not run), and of all stages together [ms].
  double wallMs(const std::string& name) const;
  double totalWallMs() const;
  double totalCpuMs() const;
};

/// The objects one sector finished (Pipeline::addSector).
struct EarlySectorResult {
  std::vector<DetectedObject> objects;   // final objects, classified, with fitted boxes
  std::vector<float> last_point_time_s;  // per object: the time field of its last point [s]
  std::size_t rejected = 0;              // final objects the classifier rejected (not given)
  std::size_t pending = 0;               // objects found but not final yet ...
  std::size_t pending_hough = 0;         // ... of which closed but held by the Hough rule
  double swept_deg = 0.0;                // [deg] of the revolution swept so far (0: unknown)
  std::vector<StageTiming> timings;      // the stages of this sector
};

/// Called with the detector's objects before the classifier changes them (scoring the
/// detector alone, feature tables); no copy is made.
using DetectionsObserver =
    std::function<void(const LabeledCloud& foreground, const std::vector<DetectedObject>&)>;

/// The detection chain (see the file comment).
class Pipeline {
 public:
  /// Validates `params` (throws std::invalid_argument naming the field), builds the stages and,
  /// when the classifier is enabled, loads its model (throws std::runtime_error naming the
  /// file).
  explicit Pipeline(const PipelineParams& params);
  /// The same with another detector than the one params.detector names (an external system's
  /// detections, a detector built by a nodelet from its own parameters).
  Pipeline(const PipelineParams& params, std::unique_ptr<ObjectDetector> detector);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// The whole chain on one revolution. With params.tracking, the tracker runs after it in the
  /// sensor frame, at the cloud's header stamp (PCL: microseconds).
  const PipelineResult& process(const CloudXYZIRT& cloud,
                                const DetectionsObserver& observer = nullptr);
  /// The same with the sensor's pose in a fixed frame at `stamp_s` (for the tracker).
  const PipelineResult& process(const CloudXYZIRT& cloud, const Eigen::Isometry3d& world_T_sensor,
                                double stamp_s, const DetectionsObserver& observer = nullptr);
  /// The chain's first two stages only: labels and foreground of the result (objects left
  /// empty), as process() makes them. No tracking.
  const PipelineResult& segment(const CloudXYZIRT& cloud);
  /// The chain after the segmentation, on a foreground made elsewhere (the labels and
  /// foreground of the result are left empty). No tracking.
  const PipelineResult& detect(const LabeledCloud& foreground,
                               const DetectionsObserver& observer = nullptr);

  /// Early objects (early_objects.h): the next `count` points of the revolution `revolution`
  /// (its cloud's header.seq; a new number starts a revolution), in time order. Runs the chain
  /// on the revolution's points so far and returns the objects that are final now and were
  /// not given before (valid until the next call). Ids count on over the revolution. A
  /// revolution whose first sector starts later than that sector's own span (its start was
  /// missed) gives nothing early.
  const EarlySectorResult& addSector(std::uint32_t revolution, const PointXYZIRT* points,
                                     std::size_t count);
  /// At the seam: process() of the whole revolution (whose first points must be those given
  /// to addSector(); otherwise nothing counts as given early), with given_early and
  /// last_point_time_s per object and early_mismatches set. Ends the revolution.
  const PipelineResult& finishRevolution(const CloudXYZIRT& cloud,
                                         const DetectionsObserver& observer = nullptr);
  const PipelineResult& finishRevolution(const CloudXYZIRT& cloud,
                                         const Eigen::Isometry3d& world_T_sensor, double stamp_s,
                                         const DetectionsObserver& observer = nullptr);

  const PipelineParams& params() const { return params_; }
  const PipelineResult& result() const { return result_; }
  ObjectDetector& detector() { return *detector_; }
  /// Replaces the detector (between two revolutions).
  void setDetector(std::unique_ptr<ObjectDetector> detector);
  ObjectClassifier& classifier() { return *classifier_; }
  GridSegmenter& segmenter();  // built on first use (detect() alone never needs it)
  /// The tracker (params.tracking), else null.
  Tracker* tracker() { return tracker_.get(); }
  /// A fresh tracker (params.tracking): a new sequence starts, track ids from 1 again.
  void restartTracker();

 private:
  void detectInto(const LabeledCloud& foreground, const DetectionsObserver& observer);
  void matchEarly(const CloudXYZIRT& cloud);

  // Early objects: the revolution so far, its own segmenter (the classic one may be streaming),
  // and the sorted point indices of the objects given (kept) or finished (rejected).
  struct EarlyState;
  std::unique_ptr<EarlyState> early_;

  PipelineParams params_;
  std::unique_ptr<GridSegmenter> segmenter_;
  std::unique_ptr<ObjectDetector> detector_;
  std::unique_ptr<ObjectClassifier> classifier_;
  std::unique_ptr<BoxFitter> box_fitter_;
  std::unique_ptr<Tracker> tracker_;
  PipelineResult result_;
};

/// The chain's first two stages with a segmenter held elsewhere (the segmentation nodelet's
/// streaming one, the single-stage benchmarks): the class of every point of `cloud`, then the
/// foreground (the detectors' input; skipped when `foreground` is null). Stage times are
/// appended to `timings` when given. Pipeline::process() and segment() run this.
void segmentForeground(GridSegmenter& segmenter, const CloudXYZIRT& cloud,
                       std::vector<SegmentClass>* labels, LabeledCloud* foreground,
                       std::vector<StageTiming>* timings = nullptr);

/// The detector params.detector names, built from its parameters (throws std::invalid_argument).
std::unique_ptr<ObjectDetector> makeDetector(const PipelineParams& params);

}  // namespace core
}  // namespace urban_detection
