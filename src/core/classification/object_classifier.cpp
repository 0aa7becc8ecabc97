#include "urban_detection/core/classification/object_classifier.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

namespace urban_detection {
namespace core {

namespace {

constexpr const char* kFormat = "urban_detection_object_classifier";
constexpr int kVersion = 1;

int featureCount(bool use_intensity) {
  return use_intensity ? kNumObjectFeatures : kFirstIntensityFeature;
}

// Rows of the used features as an OpenCV sample matrix (CV_32F, one row per object).
cv::Mat sampleMatrix(const std::vector<ObjectFeatureVector>& rows, int used) {
  cv::Mat m(static_cast<int>(rows.size()), used, CV_32F);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    float* dst = m.ptr<float>(static_cast<int>(r));
    for (int k = 0; k < used; ++k) dst[k] = std::isfinite(rows[r][k]) ? rows[r][k] : 0.0f;
  }
  return m;
}

[[noreturn]] void refuse(const std::string& path, const std::string& what) {
  throw std::runtime_error("object classifier model " + path + ": " + what);
}

}  // namespace

bool parseObjectCategory(const std::string& name, ObjectCategory* c) {
  for (int k = 0; k < kNumObjectCategories; ++k) {
    const auto cat = static_cast<ObjectCategory>(k);
    if (name == toString(cat)) {
      *c = cat;
      return true;
    }
  }
  return false;
}

std::string validate(const ClassifierTrainingParams& p) {
  return checkFieldRanges(p);
}

ObjectCategory decideClass(const std::array<float, 5>& p, const ClassDecision& d,
                           bool keep_uncertain, float* confidence, bool* uncertain) {
  if (uncertain) *uncertain = false;
  static_assert(kNumObjectCategories == 5, "vote shares of five classes");
  // An object class sure enough on its own (rare classes get lower thresholds).
  int chosen = -1;
  double best_ratio = 0.0;
  for (int c = 1; c <= 3; ++c) {
    const double t = d.class_thresholds[static_cast<std::size_t>(c - 1)];
    if (p[c] > 0.0f && p[c] >= t) {
      const double ratio = t > 0.0 ? p[c] / t : 1e9;
      if (ratio > best_ratio) {
        best_ratio = ratio;
        chosen = c;
      }
    }
  }
  const double p_object = 1.0 - p[0];
  if (chosen < 0 && p_object >= d.object_threshold) {
    chosen = 1;
    for (int c = 2; c < kNumObjectCategories; ++c) {
      if (p[c] > p[chosen]) chosen = c;
    }
  }
  if (chosen >= 0) {
    *confidence = p[chosen];
    return static_cast<ObjectCategory>(chosen);
  }
  if (keep_uncertain && p_object >= d.uncertain_threshold) {
    if (uncertain) *uncertain = true;
    *confidence = static_cast<float>(p_object);
    return ObjectCategory::kOtherObject;
  }
  *confidence = p[0];
  return ObjectCategory::kNonObject;
}

std::string validate(const ObjectClassifierParams& p) {
  std::string error = checkFieldRanges(p);
  if (error.empty() && p.enabled && p.model_path.empty()) {
    error = "model must name a model file when enabled";
  }
  return error;
}

// ------------------------------------------------------------------------------------------
// ObjectClassifierModel

ObjectClassifierModel::ObjectClassifierModel() = default;
ObjectClassifierModel::~ObjectClassifierModel() = default;
ObjectClassifierModel::ObjectClassifierModel(ObjectClassifierModel&&) noexcept = default;
ObjectClassifierModel& ObjectClassifierModel::operator=(ObjectClassifierModel&&) noexcept = default;

bool ObjectClassifierModel::trained() const {
  return forest_ && forest_->isTrained();
}

int ObjectClassifierModel::trees() const {
  return trained() ? static_cast<int>(forest_->getRoots().size()) : 0;
}

int ObjectClassifierModel::usedFeatures() const {
  return featureCount(use_intensity_);
}

ObjectClassifierModel ObjectClassifierModel::train(const std::vector<ObjectFeatureVector>& features,
                                                   const std::vector<ObjectCategory>& classes,
                                                   const ClassifierTrainingParams& params,
                                                   const ObjectFeatureParams& feature_params) {
  std::string error = validate(params);
  if (error.empty()) error = validate(feature_params);
  if (!error.empty()) throw std::invalid_argument("classifier training: " + error);
  if (features.size() != classes.size()) {
    throw std::invalid_argument("classifier training: one class per feature row needed");
  }
  std::vector<ObjectFeatureVector> rows;
  std::vector<int> labels;
  std::array<std::size_t, kNumObjectCategories> count{};
  for (std::size_t i = 0; i < features.size(); ++i) {
    const int c = static_cast<int>(classes[i]);
    if (c < 0 || c >= kNumObjectCategories) continue;
    rows.push_back(features[i]);
    labels.push_back(c);
    ++count[c];
  }
  // Classes without samples get probability 0 (e.g. no cyclist in a cross-validation fold);
  // the object / non-object decision needs both sides.
  std::size_t objects = 0;
  for (int c = 1; c < kNumObjectCategories; ++c) objects += count[c];
  if (count[0] == 0 || objects == 0) {
    throw std::invalid_argument(
        "classifier training: needs samples of non_object and of at least one object class");
  }
  ObjectClassifierModel m;
  m.use_intensity_ = params.use_intensity;
  m.decision_.object_threshold = params.object_threshold;
  m.decision_.class_thresholds = params.class_thresholds;
  m.decision_.uncertain_threshold = params.uncertain_threshold;
  m.feature_params_ = feature_params;
  m.description_ = params.description;
  m.training_groups_ = params.training_groups;
  const int used = m.usedFeatures();
  const cv::Mat samples = sampleMatrix(rows, used);
  const cv::Mat responses(static_cast<int>(labels.size()), 1, CV_32S, labels.data());
  // Class balance as row weights (the forest weighs its split impurity and leaf votes by them).
  std::size_t present = 0;
  for (const std::size_t n : count) present += n > 0;
  cv::Mat weights(static_cast<int>(labels.size()), 1, CV_32F);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const double share = static_cast<double>(rows.size()) /
                         (static_cast<double>(present) * static_cast<double>(count[labels[i]]));
    weights.at<float>(static_cast<int>(i)) =
        static_cast<float>(std::pow(share, params.class_balance));
  }
  cv::Mat var_type(1, used + 1, CV_8U, cv::Scalar(cv::ml::VAR_ORDERED));
  var_type.at<std::uint8_t>(0, used) = cv::ml::VAR_CATEGORICAL;
  const cv::Ptr<cv::ml::TrainData> data = cv::ml::TrainData::create(
      samples, cv::ml::ROW_SAMPLE, responses, cv::noArray(), cv::noArray(), weights, var_type);
  cv::Ptr<cv::ml::RTrees> forest = cv::ml::RTrees::create();
  forest->setMaxDepth(params.max_depth);
  forest->setMinSampleCount(params.min_sample_count);
  forest->setRegressionAccuracy(0.0f);
  forest->setUseSurrogates(false);
  forest->setMaxCategories(kNumObjectCategories);
  forest->setCalculateVarImportance(false);
  forest->setActiveVarCount(params.active_var_count);
  forest->setTermCriteria(cv::TermCriteria(cv::TermCriteria::MAX_ITER, params.trees, 0.0));
  // The forest draws its bootstrap samples and split candidates from OpenCV's global RNG;
  // seeding it makes training reproducible bit for bit.
  cv::theRNG().state = 0x5eed5eedULL;
  if (!forest->train(data)) throw std::runtime_error("classifier training: the forest failed");
  m.forest_ = forest;
  m.flatten();
  m.compact();
  return m;
}

