// Object features (object_features.h) on synthetic objects with known values, and the object
// classifier (object_classifier.h): training determinism, save/load, refusal of bad model
// files, the classification stage's decisions and its YAML parameters.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_scans.h"
#include "test_files.h"
#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/params/params_yaml.h"

namespace core = urban_detection::core;
using urban_detection::LabeledCloud;
using urban_detection::makeLabeledPoint;
using namespace urban_detection::test;  // NOLINT: scan helpers

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A hand-made object: points appended to `fg` with spread indices.
core::DetectedObject object(const std::vector<Eigen::Vector4f>& xyzi, LabeledCloud* fg) {
  core::DetectedObject o;
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const auto& p : xyzi) {
    o.indices.push_back(static_cast<std::uint32_t>(5 * fg->size() + 3));
    fg->push_back(makeLabeledPoint(p.x(), p.y(), p.z(), 4, o.indices.back(), p.w()));
    sum += p.head<3>();
  }
  o.centroid = sum / static_cast<float>(xyzi.size());
  return o;
}

}  // namespace

TEST(ObjectFeatures, VerticalPlaneHasKnownGeometryAndIntensity) {
  // A 2 m wide, 1.5 m tall vertical plane 10 m ahead standing on the ground (sensor 1.73 m
  // above it): rows of constant z, points every 0.05 m in y; intensities alternate 10 / 30.
  std::vector<Eigen::Vector4f> pts;
  int k = 0;
  for (int row = 0; row < 16; ++row) {
    const float z = -1.73f + 0.1f * row;
    for (int c = 0; c <= 40; ++c, ++k) {
      pts.emplace_back(10.0f, -1.0f + 0.05f * c, z, k % 2 ? 30.0f : 10.0f);
    }
  }
  LabeledCloud fg;
  core::DetectedObject o = object(pts, &fg);
  o.obb_size = Eigen::Vector3f(2.0f, 0.02f, 1.5f);
  core::ObjectFeatureExtractor x;
  x.indexForeground(fg);
  const core::ObjectFeatureVector f = x.compute(fg, o);
  EXPECT_EQ(f[core::kFeatPoints], 16 * 41);
  EXPECT_NEAR(f[core::kFeatRange], 10.0, 1e-3);
  EXPECT_NEAR(f[core::kFeatPointsAt10m], 16 * 41, 1.0);
  EXPECT_NEAR(f[core::kFeatLength], 2.0, 1e-6);
  EXPECT_NEAR(f[core::kFeatWidth], 0.02, 1e-6);
  EXPECT_NEAR(f[core::kFeatHeight], 1.5, 1e-4);
  EXPECT_NEAR(f[core::kFeatBottom], 0.0, 1e-4);
  EXPECT_NEAR(f[core::kFeatTop], 1.5, 1e-4);
  EXPECT_NEAR(f[core::kFeatMeanAboveBottom], 0.75, 1e-3);
  // A plane: no thickness (scattering 0), its normal horizontal.
  EXPECT_LT(f[core::kFeatScattering], 1e-3);
  EXPECT_GT(f[core::kFeatPlanarity], 0.3);
  EXPECT_LT(f[core::kFeatNormalZ], 0.01);
  // 16 rows of 41 points; the range along a row is smooth: no jumps.
  EXPECT_EQ(f[core::kFeatRows], 16);
  EXPECT_NEAR(f[core::kFeatPointsPerRow], 41.0, 1e-4);
  EXPECT_EQ(f[core::kFeatJumpFraction], 0.0f);
  EXPECT_LT(f[core::kFeatMeanSecondDiff], 1e-3);
  EXPECT_NEAR(f[core::kFeatRowNeighbours], 16.0 * 39 / (16 * 41), 1e-4);
  // Azimuth step 0.05 m at 10 m = 0.286 deg = 1.69 x the 0.17 deg resolution.
  EXPECT_NEAR(f[core::kFeatAzimuthFill], 0.05 / 10.0 / (0.17 * M_PI / 180.0), 0.02);
  // Vertical profile: 4 rows in each quarter (the top row falls in the last).
  EXPECT_NEAR(f[core::kFeatProfile0] + f[core::kFeatProfile1] + f[core::kFeatProfile2] +
                  f[core::kFeatProfile3],
              1.0, 1e-5);
  EXPECT_NEAR(f[core::kFeatBelow05], 5.0 / 16.0, 1e-4);  // rows at 0.0 .. 0.4 m
  EXPECT_NEAR(f[core::kFeatAbove15], 0.0, 1e-4);
  EXPECT_NEAR(f[core::kFeatIntensityMean], 20.0, 0.05);
  EXPECT_NEAR(f[core::kFeatIntensityStd], 10.0, 0.05);
  EXPECT_EQ(f[core::kFeatIntensityQ10], 10.0f);
  EXPECT_EQ(f[core::kFeatIntensityQ90], 30.0f);
  EXPECT_EQ(f[core::kFeatIntensityMax], 30.0f);
}

