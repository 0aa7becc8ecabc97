// The optimised classification stage against its plain references, bit for bit: the feature
// pass (ObjectFeatureExtractor::compute against computeReference) and the compact forest
// (ObjectClassifierModel::predict against predictPlain) on the objects the hierarchical grid
// finds in real scans (KITTI raw, SemanticKITTI: clouds in laser order), on decoded packets of
// the simulated drive (firing order) and on hand-made objects that reach the rare paths (rows
// of many interleaved runs, equal azimuths, absurd elevation spans, missing points).
#include "simulated_drive.h"
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/classification/object_features.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/simulation/lidar_simulator.h"
#include "urban_detection/core/simulation/scene_generator.h"
#include "urban_detection/core/simulation/simulation_config.h"

namespace core = urban_detection::core;
using urban_detection::CloudXYZIRT;
using urban_detection::LabeledCloud;
using urban_detection::makeLabeledPoint;

namespace {

// One frame's foreground and the hierarchical grid's objects in it.
struct Frame {
  std::string name;
  LabeledCloud foreground;
  std::vector<core::DetectedObject> objects;
};

Frame detectFrame(const std::string& name, const CloudXYZIRT& cloud) {
  static core::GridSegmenter segmenter;
  static core::HierarchicalGridDetector detector;
  Frame f;
  f.name = name;
  std::vector<core::SegmentClass> labels;
  segmenter.segment(cloud, &labels);
  core::extractForeground(cloud, labels, &f.foreground);
  detector.detect(f.foreground, &f.objects);
  return f;
}

std::vector<Frame> realFrames() {
  std::vector<Frame> frames;
  const std::string root = UD_SHARED_DATA;
  for (const char* drive : {"drive_0048", "drive_0005"}) {
    for (const std::string& file : core::listFiles(root + "/kitti_raw/" + drive, ".pcd")) {
      CloudXYZIRT c;
      if (core::readPcdXyzi(file, &c)) frames.push_back(detectFrame(file, c));
    }
  }
  for (const char* seq : {"00", "05", "10"}) {
    const auto files =
        core::listFiles(root + "/semantic_kitti/sequences/" + seq + "/velodyne", ".bin");
    for (std::size_t i = 0; i < files.size() && i < 3; ++i) {
      CloudXYZIRT c;
      if (core::readKittiBin(files[i], &c)) frames.push_back(detectFrame(files[i], c));
    }
  }
  return frames;
}

// Revolutions of the simulated drive (config/demo_drive.yaml), decoded as PacketSource does.
std::vector<Frame> simulatedFrames(int count) {
  std::vector<Frame> out;
  int r = 0;
  for (const CloudXYZIRT& cloud : ud_test::simulatedRevolutions(count)) {
    out.push_back(detectFrame("simulated revolution " + std::to_string(r++), cloud));
  }
  return out;
}

bool sameBits(const core::ObjectFeatureVector& a, const core::ObjectFeatureVector& b) {
  return std::memcmp(a.data(), b.data(), sizeof(float) * a.size()) == 0;
}

std::string differences(const core::ObjectFeatureVector& a, const core::ObjectFeatureVector& b) {
  std::string s;
  for (int k = 0; k < core::kNumObjectFeatures; ++k) {
    if (std::memcmp(&a[k], &b[k], sizeof(float)) != 0) {
      s += std::string(" ") + core::featureName(k) + " " + std::to_string(a[k]) + " vs " +
           std::to_string(b[k]);
    }
  }
  return s;
}

// Features of every object by both paths (one extractor, the reference's scratch shared with
// the fast path's, as in the stage); returns the fast features.
std::vector<core::ObjectFeatureVector> checkFeatures(const std::vector<Frame>& frames,
                                                     std::size_t* objects) {
  core::ObjectFeatureExtractor extractor;
  std::vector<core::ObjectFeatureVector> all;
  for (const Frame& f : frames) {
    extractor.indexForeground(f.foreground);
    for (std::size_t i = 0; i < f.objects.size(); ++i) {
      const core::ObjectFeatureVector fast = extractor.compute(f.foreground, f.objects[i]);
      const core::ObjectFeatureVector ref = extractor.computeReference(f.foreground, f.objects[i]);
      EXPECT_TRUE(sameBits(fast, ref))
          << f.name << " object " << i << ":" << differences(fast, ref);
      all.push_back(fast);
    }
    *objects += f.objects.size();
  }
  return all;
}

// predict() against predictPlain() bit for bit, and both against OpenCV's votes.
void checkForest(const core::ObjectClassifierModel& model,
                 const std::vector<core::ObjectFeatureVector>& rows) {
  std::vector<std::array<float, core::kNumObjectCategories>> fast, plain, opencv;
  model.predict(rows, &fast);
  model.predictPlain(rows, &plain);
  model.predictReference(rows, &opencv);
  ASSERT_EQ(fast.size(), rows.size());
  ASSERT_EQ(plain.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(std::memcmp(fast[i].data(), plain[i].data(), sizeof(fast[i])), 0) << "row " << i;
    for (int c = 0; c < core::kNumObjectCategories; ++c) {
      EXPECT_NEAR(plain[i][c], opencv[i][c], 1e-6) << "row " << i << " class " << c;
    }
  }
}

core::ObjectClassifierModel shippedModel() {
  const std::string path = std::string(UD_SOURCE_DIR) + "/config/object_classifier.yml.gz";
  return core::ObjectClassifierModel::load(path);
}

}  // namespace