void ObjectClassifierModel::save(const std::string& path) const {
  if (!trained()) throw std::runtime_error("cannot save an untrained classifier to " + path);
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::WRITE)) {
      throw std::runtime_error("cannot write object classifier model " + path);
    }
    fs << "format" << kFormat << "version" << kVersion;
    fs << "description" << description_;
    if (!training_groups_.empty()) {
      fs << "training_sequences"
         << "[";
      for (const std::string& g : training_groups_) fs << g;
      fs << "]";
    }
    fs << "object_threshold" << decision_.object_threshold;
    fs << "class_thresholds"
       << "[" << decision_.class_thresholds[0] << decision_.class_thresholds[1]
       << decision_.class_thresholds[2] << "]";
    fs << "uncertain_threshold" << decision_.uncertain_threshold;
    fs << "use_intensity" << static_cast<int>(use_intensity_);
    fs << "feature_params"
       << "{"
       << "sensor_height_m" << feature_params_.sensor_height_m << "row_gap_deg"
       << feature_params_.row_gap_deg << "max_azimuth_gap_deg"
       << feature_params_.max_azimuth_gap_deg << "jump_m" << feature_params_.jump_m
       << "azimuth_resolution_deg" << feature_params_.azimuth_resolution_deg << "}";
    fs << "features"
       << "[";
    for (int k = 0; k < usedFeatures(); ++k) fs << featureName(k);
    fs << "]";
    fs << "classes"
       << "[";
    for (int c = 0; c < kNumObjectCategories; ++c) fs << toString(static_cast<ObjectCategory>(c));
    fs << "]";
    fs << "forest"
       << "{";
    forest_->write(fs);
    fs << "}";
    fs.release();
  } catch (const cv::Exception& e) {
    throw std::runtime_error("cannot write object classifier model " + path + ": " + e.what());
  }
}

