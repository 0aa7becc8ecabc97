/// \file training.h
/// The training protocol of the object classifier (urban_detection_train_classifier) on
/// labelled scans, as a library: the training label of each detection by the evaluation's
/// rules, the training set of a set of sequences ("groups"), the paper's scoring of the kept
/// detections, the choice of a decision (object threshold, class thresholds, uncertain band) by
/// an inner cross-validation over sequences, and the leave-one-sequence-out folds: a forest
/// trained on every other sequence classifies the held-out one. Augmented and simulated frames
/// are trained on and never scored. ROS-free.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/evaluation/augmentation.h"
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/evaluation.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {

using ClassProbabilities = std::array<float, kNumObjectCategories>;

/// One detector's output on one frame, with the features and labels of its detections.
struct TrainingDetections {
  std::vector<DetectedObject> objects;
  std::vector<ObjectFeatureVector> features;
  std::vector<ObjectCategory> labels;        ///< training label (kUnknown: not trained on)
  std::vector<ClassProbabilities> held_out;  ///< leave-one-sequence-out probabilities
  std::vector<DetectionVerdict> verdicts;    ///< the scoring's verdicts (labelled frames)
  std::vector<std::string> contents;         ///< detectionContent() (labelled frames)
};

/// One frame of the training table.
struct TrainingFrame {
  std::string id, group;      ///< frame id, its sequence
  bool augmented = false;     ///< made by augmentSequence (or simulated): trained on, never scored
  bool always_train = false;  ///< simulated: in the training set of every fold
  EvalFrame gt;
  std::vector<float> gt_range;                ///< per GT object, its horizontal distance [m]
  std::vector<TrainingDetections> detectors;  ///< [0]: the one the forest learns from
};

/// A false detection made mostly of a real object's points (a fragment or a merge): a
/// non-object (kReject) or left out (kSkip).
enum class FragmentRule { kReject, kSkip };

/// The object threshold alone (kObject) or, after it, each class threshold and the uncertain
/// band in turn (kClass).
enum class DecisionRule { kObject, kClass };

/// The training label of detection `d` of a frame scored as `m`: a true detection takes its
/// GT object's class; an ignored one is an other street object when `content` (what most of
/// its points are, detectionContent()) is "other-object", else not trained on; a false one is
/// a non-object, or not trained on when it is a fragment ("part_of_...") under kSkip.
ObjectCategory trainingLabel(const FrameMatch& m, std::size_t d, const EvalFrame& gt,
                             const std::string& content, FragmentRule fragments);

/// The rows and labels of detector 0 over the frames whose group is in `groups` (and the
/// always-trained frames).
void trainingSet(const std::vector<TrainingFrame>& frames, const std::set<std::string>& groups,
                 std::vector<ObjectFeatureVector>* x, std::vector<ObjectCategory>* y);

/// Score and breakdown of a set of frames.
struct TrainingScore {
  DetectionScore score;       ///< under EvaluationParams::min_points
  DetectionScore all;         ///< every object (N = 1)
  RecallBreakdown breakdown;  ///< per class, points, range
  void add(const TrainingScore& o);
};

/// Class probabilities of detection `i` of frame `fi`.
using ProbabilityFn = std::function<ClassProbabilities(std::size_t fi, std::size_t i)>;
/// Per frame and detection, the class a later stage gave (kUnknown: the decision's own).
using ClassOverride = std::map<std::size_t, std::vector<ObjectCategory>>;

/// Scores the scored frames of `groups` for detector k, classified by `decision` (null: the
/// detector alone, every detection kept) with `probs`. Adds per group to `by_group` when not
/// null.
TrainingScore scoreFrames(const std::vector<TrainingFrame>& frames,
                          const std::set<std::string>& groups, std::size_t k,
                          const ClassDecision* decision, const ProbabilityFn& probs,
                          const EvaluationParams& ep,
                          std::map<std::string, TrainingScore>* by_group,
                          const ClassOverride* override_class = nullptr);

/// What the decision is chosen for: the pooled F and, as much, the mean recall of the classes
/// present (vehicle, pedestrian, cyclist): missing a person costs more than keeping a bush.
double decisionObjective(const TrainingScore& s);

/// Thresholds tried when choosing a decision (0.05 to 0.95 in steps of 0.05).
std::vector<double> thresholdGrid();

/// A forest trained on detector 0's detections of the frames of `groups`.
ObjectClassifierModel trainOn(const std::vector<TrainingFrame>& frames,
                              const std::set<std::string>& groups,
                              const ClassifierTrainingParams& params,
                              const ObjectFeatureParams& fp);

/// Time as evidence: a sequence's scans in order through the tracker in the world frame of
/// `poses` (indexed by the scan number of the frame id "SEQ/NNNNNN"), every detection with its
/// class (non-objects included, with P(non_object)). A confirmed track whose accumulated class
/// is an object class makes its detection an object of that class: written to `out` per frame
/// (kUnknown: the scan's own decision stands).
struct TemporalStats {
  std::size_t kept = 0;       ///< rejected by their scan, kept by their track's class
  std::size_t reclassed = 0;  ///< kept by their scan, class taken from their track
};
void temporalClasses(const std::vector<TrainingFrame>& frames, const std::string& group,
                     std::size_t k, const ClassDecision& decision, const ProbabilityFn& probs,
                     const std::vector<Eigen::Isometry3d>& poses,
                     const TrackerParams& tracker_params, ClassOverride* out, TemporalStats* stats);

/// Time as evidence for every group: temporalClasses() of detector 0's held-out
/// probabilities under each fold's decision, with the poses of the group's sequence folder
/// (`dir` itself when it is one sequence, else dir/sequences/<group>). A group without poses
/// is skipped with a warning on stderr, and the result is false.
bool temporalEvidence(const std::vector<TrainingFrame>& frames,
                      const std::vector<std::string>& groups, const std::string& dir,
                      const std::map<std::string, ClassDecision>& fold_decision, ClassOverride* out,
                      TemporalStats* stats);

/// The decision's thresholds as "object/vehicle/pedestrian/cyclist/uncertain" (2 decimals),
/// and as a JSON object.
std::string decisionText(const ClassDecision& d);
std::string decisionJson(const ClassDecision& d);

/// The decision maximising decisionObjective() on `groups` (detector 0) under `probs`.
ClassDecision bestDecision(const std::vector<TrainingFrame>& frames,
                           const std::set<std::string>& groups, const ProbabilityFn& probs,
                           const EvaluationParams& ep, DecisionRule rule, double uncertain_band);

/// One fold over groups.
struct GroupFold {
  std::set<std::string> train, test;
};
/// `folds` folds: group g is tested in fold g % folds and trained on in the others.
std::vector<GroupFold> crossValidationFolds(const std::vector<std::string>& groups, int folds);

/// Decision for a model trained on `groups`: inner cross-validation over the groups (3 folds,
/// fewer with fewer groups; params.object_threshold alone with fewer than 2 groups).
ClassDecision innerDecision(std::vector<TrainingFrame>* frames,
                            const std::vector<std::string>& groups,
                            const ClassifierTrainingParams& params, const ObjectFeatureParams& fp,
                            const EvaluationParams& ep, DecisionRule rule, double uncertain_band);

/// Every group but `held_out`, in order.
std::vector<std::string> leaveOneOut(const std::vector<std::string>& groups,
                                     const std::string& held_out);

/// Training rows per class of detector 0 over every frame; `*not_trained_on` receives the
/// number of its detections labelled kUnknown.
using LabelCounts = std::array<std::size_t, kNumObjectCategories>;
LabelCounts trainingLabelCounts(const std::vector<TrainingFrame>& frames,
                                std::size_t* not_trained_on);

/// The groups of the scored (not augmented) frames, in order of appearance.
std::vector<std::string> scoredGroups(const std::vector<TrainingFrame>& frames);

/// Leave-one-sequence-out: for each group, a forest trained on the other groups (decision from
/// innerDecision() when `auto_threshold`, else tp.object_threshold) fills the held_out
/// probabilities of every detector of the held-out group's frames. Returns each fold's
/// decision by held-out group.
std::map<std::string, ClassDecision> leaveOneSequenceOut(
    std::vector<TrainingFrame>* frames, const std::vector<std::string>& groups,
    const ClassifierTrainingParams& tp, const ObjectFeatureParams& fp, const EvaluationParams& ep,
    bool auto_threshold, DecisionRule rule, double uncertain_band);

/// The held-out probabilities of detector k (after leaveOneSequenceOut()); `frames` must
/// outlive the function.
ProbabilityFn heldOutProbabilities(const std::vector<TrainingFrame>& frames, std::size_t k);

/// [label][prediction] counts.
using CategoryConfusion =
    std::array<std::array<std::size_t, kNumObjectCategories>, kNumObjectCategories>;
/// Pooled confusion of the held-out predictions of detector 0, each frame classified with its
/// fold's decision (labelled detections of scored frames only).
CategoryConfusion heldOutConfusion(const std::vector<TrainingFrame>& frames,
                                   const std::map<std::string, ClassDecision>& fold_decision);

/// The confusion as the text table urban_detection_train_classifier prints (a header line of
/// the predictions, then one line per label) and as a JSON array of rows.
std::string confusionTable(const CategoryConfusion& confusion);
std::string confusionJson(const CategoryConfusion& confusion);

/// A detection score as one row of the leave-one-sequence-out table ("NO MO FO P R F") and
/// as a JSON object {"no", "mo", "fo", "precision", "recall", "f_rate"}.
std::string trainingScoreRow(const DetectionScore& s);
std::string trainingScoreJson(const DetectionScore& s);

/// The first `max_frames` revolutions of a simulated drive (ground-truth file and pcap of
/// urban_detection_simulate, nominal calibration) through pipelines[0] as training frames
/// ("sim/<id>", group "sim", augmented: trained on in every fold, never scored), appended to
/// `frames`. Returns the labelled rows added. Throws std::runtime_error when the drive cannot
/// be read.
std::size_t addSimTrainingFrames(const std::string& gt, const std::string& pcap,
                                 std::size_t max_frames,
                                 const std::vector<std::unique_ptr<Pipeline>>& pipelines,
                                 ObjectFeatureExtractor* extractor, FragmentRule fragments,
                                 std::vector<TrainingFrame>* frames);

/// A labelled frame through the first `detectors` pipelines: pipelines[0] runs the whole chain
/// on the cloud, the others detect on its foreground; every detection is scored against the
/// frame's ground truth (default EvaluationParams), its features computed and its training
/// label set by trainingLabel() with its detectionContent(). The result has
/// pipelines.size() detectors (those not run are empty); id, group and detectors are set,
/// gt and gt_range are left to the caller.
TrainingFrame labelledTrainingFrame(const Frame& f, const Dataset& ds, const std::string& group,
                                    const std::vector<std::unique_ptr<Pipeline>>& pipelines,
                                    std::size_t detectors, ObjectFeatureExtractor* extractor,
                                    FragmentRule fragments);

/// A frame made by augmentSequence() (`gt` from its labels), through pipelines[0] only: the
/// detections matched to a pasted object (instance id >= kPastedInstanceBase) are labelled
/// with its class, the others are not trained on (the rest of the scan is in the table
/// already); adds their count to `*pasted`. Marked augmented (never scored).
TrainingFrame augmentedTrainingFrame(const std::string& id, const std::string& group,
                                     const CloudXYZIRT& cloud, const EvalFrame& gt,
                                     const std::vector<std::unique_ptr<Pipeline>>& pipelines,
                                     ObjectFeatureExtractor* extractor, std::size_t* pasted);

/// The scan of a SemanticKITTI frame with its labels for augmentSequence(): per point its
/// dataset class | GT object id << 16.
LabelledScan labelledScanOf(const Frame& f);

}  // namespace core
}  // namespace urban_detection