TEST(ClassificationEquivalence, RealScansFeaturesAndVotesEqualTheReference) {
  const std::vector<Frame> frames = realFrames();
  if (frames.empty()) GTEST_SKIP() << "no KITTI raw / SemanticKITTI scans in " << UD_SHARED_DATA;
  std::size_t objects = 0;
  const auto features = checkFeatures(frames, &objects);
  EXPECT_GT(objects, 20 * frames.size());  // ~60 objects per KITTI raw sweep
  checkForest(shippedModel(), features);
}

TEST(ClassificationEquivalence, SimulatedDriveFeaturesAndVotesEqualTheReference) {
  std::size_t objects = 0;
  const auto features = checkFeatures(simulatedFrames(3), &objects);
  EXPECT_GT(objects, 10u);
  checkForest(shippedModel(), features);
}

// Objects made to reach every branch of the row ordering: rows already ordered, reversed,
// interleaved runs of two to many lasers, equal azimuths (the fallback to std::sort), points
// missing from the foreground, non-finite points and one absurdly tall object (the reference
// path past the counting sort's bin limit).
TEST(ClassificationEquivalence, HandMadeRowsEqualTheReference) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  LabeledCloud fg;
  std::vector<core::DetectedObject> objects;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int shape = 0; shape < 240; ++shape) {
    core::DetectedObject o;
    const float range = 4.0f + 40.0f * u(rng);
    const float bearing = 6.2831853f * u(rng);
    const int lasers = 1 + shape % 6;
    const int per_laser = 2 + static_cast<int>(rng() % 60);
    const int order = shape % 5;  // 0 ascending, 1 descending, 2 shuffled, 3/4 interleaved
    const bool ties = shape % 7 == 0;
    std::vector<std::uint32_t> idx;
    for (int l = 0; l < lasers; ++l) {
      for (int k = 0; k < per_laser; ++k) {
        // Two lasers per elevation row sometimes (0.05 deg apart): interleaved runs.
        const float elev =
            (-0.1f + 0.006f * static_cast<float>(l / 2) + (l % 2 == 1 ? 0.0009f : 0.0f));
        float az = 0.003f * static_cast<float>(k) + (l % 2 == 1 ? 0.0011f : 0.0f);
        if (ties) az = 0.003f * static_cast<float>(k / 2);
        const float r = range + (u(rng) < 0.3f ? 1.5f * u(rng) : 0.02f * u(rng));
        const float a = bearing + az;
        float z = 1.0f + r * elev;
        if (shape == 17 && k == 0) z = 5000.0f;  // absurd elevation span
        const std::uint32_t index = static_cast<std::uint32_t>(fg.size() * 3 + 1);
        auto p = makeLabeledPoint(r * std::cos(a), r * std::sin(a), z, 4, index,
                                  static_cast<float>(rng() % 256));
        if (shape % 11 == 0 && k == 1) p.x = nan;
        fg.push_back(p);
        idx.push_back(index);
      }
    }
    if (order == 1) std::reverse(idx.begin(), idx.end());
    if (order == 2) std::shuffle(idx.begin(), idx.end(), rng);
    if (order >= 3) {
      // Each laser's run, runs in a random order, some reversed.
      std::vector<std::vector<std::uint32_t>> runs(static_cast<std::size_t>(lasers));
      for (std::size_t k = 0; k < idx.size(); ++k) {
        runs[k / static_cast<std::size_t>(per_laser)].push_back(idx[k]);
      }
      std::shuffle(runs.begin(), runs.end(), rng);
      idx.clear();
      for (auto& run : runs) {
        if (order == 4 && rng() % 2) std::reverse(run.begin(), run.end());
        idx.insert(idx.end(), run.begin(), run.end());
      }
    }
    if (shape % 13 == 0) idx.push_back(999999999u);  // not in the foreground
    o.indices = idx;
    o.centroid = Eigen::Vector3f(range * std::cos(bearing), range * std::sin(bearing), 1.0f);
    o.obb_size = Eigen::Vector3f(1.0f + u(rng), 0.5f + u(rng), 1.5f);
    objects.push_back(o);
  }
  objects.emplace_back();  // an empty object
  core::ObjectFeatureExtractor extractor;
  extractor.indexForeground(fg);
  std::vector<core::ObjectFeatureVector> rows;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const auto fast = extractor.compute(fg, objects[i]);
    const auto ref = extractor.computeReference(fg, objects[i]);
    EXPECT_TRUE(sameBits(fast, ref)) << "object " << i << ":" << differences(fast, ref);
    rows.push_back(fast);
  }
  checkForest(shippedModel(), rows);
}

// The compact forest on rows spread over and beyond the features' ranges, with non-finite
// values (read as 0 by both), and on fewer rows than the four walked together.
TEST(ClassificationEquivalence, CompactForestEqualsThePlainWalk) {
  const core::ObjectClassifierModel model = shippedModel();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (const std::size_t count : {1u, 3u, 4u, 5u, 333u}) {
    std::vector<core::ObjectFeatureVector> x(count);
    for (auto& f : x) {
      for (int k = 0; k < core::kNumObjectFeatures; ++k) {
        const float scale = k < 3 ? 500.0f : (k >= core::kFirstIntensityFeature ? 128.0f : 4.0f);
        f[k] = scale * (1.0f + u(rng));
        if (rng() % 50 == 0) f[k] = std::numeric_limits<float>::quiet_NaN();
        if (rng() % 50 == 0) f[k] = -std::numeric_limits<float>::infinity();
      }
    }
    checkForest(model, x);
  }
}