ObjectClassifierModel ObjectClassifierModel::load(const std::string& path) {
  std::error_code ec;
  if (path.empty()) refuse("''", "no file given");
  if (!std::filesystem::exists(path, ec)) refuse(path, "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) refuse(path, "not a regular file");
  ObjectClassifierModel m;
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) refuse(path, "cannot be opened");
    std::string format;
    fs["format"] >> format;
    if (format != kFormat) {
      refuse(path, "not an urban_detection object classifier (format '" + format + "')");
    }
    int version = 0;
    fs["version"] >> version;
    if (version != kVersion) {
      refuse(path, "version " + std::to_string(version) + ", this build reads version " +
                       std::to_string(kVersion));
    }
    fs["description"] >> m.description_;
    // Optional: models written before the key name their sequences in the description.
    m.training_groups_.clear();
    const cv::FileNode groups = fs["training_sequences"];
    if (groups.isSeq()) {
      for (const auto& g : groups) m.training_groups_.push_back(static_cast<std::string>(g));
    } else {
      const std::string marker = "scans of sequences ";
      const std::size_t at = m.description_.find(marker);
      if (at != std::string::npos) {
        std::istringstream words(m.description_.substr(at + marker.size()));
        std::string w;
        while (words >> w && w.find_first_not_of("0123456789") == std::string::npos) {
          m.training_groups_.push_back(w);
        }
      }
    }
    double threshold = -1.0;
    fs["object_threshold"] >> threshold;
    if (!(threshold >= 0.0 && threshold <= 1.0)) refuse(path, "object_threshold not in [0, 1]");
    m.decision_.object_threshold = threshold;
    // Optional (files without them: only the object threshold decides).
    const cv::FileNode ct = fs["class_thresholds"];
    if (!ct.empty()) {
      std::vector<double> t;
      ct >> t;
      if (t.size() != 3) refuse(path, "class_thresholds must list 3 probabilities");
      for (std::size_t k = 0; k < 3; ++k) {
        if (!(t[k] >= 0.0 && t[k] <= 1.0)) refuse(path, "class_thresholds not in [0, 1]");
        m.decision_.class_thresholds[k] = t[k];
      }
    }
    const cv::FileNode ut = fs["uncertain_threshold"];
    if (!ut.empty()) {
      double u = -1.0;
      ut >> u;
      if (!(u >= 0.0 && u <= 1.0)) refuse(path, "uncertain_threshold not in [0, 1]");
      m.decision_.uncertain_threshold = u;
    }
    int use_intensity = -1;
    fs["use_intensity"] >> use_intensity;
    if (use_intensity != 0 && use_intensity != 1) refuse(path, "use_intensity must be 0 or 1");
    m.use_intensity_ = use_intensity == 1;
    const cv::FileNode fp = fs["feature_params"];
    if (!fp.isMap()) refuse(path, "feature_params missing");
    fp["sensor_height_m"] >> m.feature_params_.sensor_height_m;
    fp["row_gap_deg"] >> m.feature_params_.row_gap_deg;
    fp["max_azimuth_gap_deg"] >> m.feature_params_.max_azimuth_gap_deg;
    fp["jump_m"] >> m.feature_params_.jump_m;
    fp["azimuth_resolution_deg"] >> m.feature_params_.azimuth_resolution_deg;
    const std::string fp_error = validate(m.feature_params_);
    if (!fp_error.empty()) refuse(path, "feature_params: " + fp_error);
    std::vector<std::string> names, classes;
    fs["features"] >> names;
    if (static_cast<int>(names.size()) != m.usedFeatures()) {
      refuse(path, "lists " + std::to_string(names.size()) + " features, this build computes " +
                       std::to_string(m.usedFeatures()));
    }
    for (int k = 0; k < m.usedFeatures(); ++k) {
      if (names[k] != featureName(k)) {
        refuse(path, "feature " + std::to_string(k) + " is '" + names[k] + "', this build's is '" +
                         featureName(k) + "'");
      }
    }
    fs["classes"] >> classes;
    if (static_cast<int>(classes.size()) != kNumObjectCategories) {
      refuse(path, "lists " + std::to_string(classes.size()) + " classes, expected " +
                       std::to_string(kNumObjectCategories));
    }
    for (int c = 0; c < kNumObjectCategories; ++c) {
      if (classes[c] != toString(static_cast<ObjectCategory>(c))) {
        refuse(path, "class " + std::to_string(c) + " is '" + classes[c] + "'");
      }
    }
    const cv::FileNode forest_node = fs["forest"];
    if (!forest_node.isMap()) refuse(path, "no forest");
    cv::Ptr<cv::ml::RTrees> forest = cv::ml::RTrees::create();
    forest->read(forest_node);
    if (!forest->isTrained() || forest->getRoots().empty()) refuse(path, "the forest is empty");
    if (forest->getVarCount() != m.usedFeatures()) {
      refuse(path, "the forest takes " + std::to_string(forest->getVarCount()) +
                       " features, the file lists " + std::to_string(m.usedFeatures()));
    }
    if (!forest->isClassifier()) refuse(path, "the forest is not a classifier");
    m.forest_ = forest;
    m.flatten();
    // Every node index must lie inside the forest and every split test a listed feature
    // (a hand-edited or damaged file must not make predict() read out of bounds).
    const std::int32_t n = static_cast<std::int32_t>(m.flat_.size());
    for (const std::int32_t r : m.roots_) {
      if (r < 0 || r >= n) refuse(path, "a tree root outside the forest");
    }
    // OpenCV stores children after their parent: requiring it also rules out cycles.
    for (std::int32_t i = 0; i < n; ++i) {
      const FlatNode& f = m.flat_[static_cast<std::size_t>(i)];
      if (f.var >= m.usedFeatures() ||
          (f.var >= 0 && (f.left <= i || f.left >= n || f.right <= i || f.right >= n))) {
        refuse(path, "a node outside the forest or testing an unknown feature");
      }
    }
    m.compact();
  } catch (const cv::Exception& e) {
    refuse(path, std::string("corrupt (") + e.err + ")");
  }
  return m;
}