TEST(ObjectFeatures, PorousBushHasJumpsSmoothBoxHasNone) {
  std::mt19937 rng(7);
  LabeledCloud fg;
  core::DetectedObject bush_o = scan(bush({9.0, -6.0, -1.0}, 1.0, &rng), -45, -22, -14, 2, &fg);
  core::DetectedObject car = scan(box({8.0, 1.2, -1.6}, {12.2, 3.0, -0.3}), 0, 25, -14, 0, &fg);
  core::ObjectFeatureExtractor x;
  x.indexForeground(fg);
  const auto fb = x.compute(fg, bush_o);
  const auto fc = x.compute(fg, car);
  EXPECT_GT(fb[core::kFeatJumpFraction], 0.3);
  EXPECT_LT(fc[core::kFeatJumpFraction], 0.05);
  EXPECT_GT(fb[core::kFeatMeanSecondDiff], 5.0 * fc[core::kFeatMeanSecondDiff]);
  // Rows every 0.4 deg: the car spans 14 deg of elevation at most.
  EXPECT_GE(fc[core::kFeatRows], 20);
  EXPECT_LE(fc[core::kFeatRows], 36);
}

// The intensity quantiles' selection against a full sort: integer intensities (as decoded),
// fractional ones, values below 0 and above 255, many duplicates, one value, repeated ranks.
TEST(ObjectFeatures, SelectRanksEqualsTheSortedValues) {
  std::mt19937 rng(11);
  std::vector<float> scratch;
  for (int trial = 0; trial < 700; ++trial) {
    const std::size_t n = 1 + rng() % (trial < 140 ? 20 : trial < 280 ? 100 : 3000);
    std::vector<float> values(n);
    for (float& v : values) {
      switch (trial % 7) {
        case 0:
          v = static_cast<float>(rng() % 256);
          break;
        case 1:
          v = std::uniform_real_distribution<float>(0.0f, 255.0f)(rng);
          break;
        case 2:
          v = std::uniform_real_distribution<float>(-50.0f, 400.0f)(rng);
          break;
        case 3:
          v = static_cast<float>(rng() % 3) * 0.25f + 7.0f;
          break;
        case 4:  // KITTI files: reflectance in [0, 1]
          v = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
          break;
        case 5:  // a spread that overflows a float difference, and a few extremes
          v = rng() % 7 == 0   ? std::numeric_limits<float>::lowest()
              : rng() % 7 == 0 ? std::numeric_limits<float>::max()
                               : std::uniform_real_distribution<float>(-1e30f, 1e30f)(rng);
          break;
        default:  // clustered: most values in one bucket, a far outlier
          v = rng() % 500 == 0 ? 1e6f : 3.0f + static_cast<float>(rng() % 1000) * 1e-6f;
          break;
      }
    }
    std::vector<std::size_t> ranks = {static_cast<std::size_t>(0.1 * n),
                                      static_cast<std::size_t>(0.5 * n),
                                      static_cast<std::size_t>(0.9 * n), n - 1};
    for (std::size_t& r : ranks) r = std::min(r, n - 1);
    std::sort(ranks.begin(), ranks.end());
    std::vector<float> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    float out[4];
    core::selectRanks(values, ranks.data(), 4, out, &scratch);
    for (int r = 0; r < 4; ++r) {
      ASSERT_EQ(out[r], sorted[ranks[r]]) << "trial " << trial << " rank " << ranks[r];
    }
    // More ranks than buckets gathered in one pass.
    std::vector<std::size_t> many(12);
    for (std::size_t r = 0; r < many.size(); ++r) many[r] = r * (n - 1) / (many.size() - 1);
    float many_out[12];
    core::selectRanks(values, many.data(), 12, many_out, &scratch);
    for (std::size_t r = 0; r < many.size(); ++r) {
      ASSERT_EQ(many_out[r], sorted[many[r]]) << "trial " << trial << " rank " << many[r];
    }
  }
}

