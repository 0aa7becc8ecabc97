/// \file object_classifier.h
/// Object classification after either ObjectDetector: per-object features
/// (object_features.h) and a random forest (OpenCV ml RTrees) give each object a class
/// (vehicle, pedestrian, cyclist, other street object) or reject it as a non-object
/// (vegetation, terrain, building, fence, structure). ROS-free.
///
/// Decision rule: the forest's vote shares are class probabilities. An object is kept when
/// P(object) = 1 - P(non_object) is at least the threshold stored in the model (chosen by
/// cross-validation when it was trained) or the one set in the parameters; its class is then
/// the object class with the most votes and its confidence that class's vote share.
///
/// Model file: an OpenCV FileStorage document (YAML, optionally gzip-compressed, `.yml.gz`)
/// written by urban_detection_train_classifier: a format tag and version, the feature
/// parameters and names the forest was trained with (a model trained without the intensity
/// features lists none of them), the class names, the threshold, a description of the
/// training data, and the forest. A missing, unreadable, corrupt or mismatched file (other
/// feature list, other classes, forest of another width) is refused with one message naming
/// the file and what is wrong.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"

namespace cv {
namespace ml {
class RTrees;
}  // namespace ml
}  // namespace cv

namespace urban_detection {
namespace core {

/// Number of classes the model knows (ObjectCategory values 0..kNumObjectCategories-1).
constexpr int kNumObjectCategories = 5;

/// Parses a class name of toString(); false for anything else (also "unknown").
bool parseObjectCategory(const std::string& name, ObjectCategory* c);

/// Options of the training (urban_detection_train_classifier).
struct ClassifierTrainingParams {
  int trees = 32;                 // [-] trees of the forest
  int max_depth = 12;             // [-] depth limit of a tree
  int min_sample_count = 4;       // [-] a node with fewer samples is not split
  int active_var_count = 0;       // [-] features tried per split (0: sqrt of their number)
  bool use_intensity = true;      // [-] false: train without the intensity features
  double object_threshold = 0.5;  // [0..1] P(object) needed to keep an object
  /// [0..1] P(vehicle), P(pedestrian), P(cyclist) that alone keep an object as that class
  /// (1: only the object threshold decides)
  std::array<double, 3> class_thresholds{{1.0, 1.0, 1.0}};
  /// [0..1] P(object) from which an object below the thresholds stays as an uncertain
  /// other_object (1: none)
  double uncertain_threshold = 1.0;
  /// [0..1] class balance of the training rows: each row weighs (rows / (classes x rows of
  /// its class))^class_balance (0: every row alike, 1: every class alike)
  double class_balance = 0.0;
  std::string description;  // free text stored in the model (data, seed, command)
  /// The data groups the rows come from (SemanticKITTI sequences: "00", "01", ...), stored in
  /// the model (key training_sequences) so an evaluation can say when it scores them.
  std::vector<std::string> training_groups;
};

/// ClassifierTrainingParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<ClassifierTrainingParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"trees", "", 1, 10000, "trees of the forest"}, p.trees);
    f({"max_depth", "", 1, 64, "depth limit of a tree"}, p.max_depth);
    f({"min_sample_count", "", 1, 100000, "a node with fewer samples is not split"},
      p.min_sample_count);
    f({"active_var_count", "", 0, kNumObjectFeatures,
       "features tried per split (0: sqrt of their number)"},
      p.active_var_count);
    f({"use_intensity", "false: train without the intensity features"}, p.use_intensity);
    f({"object_threshold", "", 0.0, 1.0, "P(object) needed to keep an object"}, p.object_threshold);
    f({"class_threshold_vehicle", "", 0.0, 1.0, "P(vehicle) that alone keeps a vehicle"},
      p.class_thresholds[0]);
    f({"class_threshold_pedestrian", "", 0.0, 1.0, "P(pedestrian) that alone keeps a pedestrian"},
      p.class_thresholds[1]);
    f({"class_threshold_cyclist", "", 0.0, 1.0, "P(cyclist) that alone keeps a cyclist"},
      p.class_thresholds[2]);
    f({"uncertain_threshold", "", 0.0, 1.0,
       "P(object) from which an object stays as an uncertain other_object (1: none)"},
      p.uncertain_threshold);
    f({"class_balance", "", 0.0, 1.0,
       "class balance of the training rows (0: every row alike, 1: every class alike)"},
      p.class_balance);
    f({"description", "free text stored in the model"}, p.description);
  }
};