void ObjectClassifierModel::flatten() {
  flat_.clear();
  roots_.clear();
  const std::vector<cv::ml::DTrees::Node>& nodes = forest_->getNodes();
  const std::vector<cv::ml::DTrees::Split>& splits = forest_->getSplits();
  // The forest's node array already holds every tree; its indices are kept.
  flat_.reserve(nodes.size());
  for (const cv::ml::DTrees::Node& n : nodes) {
    FlatNode f{-1, 0.0f, -1, -1, static_cast<std::int32_t>(std::lround(n.value))};
    if (n.split >= 0) {
      const cv::ml::DTrees::Split& sp = splits[static_cast<std::size_t>(n.split)];
      f.var = sp.varIdx;
      f.threshold = sp.c;
      // OpenCV goes left when value <= c, the other way for an inversed split.
      f.left = sp.inversed ? n.right : n.left;
      f.right = sp.inversed ? n.left : n.right;
    }
    flat_.push_back(f);
  }
  for (const int r : forest_->getRoots()) roots_.push_back(r);
}

void ObjectClassifierModel::compact() {
  compact_.clear();
  compact_roots_.clear();
  vote_sums_.clear();
  // Too large for the child field (or a feature index beyond var's bits): predict() walks
  // flat_ as predictPlain() does.
  if (flat_.size() >= (std::size_t{1} << (32 - kVarBits)) || usedFeatures() >= int(kLeaf)) return;
  compact_.reserve(flat_.size());
  // Depth first, left child first: an explicit stack of (node, compact node whose right
  // child it is, or -1).
  std::vector<std::pair<std::int32_t, std::int64_t>> stack;
  for (const std::int32_t root : roots_) {
    compact_roots_.push_back(static_cast<std::uint32_t>(compact_.size()));
    stack.emplace_back(root, -1);
    while (!stack.empty()) {
      const auto [node, parent] = stack.back();
      stack.pop_back();
      if (compact_.size() >= flat_.size()) {
        // More nodes than the source: subtrees shared between parents (a hand-made file; an
        // OpenCV forest reaches each node once). Walk flat_ instead.
        compact_.clear();
        compact_roots_.clear();
        return;
      }
      const std::uint32_t at = static_cast<std::uint32_t>(compact_.size());
      if (parent >= 0) compact_[static_cast<std::size_t>(parent)].meta |= at << kVarBits;
      const FlatNode& f = flat_[static_cast<std::size_t>(node)];
      if (f.var < 0) {
        const std::uint32_t label = f.label >= 0 && f.label < kNumObjectCategories
                                        ? static_cast<std::uint32_t>(f.label)
                                        : static_cast<std::uint32_t>(kNumObjectCategories);
        compact_.push_back({0.0f, kLeaf | label << kVarBits});
        continue;
      }
      compact_.push_back({f.threshold, static_cast<std::uint32_t>(f.var)});
      stack.emplace_back(f.right, static_cast<std::int64_t>(at));
      stack.emplace_back(f.left, -1);
    }
  }
  const float vote = 1.0f / static_cast<float>(roots_.size());
  vote_sums_.assign(roots_.size() + 1, 0.0f);
  for (std::size_t k = 1; k < vote_sums_.size(); ++k) vote_sums_[k] = vote_sums_[k - 1] + vote;
}