TEST(ObjectFeatures, MissingIndicesAndEmptyObjects) {
  LabeledCloud fg;
  core::DetectedObject o = object({{5.0f, 0.0f, -1.0f, 1.0f}, {5.0f, 0.1f, -1.0f, 3.0f}}, &fg);
  o.indices.push_back(999999);  // not in the foreground
  o.indices.push_back(1u << 30);
  core::ObjectFeatureExtractor x;
  x.indexForeground(fg);
  auto f = x.compute(fg, o);
  EXPECT_EQ(f[core::kFeatPoints], 2);
  core::DetectedObject empty;
  empty.obb_size = Eigen::Vector3f(1.0f, 0.5f, 0.0f);
  f = x.compute(fg, empty);
  EXPECT_EQ(f[core::kFeatPoints], 0);
  EXPECT_EQ(f[core::kFeatLength], 1.0f);
  for (const float v : f) EXPECT_TRUE(std::isfinite(v));
  // A NaN point is skipped.
  fg.push_back(makeLabeledPoint(NAN, 0.0f, 0.0f, 4, 77, 1.0f));
  o.indices.push_back(77);
  x.indexForeground(fg);
  f = x.compute(fg, o);
  EXPECT_EQ(f[core::kFeatPoints], 2);
  EXPECT_THROW(core::ObjectFeatureExtractor(core::ObjectFeatureParams{1.73, -1.0}),
               std::invalid_argument);
}

namespace {

// A separable synthetic training set: the class is given by height and intensity spread.
void toyData(std::vector<core::ObjectFeatureVector>* x, std::vector<core::ObjectCategory>* y) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const core::ObjectCategory cats[] = {
      core::ObjectCategory::kNonObject, core::ObjectCategory::kVehicle,
      core::ObjectCategory::kPedestrian, core::ObjectCategory::kCyclist,
      core::ObjectCategory::kOtherObject};
  for (int i = 0; i < 400; ++i) {
    const int c = i % 5;
    core::ObjectFeatureVector f;
    for (float& v : f) v = u(rng);
    f[core::kFeatHeight] = static_cast<float>(c) + 0.5f * u(rng);
    f[core::kFeatIntensityStd] = 10.0f * c + u(rng);
    x->push_back(f);
    y->push_back(cats[c]);
  }
}

core::ObjectClassifierModel toyModel(bool use_intensity = true) {
  std::vector<core::ObjectFeatureVector> x;
  std::vector<core::ObjectCategory> y;
  toyData(&x, &y);
  core::ClassifierTrainingParams p;
  p.trees = 16;
  p.use_intensity = use_intensity;
  p.description = "toy";
  return core::ObjectClassifierModel::train(x, y, p, core::ObjectFeatureParams());
}

}  // namespace

TEST(ObjectClassifierModel, TrainingIsDeterministicAndRoundTrips) {
  const std::string a = ud_test::tempPath("model_a.yml"), b = ud_test::tempPath("model_b.yml");
  toyModel().save(a);
  toyModel().save(b);
  const std::string text = readFile(a);
  ASSERT_GT(text.size(), 1000u);
  EXPECT_EQ(text, readFile(b)) << "two trainings on the same rows gave different files";
  const core::ObjectClassifierModel m = core::ObjectClassifierModel::load(a);
  EXPECT_EQ(m.trees(), 16);
  EXPECT_EQ(m.description(), "toy");
  EXPECT_TRUE(m.useIntensity());
  std::vector<core::ObjectFeatureVector> x;
  std::vector<core::ObjectCategory> y;
  toyData(&x, &y);
  std::vector<std::array<float, core::kNumObjectCategories>> p;
  m.predict(x, &p);
  int right = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    int best = 0;
    for (int c = 1; c < core::kNumObjectCategories; ++c) {
      if (p[i][c] > p[i][best]) best = c;
    }
    right += best == static_cast<int>(y[i]);
    float sum = 0.0f;
    for (float v : p[i]) sum += v;
    EXPECT_NEAR(sum, 1.0f, 1e-5);
  }
  EXPECT_GE(right, 390);
  // Compressed files work too.
  const std::string gz = ud_test::tempPath("model.yml.gz");
  m.save(gz);
  EXPECT_LT(readFile(gz).size(), text.size() / 2);
  EXPECT_EQ(core::ObjectClassifierModel::load(gz).trees(), 16);
  std::remove(a.c_str());
  std::remove(b.c_str());
  std::remove(gz.c_str());
}

