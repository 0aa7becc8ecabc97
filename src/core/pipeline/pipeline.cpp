#include "urban_detection/core/pipeline/pipeline.h"

#include <time.h>

#include <chrono>
#include <stdexcept>
#include <utility>

namespace urban_detection {
namespace core {

namespace {

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

// Times one stage from construction to stop(), appending it to `timings`.
class StageClock {
 public:
  explicit StageClock(const char* name)
      : name_(name), wall_(std::chrono::steady_clock::now()), cpu_(threadCpuMs()) {}
  void stop(std::vector<StageTiming>* timings) const {
    StageTiming t;
    t.name = name_;
    t.wall_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_).count();
    t.cpu_ms = threadCpuMs() - cpu_;
    timings->push_back(t);
  }

 private:
  const char* name_;
  std::chrono::steady_clock::time_point wall_;
  double cpu_;
};

template <class Params>
std::string nested(const std::string& prefix, const Params& p) {
  const std::string error = validate(p);
  return error.empty() ? "" : prefix + ": " + error;
}

// validate() but for the detector's name (a caller may bring its own detector).
std::string validateStages(const PipelineParams& p) {
  const std::string range = checkFieldRanges(p);  // names the nested field ("segmentation/...")
  if (!range.empty()) return range;
  for (const std::string& e :
       {nested("segmentation", p.segmentation), nested("hierarchical_grid", p.hierarchical_grid),
        nested("kdtree", p.kdtree), nested("classifier", p.classifier),
        nested("box_fitting", p.box_fitting), nested("tracker", p.tracker)}) {
    if (!e.empty()) return e;
  }
  return "";
}

}  // namespace

std::string validate(const PipelineParams& p) {
  if (p.detector != "hierarchical_grid" && p.detector != "kdtree") {
    return "parameter 'detector' = '" + p.detector + "': accepted hierarchical_grid or kdtree";
  }
  return validateStages(p);
}

double PipelineResult::wallMs(const std::string& name) const {
  double ms = 0.0;
  for (const StageTiming& t : timings) {
    if (name == t.name) ms += t.wall_ms;
  }
  return ms;
}

double PipelineResult::totalWallMs() const {
  double ms = 0.0;
  for (const StageTiming& t : timings) ms += t.wall_ms;
  return ms;
}

double PipelineResult::totalCpuMs() const {
  double ms = 0.0;
  for (const StageTiming& t : timings) ms += t.cpu_ms;
  return ms;
}

std::unique_ptr<ObjectDetector> makeDetector(const PipelineParams& params) {
  if (params.detector == "kdtree") return std::make_unique<KdTreeDetector>(params.kdtree);
  if (params.detector == "hierarchical_grid") {
    return std::make_unique<HierarchicalGridDetector>(params.hierarchical_grid);
  }
  throw std::invalid_argument("parameter 'detector' = '" + params.detector +
                              "': accepted hierarchical_grid or kdtree");
}

Pipeline::Pipeline(const PipelineParams& params) : Pipeline(params, makeDetector(params)) {}

Pipeline::Pipeline(const PipelineParams& params, std::unique_ptr<ObjectDetector> detector)
    : params_(params), detector_(std::move(detector)) {
  const std::string error = validateStages(params_);
  if (!error.empty()) throw std::invalid_argument(error);
  if (!detector_) throw std::invalid_argument("Pipeline: no detector");
  classifier_ = std::make_unique<ObjectClassifier>(params_.classifier);
  box_fitter_ = std::make_unique<BoxFitter>(params_.box_fitting);
  if (params_.tracking) tracker_ = std::make_unique<Tracker>(params_.tracker);
  result_.timings.reserve(8);
}

Pipeline::~Pipeline() = default;

void Pipeline::setDetector(std::unique_ptr<ObjectDetector> detector) {
  if (!detector) throw std::invalid_argument("Pipeline: no detector");
  detector_ = std::move(detector);
}

void Pipeline::restartTracker() {
  if (tracker_) tracker_ = std::make_unique<Tracker>(params_.tracker);
}

GridSegmenter& Pipeline::segmenter() {
  if (!segmenter_) segmenter_ = std::make_unique<GridSegmenter>(params_.segmentation);
  return *segmenter_;
}

const PipelineResult& Pipeline::process(const CloudXYZIRT& cloud,
                                        const DetectionsObserver& observer) {
  // PCL stamps are microseconds.
  return process(cloud, Eigen::Isometry3d::Identity(),
                 1e-6 * static_cast<double>(cloud.header.stamp), observer);
}

const PipelineResult& Pipeline::process(const CloudXYZIRT& cloud,
                                        const Eigen::Isometry3d& world_T_sensor, double stamp_s,
                                        const DetectionsObserver& observer) {
  result_.timings.clear();
  GridSegmenter& seg = segmenter();
  const StageClock segmentation("segmentation");
  seg.segment(cloud, &result_.labels);
  segmentation.stop(&result_.timings);
  const StageClock foreground("foreground_extraction");
  extractForeground(cloud, result_.labels, &result_.foreground);
  foreground.stop(&result_.timings);
  detectInto(result_.foreground, observer);
  if (tracker_) {
    const StageClock tracking("tracking");
    tracker_->update(result_.objects, world_T_sensor, stamp_s);
    tracking.stop(&result_.timings);
  }
  result_.tracks = tracker_ ? &tracker_->tracks() : nullptr;
  return result_;
}

const PipelineResult& Pipeline::detect(const LabeledCloud& foreground,
                                       const DetectionsObserver& observer) {
  result_.timings.clear();
  result_.labels.clear();
  result_.foreground.clear();
  result_.tracks = nullptr;
  detectInto(foreground, observer);
  return result_;
}

void Pipeline::detectInto(const LabeledCloud& foreground, const DetectionsObserver& observer) {
  const StageClock detection("detection");
  detector_->detect(foreground, &result_.objects);
  detection.stop(&result_.timings);
  if (observer) observer(foreground, result_.objects);
  result_.rejected.clear();
  if (classifier_->params().enabled) {
    const StageClock classification("classification");
    result_.classification = classifier_->apply(foreground, &result_.objects, &result_.rejected);
    classification.stop(&result_.timings);
  } else {
    result_.classification = ObjectClassifierStats();
    result_.classification.input = result_.classification.kept = result_.objects.size();
  }
  if (box_fitter_->params().enabled) {
    const StageClock boxes("box_fitting");
    box_fitter_->fit(foreground, &result_.objects);
    boxes.stop(&result_.timings);
  }
}

}  // namespace core
}  // namespace urban_detection