void ObjectClassifierModel::predict(
    const std::vector<ObjectFeatureVector>& features,
    std::vector<std::array<float, kNumObjectCategories>>* probabilities) const {
  if (compact_.empty()) return predictPlain(features, probabilities);
  probabilities->assign(features.size(), std::array<float, kNumObjectCategories>{});
  if (features.empty()) return;
  const std::size_t rows = features.size();
  const int used = usedFeatures();
  constexpr std::size_t kCounts = kNumObjectCategories + 1;  // the last: leaves without class
  std::vector<float> x(rows * kNumObjectFeatures);
  std::vector<std::uint16_t> votes(rows * kCounts, 0);
  for (std::size_t r = 0; r < rows; ++r) {
    float* xr = &x[r * kNumObjectFeatures];
    for (int k = 0; k < used; ++k) xr[k] = std::isfinite(features[r][k]) ? features[r][k] : 0.0f;
  }
  const CompactNode* const nodes = compact_.data();
  for (const std::uint32_t root : compact_roots_) {
    // Four rows at a time: their walks are independent chains of loads.
    std::size_t r = 0;
    for (; r + 4 <= rows; r += 4) {
      const float* x0 = &x[r * kNumObjectFeatures];
      const float* x1 = x0 + kNumObjectFeatures;
      const float* x2 = x1 + kNumObjectFeatures;
      const float* x3 = x2 + kNumObjectFeatures;
      std::uint32_t i0 = root, i1 = root, i2 = root, i3 = root;
      CompactNode n0 = nodes[i0], n1 = n0, n2 = n0, n3 = n0;
      for (;;) {
        const std::uint32_t v0 = n0.meta & kLeaf, v1 = n1.meta & kLeaf, v2 = n2.meta & kLeaf,
                            v3 = n3.meta & kLeaf;
        if ((v0 & v1 & v2 & v3) == kLeaf) break;
        if (v0 != kLeaf) n0 = nodes[i0 = x0[v0] <= n0.threshold ? i0 + 1 : n0.meta >> kVarBits];
        if (v1 != kLeaf) n1 = nodes[i1 = x1[v1] <= n1.threshold ? i1 + 1 : n1.meta >> kVarBits];
        if (v2 != kLeaf) n2 = nodes[i2 = x2[v2] <= n2.threshold ? i2 + 1 : n2.meta >> kVarBits];
        if (v3 != kLeaf) n3 = nodes[i3 = x3[v3] <= n3.threshold ? i3 + 1 : n3.meta >> kVarBits];
      }
      ++votes[r * kCounts + (n0.meta >> kVarBits)];
      ++votes[(r + 1) * kCounts + (n1.meta >> kVarBits)];
      ++votes[(r + 2) * kCounts + (n2.meta >> kVarBits)];
      ++votes[(r + 3) * kCounts + (n3.meta >> kVarBits)];
    }
    for (; r < rows; ++r) {
      const float* xr = &x[r * kNumObjectFeatures];
      std::uint32_t i = root;
      CompactNode n = nodes[i];
      while ((n.meta & kLeaf) != kLeaf) {
        i = xr[n.meta & kLeaf] <= n.threshold ? i + 1 : n.meta >> kVarBits;
        n = nodes[i];
      }
      ++votes[r * kCounts + (n.meta >> kVarBits)];
    }
  }
  for (std::size_t r = 0; r < rows; ++r) {
    auto& p = (*probabilities)[r];
    for (int c = 0; c < kNumObjectCategories; ++c) p[c] = vote_sums_[votes[r * kCounts + c]];
  }
}

