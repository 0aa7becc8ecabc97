#include "urban_detection/core/pipeline/pipeline.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>
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
        nested("box_fitting", p.box_fitting), nested("tracker", p.tracker),
        nested("early", p.early)}) {
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

struct Pipeline::EarlyState {
  explicit EarlyState(const PipelineParams& p) : segmenter(p.segmentation), completion(p.early) {}
  bool active = false;
  bool joined_late = false;
  std::uint32_t revolution = 0;
  CloudXYZIRT cloud;  // the revolution so far
  GridSegmenter segmenter;
  SectorCompletion completion;
  std::vector<SegmentClass> labels;
  LabeledCloud foreground;
  std::vector<DetectedObject> objects, candidates, rejected;
  std::vector<std::uint8_t> final;
  std::vector<std::uint32_t> key;
  // Sorted point indices of every object finished so far -> the object given (kept), or an
  // empty object (rejected: nothing given).
  std::map<std::vector<std::uint32_t>, DetectedObject> finished;
  std::map<std::vector<std::uint32_t>, bool> given;  // kept objects given early
  std::uint32_t next_id = 1;
  EarlySectorResult result;
};

namespace {

void sortedIndices(const DetectedObject& o, std::vector<std::uint32_t>* key) {
  key->assign(o.indices.begin(), o.indices.end());
  std::sort(key->begin(), key->end());
}

float lastPointTime(const CloudXYZIRT& cloud, const DetectedObject& o) {
  float t = -std::numeric_limits<float>::infinity();
  for (const std::uint32_t i : o.indices) {
    if (i < cloud.size()) t = std::max(t, cloud[i].time);
  }
  return t;
}

bool sameObject(const DetectedObject& a, const DetectedObject& b) {
  return a.category == b.category && a.class_confidence == b.class_confidence &&
         a.obb_center == b.obb_center && a.obb_size == b.obb_size &&
         a.obb_yaw_rad == b.obb_yaw_rad && a.min_pt == b.min_pt && a.max_pt == b.max_pt &&
         a.centroid == b.centroid;
}

}  // namespace

Pipeline::~Pipeline() = default;

const EarlySectorResult& Pipeline::addSector(std::uint32_t revolution, const PointXYZIRT* points,
                                             std::size_t count) {
  if (!early_) early_ = std::make_unique<EarlyState>(params_);
  EarlyState& e = *early_;
  EarlySectorResult& out = e.result;
  out.objects.clear();
  out.last_point_time_s.clear();
  out.timings.clear();
  out.rejected = out.pending = out.pending_hough = 0;
  if (!e.active || revolution != e.revolution) {
    e.active = true;
    e.revolution = revolution;
    e.cloud.clear();
    e.finished.clear();
    e.given.clear();
    e.next_id = 1;
    e.segmenter.restartStream();
    // A revolution joined after its start (the first sectors missed: its first point is later
    // than this sector's span) has no seam to measure from; its objects all come at the seam.
    e.joined_late = count > 1 && points[0].time > points[count - 1].time - points[0].time;
  }
  if (e.joined_late) return out;
  e.cloud.header.seq = revolution;
  e.cloud.insert(e.cloud.end(), points, points + count);
  e.cloud.width = static_cast<std::uint32_t>(e.cloud.size());
  e.cloud.height = 1;
  const StageClock segmentation("segmentation");
  // Each sector's points are binned once; the grid so far is segmented at every sector.
  e.segmenter.addPoints(revolution, points, count);
  e.segmenter.segmentSoFar(e.cloud, &e.labels);
  segmentation.stop(&out.timings);
  const StageClock foreground("foreground_extraction");
  extractForeground(e.cloud, e.labels, &e.foreground);
  foreground.stop(&out.timings);
  const StageClock detection("detection");
  detector_->detect(e.foreground, &e.objects);
  e.completion.updateSweep(e.cloud);
  e.completion.finalObjects(e.cloud, e.segmenter, e.objects, &e.final);
  out.pending_hough = e.completion.lastHough();
  out.swept_deg = e.completion.sweptRad() * 180.0 / 3.14159265358979323846;
  e.candidates.clear();
  for (std::size_t k = 0; k < e.objects.size(); ++k) {
    if (!e.final[k]) {
      ++out.pending;
      continue;
    }
    sortedIndices(e.objects[k], &e.key);
    if (e.finished.count(e.key) != 0) continue;
    e.candidates.push_back(std::move(e.objects[k]));
  }
  detection.stop(&out.timings);
  if (e.candidates.empty()) return out;
  e.rejected.clear();
  if (classifier_->params().enabled) {
    const StageClock classification("classification");
    classifier_->apply(e.foreground, &e.candidates, &e.rejected);
    classification.stop(&out.timings);
  }
  if (box_fitter_->params().enabled) {
    const StageClock boxes("box_fitting");
    box_fitter_->fit(e.foreground, &e.candidates);
    boxes.stop(&out.timings);
  }
  for (const DetectedObject& r : e.rejected) {
    sortedIndices(r, &e.key);
    e.finished.emplace(e.key, DetectedObject());
    ++out.rejected;
  }
  for (DetectedObject& o : e.candidates) {
    o.id = e.next_id++;
    sortedIndices(o, &e.key);
    e.finished.emplace(e.key, o);
    e.given.emplace(e.key, false);
    out.last_point_time_s.push_back(lastPointTime(e.cloud, o));
    out.objects.push_back(std::move(o));
  }
  return out;
}

const PipelineResult& Pipeline::finishRevolution(const CloudXYZIRT& cloud,
                                                 const DetectionsObserver& observer) {
  process(cloud, observer);
  matchEarly(cloud);
  return result_;
}

const PipelineResult& Pipeline::finishRevolution(const CloudXYZIRT& cloud,
                                                 const Eigen::Isometry3d& world_T_sensor,
                                                 double stamp_s,
                                                 const DetectionsObserver& observer) {
  process(cloud, world_T_sensor, stamp_s, observer);
  matchEarly(cloud);
  return result_;
}

void Pipeline::matchEarly(const CloudXYZIRT& cloud) {
  result_.given_early.assign(result_.objects.size(), 0);
  result_.last_point_time_s.resize(result_.objects.size());
  result_.early_mismatches = 0;
  for (std::size_t k = 0; k < result_.objects.size(); ++k) {
    result_.last_point_time_s[k] = lastPointTime(cloud, result_.objects[k]);
  }
  if (!early_ || !early_->active) return;
  EarlyState& e = *early_;
  e.active = false;
  // The early points must be the first points of this cloud (same revolution).
  bool same = cloud.header.seq == e.revolution && e.cloud.size() <= cloud.size();
  for (std::size_t i = 0; same && i < e.cloud.size(); ++i) {
    const PointXYZIRT &a = e.cloud[i], &b = cloud[i];
    same = (a.x == b.x || (a.x != a.x && b.x != b.x)) &&
           (a.y == b.y || (a.y != a.y && b.y != b.y)) &&
           (a.z == b.z || (a.z != a.z && b.z != b.z)) && a.time == b.time;
  }
  for (std::size_t k = 0; k < result_.objects.size(); ++k) {
    sortedIndices(result_.objects[k], &e.key);
    const auto f = e.finished.find(e.key);
    if (f == e.finished.end() || f->second.indices.empty()) continue;
    if (same && sameObject(f->second, result_.objects[k])) {
      result_.given_early[k] = 1;
      e.given[e.key] = true;
    }
  }
  for (const auto& g : e.given) result_.early_mismatches += g.second ? 0 : 1;
}

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
  segmentForeground(segmenter(), cloud, &result_.labels, &result_.foreground, &result_.timings);
  detectInto(result_.foreground, observer);
  if (tracker_) {
    const StageClock tracking("tracking");
    tracker_->update(result_.objects, world_T_sensor, stamp_s);
    tracking.stop(&result_.timings);
  }
  result_.tracks = tracker_ ? &tracker_->tracks() : nullptr;
  return result_;
}

const PipelineResult& Pipeline::segment(const CloudXYZIRT& cloud) {
  result_.timings.clear();
  result_.objects.clear();
  result_.rejected.clear();
  result_.classification = ObjectClassifierStats();
  result_.tracks = nullptr;
  segmentForeground(segmenter(), cloud, &result_.labels, &result_.foreground, &result_.timings);
  return result_;
}

void segmentForeground(GridSegmenter& segmenter, const CloudXYZIRT& cloud,
                       std::vector<SegmentClass>* labels, LabeledCloud* foreground,
                       std::vector<StageTiming>* timings) {
  const StageClock segmentation("segmentation");
  segmenter.segment(cloud, labels);
  if (timings) segmentation.stop(timings);
  if (!foreground) return;
  const StageClock extraction("foreground_extraction");
  extractForeground(cloud, *labels, foreground);
  if (timings) extraction.stop(timings);
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