// The flat forest traversal of predict() against OpenCV's own RTrees::getVotes (the plain
// reference) on random rows spread over and beyond the training range, on the toy model and
// on the shipped one.
TEST(ObjectClassifierModel, FlatForestEqualsOpenCvVotes) {
  std::vector<core::ObjectClassifierModel> models;
  models.push_back(toyModel());
  models.push_back(toyModel(false));
  const std::string shipped = std::string(UD_SOURCE_DIR) + "/config/object_classifier.yml.gz";
  if (std::ifstream(shipped).good()) models.push_back(core::ObjectClassifierModel::load(shipped));
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<core::ObjectFeatureVector> x(500);
  for (auto& f : x) {
    for (int k = 0; k < core::kNumObjectFeatures; ++k) {
      // Scales of the real features: counts up to 1000, metres up to 50, intensities to 255.
      const float scale = k < 3 ? 500.0f : (k >= core::kFirstIntensityFeature ? 128.0f : 4.0f);
      f[k] = scale * (1.0f + u(rng));
    }
  }
  for (const auto& m : models) {
    std::vector<std::array<float, core::kNumObjectCategories>> fast, ref;
    m.predict(x, &fast);
    m.predictReference(x, &ref);
    ASSERT_EQ(fast.size(), ref.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      for (int c = 0; c < core::kNumObjectCategories; ++c) {
        EXPECT_NEAR(fast[i][c], ref[i][c], 1e-6) << "row " << i << " class " << c;
      }
    }
  }
}

TEST(ObjectClassifierModel, TrainingRefusesBadInput) {
  std::vector<core::ObjectFeatureVector> x(10);
  std::vector<core::ObjectCategory> y(10, core::ObjectCategory::kVehicle);
  // Only one side of the object / non-object decision.
  EXPECT_THROW(core::ObjectClassifierModel::train(x, y, {}, {}), std::invalid_argument);
  core::ClassifierTrainingParams p;
  p.trees = 0;
  toyData(&x, &y);
  EXPECT_THROW(core::ObjectClassifierModel::train(x, y, p, {}), std::invalid_argument);
}