void ObjectClassifierModel::predictPlain(
    const std::vector<ObjectFeatureVector>& features,
    std::vector<std::array<float, kNumObjectCategories>>* probabilities) const {
  probabilities->assign(features.size(), std::array<float, kNumObjectCategories>{});
  if (features.empty() || roots_.empty()) return;
  const float vote = 1.0f / static_cast<float>(roots_.size());
  const int used = usedFeatures();
  for (std::size_t r = 0; r < features.size(); ++r) {
    float x[kNumObjectFeatures];
    for (int k = 0; k < used; ++k) x[k] = std::isfinite(features[r][k]) ? features[r][k] : 0.0f;
    auto& p = (*probabilities)[r];
    for (const std::int32_t root : roots_) {
      const FlatNode* n = &flat_[static_cast<std::size_t>(root)];
      while (n->var >= 0) {
        n = &flat_[static_cast<std::size_t>(x[n->var] <= n->threshold ? n->left : n->right)];
      }
      if (n->label >= 0 && n->label < kNumObjectCategories) p[n->label] += vote;
    }
  }
}

void ObjectClassifierModel::predictReference(
    const std::vector<ObjectFeatureVector>& features,
    std::vector<std::array<float, kNumObjectCategories>>* probabilities) const {
  probabilities->assign(features.size(), std::array<float, kNumObjectCategories>{});
  if (features.empty() || !trained()) return;
  const cv::Mat samples = sampleMatrix(features, usedFeatures());
  cv::Mat votes;
  forest_->getVotes(samples, votes, 0);
  // Row 0 holds the class values of the columns; rows 1..N the votes of each sample.
  const int trees = std::max(1, this->trees());
  for (int r = 0; r < static_cast<int>(features.size()) && r + 1 < votes.rows; ++r) {
    auto& p = (*probabilities)[r];
    for (int c = 0; c < votes.cols; ++c) {
      const int cls = votes.at<int>(0, c);
      if (cls >= 0 && cls < kNumObjectCategories) {
        p[cls] = static_cast<float>(votes.at<int>(r + 1, c)) / static_cast<float>(trees);
      }
    }
  }
}