/// How the vote shares become a class (stored in the model, chosen by the training tool).
/// In order: an object class whose P(class) reaches its class threshold (the largest
/// P(class) / threshold among those that do); else, when P(object) = 1 - P(non_object)
/// reaches the object threshold, the object class with the most votes; else, when P(object)
/// reaches the uncertain threshold, an uncertain other_object whose confidence is P(object);
/// else non_object.
struct ClassDecision {
  double object_threshold = 0.5;
  std::array<double, 3> class_thresholds{{1.0, 1.0, 1.0}};  // vehicle, pedestrian, cyclist
  double uncertain_threshold = 1.0;
};

/// The class and confidence of one object's vote shares under `decision`; `keep_uncertain`
/// false turns the uncertain band into non_object. `uncertain` (optional) tells whether the
/// object was kept by the uncertain band.
ObjectCategory decideClass(const std::array<float, 5>& p, const ClassDecision& decision,
                           bool keep_uncertain, float* confidence, bool* uncertain = nullptr);

/// Empty when valid, else a message naming the first out-of-range field and its range.
std::string validate(const ClassifierTrainingParams& p);

/// A trained forest with its feature list and threshold.
class ObjectClassifierModel {
 public:
  ObjectClassifierModel();
  ~ObjectClassifierModel();
  ObjectClassifierModel(ObjectClassifierModel&&) noexcept;
  ObjectClassifierModel& operator=(ObjectClassifierModel&&) noexcept;

  /// Trains a forest on feature rows and their classes (kUnknown rows are skipped).
  /// Deterministic: the same rows and parameters give the same forest and file.
  /// A class without rows gets probability 0. Throws std::invalid_argument on invalid
  /// parameters or without rows of non_object or of any object class.
  static ObjectClassifierModel train(const std::vector<ObjectFeatureVector>& features,
                                     const std::vector<ObjectCategory>& classes,
                                     const ClassifierTrainingParams& params,
                                     const ObjectFeatureParams& feature_params);

  /// Reads a model file; throws std::runtime_error naming the file and the problem.
  static ObjectClassifierModel load(const std::string& path);
  /// Writes the model file (".gz" suffix: compressed); throws std::runtime_error on failure.
  void save(const std::string& path) const;

  bool trained() const;
  bool useIntensity() const { return use_intensity_; }
  double objectThreshold() const { return decision_.object_threshold; }
  void setObjectThreshold(double t) { decision_.object_threshold = t; }
  const ClassDecision& decision() const { return decision_; }
  void setDecision(const ClassDecision& d) { decision_ = d; }
  const ObjectFeatureParams& featureParams() const { return feature_params_; }
  const std::string& description() const { return description_; }
  /// The groups (SemanticKITTI sequences) the model was trained on: its training_sequences
  /// key, or for a model written before that key the sequences its description names
  /// ("... scans of sequences 00 01 ... ("); empty when unknown.
  const std::vector<std::string>& trainingGroups() const { return training_groups_; }
  int trees() const;

  /// Class probabilities (vote shares, indexed by ObjectCategory value) of each row, from the
  /// forest's compact copy: 8-byte nodes in depth-first order (a left child follows its
  /// parent), walked tree by tree over all rows (a tree's nodes stay in the caches for the
  /// frame's objects), the votes counted and turned into shares by a table of the sums
  /// predictPlain() forms. Equal bit for bit to predictPlain().
  void predict(const std::vector<ObjectFeatureVector>& features,
               std::vector<std::array<float, kNumObjectCategories>>* probabilities) const;
  /// The plain walk of predict(): row by row, tree by tree through the flat copy of OpenCV's
  /// node array, each vote added to its class's share.
  void predictPlain(const std::vector<ObjectFeatureVector>& features,
                    std::vector<std::array<float, kNumObjectCategories>>* probabilities) const;
  /// The same through OpenCV's RTrees::getVotes: the plain reference of predict() (tests).
  void predictReference(const std::vector<ObjectFeatureVector>& features,
                        std::vector<std::array<float, kNumObjectCategories>>* probabilities) const;