TEST(ObjectClassifierModel, RefusesBadFilesNamingThem) {
  const std::string good = ud_test::tempPath("good.yml");
  toyModel().save(good);
  const std::string text = readFile(good);
  auto expectRefused = [](const std::string& path, const std::string& what) {
    try {
      core::ObjectClassifierModel::load(path);
      ADD_FAILURE() << "accepted " << path;
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
  };
  expectRefused(ud_test::tempPath("does_not_exist.yml"), "no such file");
  expectRefused(::testing::TempDir(), "not a regular file");
  {
    ud_test::TempFile garbage(".yml", "\x01\x02 this is : not [ yaml {");
    expectRefused(garbage.path(), "");
  }
  {
    ud_test::TempFile other(".yml", "%YAML:1.0\n---\nformat: something_else\n");
    expectRefused(other.path(), "not an urban_detection object classifier");
  }
  {
    std::string t = text;
    t.replace(t.find("intensity_max"), 13, "intensity_min");
    ud_test::TempFile renamed(".yml", t);
    expectRefused(renamed.path(), "intensity_min");
  }
  {
    ud_test::TempFile truncated(".yml", text.substr(0, text.size() / 2));
    expectRefused(truncated.path(), "");
  }
  {
    std::string t = text;
    t.replace(t.find("version: 1"), 10, "version: 9");
    ud_test::TempFile future(".yml", t);
    expectRefused(future.path(), "version 9");
  }
  std::remove(good.c_str());
}

TEST(ObjectClassifier, RejectsNonObjectsAndLabelsTheRest) {
  const std::string path = ud_test::tempPath("stage.yml");
  toyModel().save(path);
  // Two objects whose features the extractor computes: a short low-spread one (height 0.3 m,
  // one intensity: the toy model's non-object) and a 2.2 m tall one with intensities 0 / 40
  // (the toy model's pedestrian).
  LabeledCloud fg;
  std::vector<Eigen::Vector4f> flat, tall;
  for (int i = 0; i < 30; ++i) flat.emplace_back(6.0f, 0.05f * i, -1.73f + 0.01f * i, 5.0f);
  for (int i = 0; i < 30; ++i) {
    tall.emplace_back(8.0f, 3.0f + 0.01f * i, -1.73f + 0.075f * i, i % 2 ? 40.0f : 0.0f);
  }
  std::vector<core::DetectedObject> objects = {object(flat, &fg), object(tall, &fg)};
  objects[0].id = 1;
  objects[1].id = 2;
  core::ObjectClassifierParams params;
  params.enabled = true;
  params.model_path = path;
  core::ObjectClassifier stage(params);
  std::vector<core::DetectedObject> out = objects, rejected;
  const core::ObjectClassifierStats s = stage.apply(fg, &out, &rejected);
  EXPECT_EQ(s.input, 2u);
  EXPECT_EQ(s.rejected, 1u);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id, 1u);  // renumbered
  EXPECT_EQ(out[0].indices, objects[1].indices);
  EXPECT_EQ(out[0].category, core::ObjectCategory::kPedestrian);
  EXPECT_GE(out[0].class_confidence, 0.5f);
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_EQ(rejected[0].category, core::ObjectCategory::kNonObject);
  EXPECT_EQ(stage.lastFeatures().size(), 2u);
  // Kept but labelled when reject_non_objects is off; everything kept at threshold 0.
  params.reject_non_objects = false;
  out = objects;
  core::ObjectClassifier(params).apply(fg, &out, &rejected);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].category, core::ObjectCategory::kNonObject);
  params.reject_non_objects = true;
  params.min_object_probability = 0.0;
  out = objects;
  core::ObjectClassifier(params).apply(fg, &out, &rejected);
  EXPECT_EQ(out.size(), 2u);
  // The decision changes without reloading the model.
  {
    core::ObjectClassifierParams strict = params;
    core::ObjectClassifier tunable(strict);
    tunable.setDecision(0.0, true);
    EXPECT_DOUBLE_EQ(tunable.threshold(), 0.0);
    out = objects;
    tunable.apply(fg, &out, &rejected);
    EXPECT_EQ(out.size(), 2u);
    tunable.setDecision(-1.0, true);
    EXPECT_DOUBLE_EQ(tunable.threshold(), tunable.model().objectThreshold());
    EXPECT_THROW(tunable.setDecision(1.5, true), std::invalid_argument);
    EXPECT_THROW(tunable.setDecision(-1.5, true), std::invalid_argument);
    // The constructor holds the table's range [-1, 1] too (it let -5 through).
    strict.min_object_probability = -5.0;
    EXPECT_THROW(core::ObjectClassifier{strict}, std::invalid_argument);
  }
  // Disabled: unchanged, unknown.
  params.enabled = false;
  out = objects;
  core::ObjectClassifier(params).apply(fg, &out, &rejected);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].category, core::ObjectCategory::kUnknown);
  // Enabled without a model, or with a bad one: refused.
  params.enabled = true;
  params.model_path = "";
  EXPECT_THROW(core::ObjectClassifier{params}, std::invalid_argument);
  params.model_path = ud_test::tempPath("missing.yml");
  EXPECT_THROW(core::ObjectClassifier{params}, std::runtime_error);
  params.model_path = path;
  params.min_object_probability = 1.5;
  EXPECT_THROW(core::ObjectClassifier{params}, std::invalid_argument);
  std::remove(path.c_str());
}

TEST(ObjectClassifier, ModelWithoutIntensityIgnoresIt) {
  const std::string path = ud_test::tempPath("no_intensity.yml");
  toyModel(false).save(path);
  const core::ObjectClassifierModel m = core::ObjectClassifierModel::load(path);
  EXPECT_FALSE(m.useIntensity());
  core::ObjectFeatureVector a{}, b{};
  a[core::kFeatHeight] = b[core::kFeatHeight] = 1.2f;
  b[core::kFeatIntensityStd] = 40.0f;
  std::vector<std::array<float, core::kNumObjectCategories>> p;
  m.predict({a, b}, &p);
  EXPECT_EQ(p[0], p[1]);
  EXPECT_EQ(readFile(path).find("intensity_mean"), std::string::npos);
  std::remove(path.c_str());
}