// ------------------------------------------------------------------------------------------
// ObjectClassifier

namespace {

ObjectClassifierModel loadIfEnabled(const ObjectClassifierParams& params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument("ObjectClassifier: " + error);
  return params.enabled ? ObjectClassifierModel::load(params.model_path) : ObjectClassifierModel();
}

}  // namespace

ObjectClassifier::ObjectClassifier(const ObjectClassifierParams& params)
    : ObjectClassifier(params, loadIfEnabled(params)) {}

ObjectClassifier::ObjectClassifier(const ObjectClassifierParams& params,
                                   ObjectClassifierModel model)
    : params_(params), model_(std::move(model)), extractor_(model_.featureParams()) {
  const std::string error = checkFieldRanges(params_);  // the table's ranges
  if (!error.empty()) throw std::invalid_argument("ObjectClassifier: " + error);
  if (params_.enabled && !model_.trained()) {
    throw std::invalid_argument("ObjectClassifier: enabled without a trained model");
  }
}

double ObjectClassifier::threshold() const {
  return params_.min_object_probability >= 0.0 ? params_.min_object_probability
                                               : model_.objectThreshold();
}

void ObjectClassifier::setDecision(double min_object_probability, bool reject_non_objects,
                                   bool keep_uncertain) {
  ObjectClassifierParams p = params_;
  p.min_object_probability = min_object_probability;
  p.reject_non_objects = reject_non_objects;
  p.keep_uncertain = keep_uncertain;
  const std::string error = checkFieldRanges(p);  // the table's range, one wording
  if (!error.empty()) throw std::invalid_argument("ObjectClassifier: " + error);
  params_ = p;
}

ObjectClassifierStats ObjectClassifier::apply(const LabeledCloud& foreground,
                                              std::vector<DetectedObject>* objects,
                                              std::vector<DetectedObject>* rejected) {
  ObjectClassifierStats s;
  s.input = objects->size();
  if (rejected) rejected->clear();
  features_.clear();
  if (!params_.enabled || objects->empty()) {
    s.kept = objects->size();
    return s;
  }
  extractor_.computeAll(foreground, *objects, &features_);
  model_.predict(features_, &probabilities_);
  ClassDecision decision = model_.decision();
  if (params_.min_object_probability >= 0.0) {
    // An explicit object threshold replaces the model's whole decision by that one rule.
    decision = ClassDecision();
    decision.object_threshold = params_.min_object_probability;
  }
  kept_.clear();
  for (std::size_t i = 0; i < objects->size(); ++i) {
    DetectedObject& o = (*objects)[i];
    const auto& p = probabilities_[i];
    bool uncertain = false;
    o.category = decideClass(p, decision, params_.keep_uncertain, &o.class_confidence, &uncertain);
    s.uncertain += uncertain;
    ++s.by_class[static_cast<int>(o.category)];
    if (o.category == ObjectCategory::kNonObject) {
      ++s.rejected;
      if (rejected) rejected->push_back(o);
      if (params_.reject_non_objects) continue;
    }
    kept_.push_back(std::move(o));
  }
  objects->swap(kept_);
  renumberObjects(objects);
  s.kept = objects->size();
  return s;
}

}  // namespace core
}  // namespace urban_detection