 private:
  // One node of the flattened forest: an inner node tests feature `var` <= `threshold` and
  // goes to `left` (true) or `right`; a leaf (var < 0) votes for class `label`.
  struct FlatNode {
    std::int32_t var;
    float threshold;
    std::int32_t left, right;
    std::int32_t label;
  };
  // One node of the compact forest: `meta` = var | child << kVarBits; an inner node tests
  // feature var <= threshold and goes to the next node (true) or to node `child`; a leaf
  // (var == kLeaf) votes for class `child` (kNumObjectCategories: no class).
  struct CompactNode {
    float threshold;
    std::uint32_t meta;
  };
  static constexpr int kVarBits = 6;
  static constexpr std::uint32_t kLeaf = (1u << kVarBits) - 1;
  int usedFeatures() const;
  void flatten();  // builds flat_ and roots_ from forest_
  void compact();  // builds compact_, compact_roots_ and vote_sums_ from the checked flat_
  std::shared_ptr<cv::ml::RTrees> forest_;  // cv::Ptr is std::shared_ptr in OpenCV 4
  std::vector<FlatNode> flat_;
  std::vector<std::int32_t> roots_;
  std::vector<CompactNode> compact_;
  std::vector<std::uint32_t> compact_roots_;
  std::vector<float> vote_sums_;  // [k]: k votes added one by one, as predictPlain() does
  bool use_intensity_ = true;
  ClassDecision decision_;
  ObjectFeatureParams feature_params_;
  std::string description_;
  std::vector<std::string> training_groups_;
};

/// Parameters of the classification stage.
struct ObjectClassifierParams {
  bool enabled = false;                  // [-] false: objects pass unclassified ("unknown"); the
                                         //     shipped config/classification.yaml turns it on
  std::string model_path;                // model file (urban_detection_train_classifier)
  double min_object_probability = -1.0;  // [-1..1] keep an object when P(object) >= this;
                                         //   negative: the threshold stored in the model
  bool reject_non_objects = true;        // [-] false: non-objects stay in the output, labelled
                                         //     "non_object"
  bool keep_uncertain = true;            // [-] objects the model is unsure of stay in the
                                         //     output as other_object with their low confidence
};

/// ObjectClassifierParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<ObjectClassifierParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"enabled", "false: objects pass unclassified"}, p.enabled);
    f({"model", "model file (urban_detection_train_classifier); relative to the file naming it"},
      p.model_path);
    f({"min_object_probability", "", -1.0, 1.0,
       "keep an object when P(object) >= this; negative: the model's threshold"},
      p.min_object_probability);
    f({"reject_non_objects", "false: non-objects stay in the output, labelled non_object"},
      p.reject_non_objects);
    f({"keep_uncertain",
       "objects the model is unsure of stay in the output as other_object with their low "
       "confidence; false: they are non-objects"},
      p.keep_uncertain);
  }
};

/// Empty when valid, else a message naming the first out-of-range field and its range.
std::string validate(const ObjectClassifierParams& p);

struct ObjectClassifierStats {
  std::size_t input = 0;                                     // objects given to apply()
  std::size_t kept = 0;                                      // objects in the output
  std::size_t rejected = 0;                                  // non-objects removed
  std::size_t uncertain = 0;                                 // kept as uncertain other_object
  std::array<std::size_t, kNumObjectCategories> by_class{};  // decisions per class
};

/// The classification stage. Holds the model and its scratch buffers between frames.
class ObjectClassifier {
 public:
  /// Validates the parameters and, when enabled, loads the model; throws std::invalid_argument
  /// (parameters) or std::runtime_error (model file) with a message naming the problem.
  explicit ObjectClassifier(const ObjectClassifierParams& params);
  /// Uses an already loaded model (its threshold unless params.min_object_probability >= 0).
  ObjectClassifier(const ObjectClassifierParams& params, ObjectClassifierModel model);

  const ObjectClassifierParams& params() const { return params_; }
  const ObjectClassifierModel& model() const { return model_; }
  /// The P(object) threshold in force.
  double threshold() const;
  /// Changes the decision (threshold override, rejection) without reloading the model; throws
  /// std::invalid_argument when min_object_probability is not in [-1, 1].
  void setDecision(double min_object_probability, bool reject_non_objects,
                   bool keep_uncertain = true);

  /// Classifies the objects of one frame (`foreground` is the detector's input) and fills
  /// category and class_confidence. Non-objects are moved to `rejected` (when not null) and
  /// removed when reject_non_objects is set; the kept objects are renumbered 1..N. Disabled:
  /// nothing changes.
  ObjectClassifierStats apply(const LabeledCloud& foreground, std::vector<DetectedObject>* objects,
                              std::vector<DetectedObject>* rejected = nullptr);

  /// The features of the last apply(), one row per input object (in input order).
  const std::vector<ObjectFeatureVector>& lastFeatures() const { return features_; }

 private:
  ObjectClassifierParams params_;
  ObjectClassifierModel model_;
  ObjectFeatureExtractor extractor_;
  std::vector<ObjectFeatureVector> features_;
  std::vector<std::array<float, kNumObjectCategories>> probabilities_;
  std::vector<DetectedObject> kept_;
};

}  // namespace core
}  // namespace urban_detection