TEST(ObjectClassifier, CategoryOfDatasetClassNames) {
  EXPECT_EQ(core::categoryOfClassName("moving-car"), core::ObjectCategory::kVehicle);
  EXPECT_EQ(core::categoryOfClassName("Van"), core::ObjectCategory::kVehicle);
  EXPECT_EQ(core::categoryOfClassName("Person_sitting"), core::ObjectCategory::kPedestrian);
  EXPECT_EQ(core::categoryOfClassName("bicyclist"), core::ObjectCategory::kCyclist);
  EXPECT_EQ(core::categoryOfClassName("bin"), core::ObjectCategory::kOtherObject);
  EXPECT_EQ(core::categoryOfClassName("pole"), core::ObjectCategory::kUnknown);
  core::ObjectCategory c;
  EXPECT_TRUE(core::parseObjectCategory("cyclist", &c));
  EXPECT_EQ(c, core::ObjectCategory::kCyclist);
  EXPECT_FALSE(core::parseObjectCategory("unknown", &c));
}

TEST(ObjectClassifier, YamlSectionResolvesTheModelBesideTheFile) {
  ud_test::TempFile yaml(".yaml",
                         "classifier:\n  enabled: true\n  model: sub/model.yml.gz\n"
                         "  min_object_probability: 0.4\n  reject_non_objects: false\n");
  core::ObjectClassifierParams p;
  std::string err;
  ASSERT_TRUE(core::loadObjectClassifierParamsYaml(yaml.path(), &p, &err)) << err;
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.model_path, ::testing::TempDir() + "sub/model.yml.gz");
  EXPECT_DOUBLE_EQ(p.min_object_probability, 0.4);
  EXPECT_FALSE(p.reject_non_objects);
  ud_test::TempFile bad(".yaml", "classifier:\n  modle: x\n");
  EXPECT_FALSE(core::loadObjectClassifierParamsYaml(bad.path(), &p, &err));
  EXPECT_NE(err.find("modle"), std::string::npos);
}

TEST(ObjectClassifier, ShippedConfigNamesTheShippedModel) {
  core::ObjectClassifierParams p;
  std::string err;
  ASSERT_TRUE(core::loadObjectClassifierParamsYaml(
      std::string(UD_SOURCE_DIR) + "/config/classification.yaml", &p, &err))
      << err;
  EXPECT_TRUE(p.enabled);
  const core::ObjectClassifierModel m = core::ObjectClassifierModel::load(p.model_path);
  EXPECT_GE(m.trees(), 10);
  EXPECT_GT(m.objectThreshold(), 0.0);
  EXPECT_LT(m.objectThreshold(), 1.0);
  // It names the sequences it learned from (key or, for older files, its description), so the
  // evaluation can say when it scores them.
  EXPECT_FALSE(m.trainingGroups().empty());
  for (const std::string& g : m.trainingGroups()) EXPECT_EQ(g.size(), 2u) << g;
}

TEST(ObjectClassifierModel, TrainingSequencesKeyAndOlderDescriptions) {
  std::vector<core::ObjectFeatureVector> x;
  std::vector<core::ObjectCategory> y;
  toyData(&x, &y);
  core::ClassifierTrainingParams p;
  p.trees = 4;
  p.description = "toy";
  p.training_groups = {"00", "07"};
  const std::string path = ud_test::tempPath("model_groups.yml");
  core::ObjectClassifierModel::train(x, y, p, core::ObjectFeatureParams()).save(path);
  EXPECT_EQ(core::ObjectClassifierModel::load(path).trainingGroups(),
            (std::vector<std::string>{"00", "07"}));
  // A file written before the key: the sequences its description names, else none.
  p.training_groups.clear();
  p.description = "random forest; trained on 20 SemanticKITTI scans of sequences 03 05 (shipped)";
  core::ObjectClassifierModel::train(x, y, p, core::ObjectFeatureParams()).save(path);
  EXPECT_EQ(core::ObjectClassifierModel::load(path).trainingGroups(),
            (std::vector<std::string>{"03", "05"}));
  p.description = "toy";
  core::ObjectClassifierModel::train(x, y, p, core::ObjectFeatureParams()).save(path);
  EXPECT_TRUE(core::ObjectClassifierModel::load(path).trainingGroups().empty());
  std::remove(path.c_str());
}
