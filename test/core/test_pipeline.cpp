// core::Pipeline: the chain written once gives exactly what its stages give one by one.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "segmentation_scene.h"
#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace urban_detection {
namespace core {
namespace {

// A street: two parked cars, a person, a post box and a long wall, sensor 1.73 m up.
CloudXYZIRT street(float shift_x = 0.0f) {
  std::vector<test::Box> boxes = {
      {6.0f + shift_x, 3.0f, 0.0f, 10.2f, 4.8f, 1.5f, 1},      // car
      {-12.0f + shift_x, -4.5f, 0.0f, -7.8f, -2.7f, 1.6f, 2},  // car
      {4.0f + shift_x, -3.0f, 0.0f, 4.5f, -2.5f, 1.8f, 3},     // person
      {-3.0f + shift_x, 5.0f, 0.0f, -2.4f, 5.6f, 1.1f, 4},     // post box
      {-30.0f, 9.0f, 0.0f, 30.0f, 9.5f, 8.0f, 5},              // wall
  };
  std::vector<int> tags;
  return test::rayCast(1.73f, boxes, &tags);
}

// The chain called stage by stage, as every caller did before the Pipeline.
std::vector<DetectedObject> byStages(const PipelineParams& p, const CloudXYZIRT& cloud,
                                     std::vector<DetectedObject>* rejected) {
  GridSegmenter segmenter(p.segmentation);
  std::vector<SegmentClass> labels;
  segmenter.segment(cloud, &labels);
  LabeledCloud foreground;
  extractForeground(cloud, labels, &foreground);
  std::vector<DetectedObject> objects;
  if (p.detector == "kdtree") {
    KdTreeDetector(p.kdtree).detect(foreground, &objects);
  } else {
    HierarchicalGridDetector(p.hierarchical_grid).detect(foreground, &objects);
  }
  ObjectClassifier classifier(p.classifier);
  classifier.apply(foreground, &objects, rejected);
  BoxFitter(p.box_fitting).fit(foreground, &objects);
  return objects;
}

void expectSameObjects(const std::vector<DetectedObject>& a, const std::vector<DetectedObject>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].indices, b[i].indices);
    EXPECT_EQ(a[i].centroid, b[i].centroid);
    EXPECT_EQ(a[i].obb_center, b[i].obb_center);
    EXPECT_EQ(a[i].obb_size, b[i].obb_size);
    EXPECT_EQ(a[i].obb_yaw_rad, b[i].obb_yaw_rad);
    EXPECT_EQ(a[i].category, b[i].category);
    EXPECT_EQ(a[i].class_confidence, b[i].class_confidence);
  }
}

std::set<std::string> stageNames(const PipelineResult& r) {
  std::set<std::string> names;
  for (const StageTiming& t : r.timings) names.insert(t.name);
  return names;
}

TEST(Pipeline, ObjectsEqualTheStagesOneByOne) {
  const CloudXYZIRT cloud = street();
  for (const char* detector : {"hierarchical_grid", "kdtree"}) {
    PipelineParams p;
    p.detector = detector;
    Pipeline pipeline(p);
    const PipelineResult& r = pipeline.process(cloud);
    std::vector<DetectedObject> rejected;
    const std::vector<DetectedObject> expected = byStages(p, cloud, &rejected);
    EXPECT_GE(expected.size(), 4u) << detector;  // cars, person, post box (the wall is tall)
    expectSameObjects(r.objects, expected);
    EXPECT_EQ(r.labels.size(), cloud.size());
    EXPECT_GT(r.foreground.size(), 0u);
    EXPECT_TRUE(r.rejected.empty());  // classifier off by default
    EXPECT_EQ(pipeline.detector().name(), detector);
  }
}

TEST(Pipeline, ShippedClassifierGivesTheSameAsTheStages) {
  const std::string model = std::string(UD_SOURCE_DIR) + "/config/object_classifier.yml.gz";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << "no shipped model at " << model;
  PipelineParams p;
  std::string error;
  ASSERT_TRUE(loadPipelineConfigsYaml({std::string(UD_SOURCE_DIR) + "/config/classification.yaml"},
                                      &p, &error))
      << error;
  ASSERT_TRUE(p.classifier.enabled);
  Pipeline pipeline(p);
  const CloudXYZIRT cloud = street();
  const PipelineResult& r = pipeline.process(cloud);
  std::vector<DetectedObject> rejected;
  const std::vector<DetectedObject> expected = byStages(p, cloud, &rejected);
  expectSameObjects(r.objects, expected);
  expectSameObjects(r.rejected, rejected);
  EXPECT_EQ(r.classification.input, r.objects.size() + r.rejected.size());
  EXPECT_EQ(stageNames(r).count("classification"), 1u);

  // The next revolution's detector output carries no class of this one (objects are reused).
  std::size_t classified = 0;
  for (const DetectedObject& o : r.objects) classified += o.category != ObjectCategory::kUnknown;
  ASSERT_GT(classified, 0u);
  std::size_t seen = 0, stale = 0;
  pipeline.process(street(0.5f), [&](const LabeledCloud&, const std::vector<DetectedObject>& o) {
    seen = o.size();
    for (const DetectedObject& d : o) stale += d.category != ObjectCategory::kUnknown;
  });
  EXPECT_GT(seen, 0u);
  EXPECT_EQ(stale, 0u);
}

TEST(Pipeline, TimingsCoverEveryStageThatRan) {
  PipelineParams p;
  Pipeline pipeline(p);
  const PipelineResult& r = pipeline.process(street());
  EXPECT_EQ(stageNames(r), (std::set<std::string>{"segmentation", "foreground_extraction",
                                                  "detection", "box_fitting"}));
  double sum = 0.0;
  for (const StageTiming& t : r.timings) {
    EXPECT_GE(t.wall_ms, 0.0) << t.name;
    EXPECT_GE(t.cpu_ms, 0.0) << t.name;
    sum += t.wall_ms;
  }
  EXPECT_GT(r.wallMs("segmentation"), 0.0);  // 96k points take more than a clock tick
  EXPECT_DOUBLE_EQ(r.totalWallMs(), sum);
  EXPECT_EQ(r.wallMs("tracking"), 0.0);

  p.box_fitting.enabled = false;
  Pipeline no_boxes(p);
  EXPECT_EQ(stageNames(no_boxes.process(street())).count("box_fitting"), 0u);
}

TEST(Pipeline, EmptyCloudGivesNothing) {
  Pipeline pipeline{PipelineParams()};
  pipeline.process(street());  // a full frame first: nothing of it may stay
  const PipelineResult& r = pipeline.process(CloudXYZIRT());
  EXPECT_TRUE(r.labels.empty());
  EXPECT_TRUE(r.foreground.empty());
  EXPECT_TRUE(r.objects.empty());
  EXPECT_TRUE(r.rejected.empty());
  EXPECT_EQ(stageNames(r).count("detection"), 1u);
}

TEST(Pipeline, DetectOnAForegroundMatchesProcess) {
  PipelineParams p;
  Pipeline whole(p), half(p);
  const PipelineResult& r = whole.process(street());
  const LabeledCloud foreground = r.foreground;
  const PipelineResult& d = half.detect(foreground);
  expectSameObjects(d.objects, r.objects);
  EXPECT_TRUE(d.labels.empty());
  EXPECT_TRUE(d.foreground.empty());
  EXPECT_EQ(stageNames(d).count("segmentation"), 0u);
}

TEST(Pipeline, ObserverSeesTheDetectorsOwnObjects) {
  PipelineParams p;
  Pipeline pipeline(p);
  std::vector<DetectedObject> seen;
  std::size_t foreground_points = 0;
  const PipelineResult& r =
      pipeline.process(street(), [&](const LabeledCloud& fg, const std::vector<DetectedObject>& o) {
        foreground_points = fg.size();
        seen = o;
      });
  HierarchicalGridDetector detector(p.hierarchical_grid);
  std::vector<DetectedObject> expected;
  detector.detect(r.foreground, &expected);
  expectSameObjects(seen, expected);  // before the box fitter changed the boxes
  EXPECT_EQ(foreground_points, r.foreground.size());
}

TEST(Pipeline, TracksFollowAMovingScene) {
  PipelineParams p;
  p.tracking = true;
  Pipeline pipeline(p);
  ASSERT_NE(pipeline.tracker(), nullptr);
  const PipelineResult* r = nullptr;
  for (int frame = 0; frame < 6; ++frame) {
    r = &pipeline.process(street(0.3f * frame), Eigen::Isometry3d::Identity(), 0.1 * frame);
  }
  ASSERT_NE(r->tracks, nullptr);
  std::size_t confirmed = 0;
  for (const Track& t : *r->tracks) confirmed += t.state == TrackState::kConfirmed;
  EXPECT_GE(confirmed, 3u);
  EXPECT_EQ(stageNames(*r).count("tracking"), 1u);

  Pipeline untracked{PipelineParams()};
  EXPECT_EQ(untracked.tracker(), nullptr);
  EXPECT_EQ(untracked.process(street()).tracks, nullptr);
}

TEST(Pipeline, RefusesBadParametersNamingThem) {
  PipelineParams p;
  p.detector = "dbscan";
  EXPECT_THROW(Pipeline{p}, std::invalid_argument);
  p = PipelineParams();
  p.segmentation.cell_size_m = -1.0;
  const std::string error = validate(p);
  EXPECT_NE(error.find("segmentation/"), std::string::npos) << error;
  EXPECT_NE(error.find("cell_size_m"), std::string::npos) << error;
  EXPECT_THROW(Pipeline{p}, std::invalid_argument);
  EXPECT_EQ(validate(PipelineParams()), "");
}

TEST(Pipeline, FieldTableNestsEveryStage) {
  std::set<std::string> groups;
  const PipelineParams defaults;
  forEachField(defaults, [&](const FieldInfo& info, const auto&) {
    groups.insert(info.name.substr(0, info.name.find('/')));
  });
  for (const char* g : {"detector", "tracking", "segmentation", "hierarchical_grid", "kdtree",
                        "classifier", "box_fitting", "tracker"}) {
    EXPECT_EQ(groups.count(g), 1u) << g;
  }
}

// The chain's first two stages, as the segmentation nodelet and the benchmarks run them with a
// segmenter of their own: the labels and foreground process() gives, nothing detected.
TEST(Pipeline, SegmentGivesTheLabelsAndForegroundOfProcess) {
  const CloudXYZIRT cloud = street();
  PipelineParams p;
  Pipeline full(p);
  const PipelineResult& r = full.process(cloud);
  ASSERT_FALSE(r.objects.empty());
  const std::vector<SegmentClass> labels = r.labels;
  const LabeledCloud foreground = r.foreground;
  ASSERT_GT(foreground.size(), 0u);

  Pipeline seg_only(p);
  const PipelineResult& s = seg_only.segment(cloud);
  EXPECT_EQ(s.labels, labels);
  ASSERT_EQ(s.foreground.size(), foreground.size());
  for (std::size_t i = 0; i < foreground.size(); ++i) {
    EXPECT_EQ(s.foreground[i].index, foreground[i].index);
    EXPECT_EQ(s.foreground[i].x, foreground[i].x);
  }
  EXPECT_TRUE(s.objects.empty());
  ASSERT_EQ(s.timings.size(), 2u);
  EXPECT_STREQ(s.timings[0].name, "segmentation");
  EXPECT_STREQ(s.timings[1].name, "foreground_extraction");

  GridSegmenter own(p.segmentation);
  std::vector<SegmentClass> own_labels;
  LabeledCloud own_foreground;
  segmentForeground(own, cloud, &own_labels, &own_foreground);
  EXPECT_EQ(own_labels, labels);
  EXPECT_EQ(own_foreground.size(), foreground.size());
  // Without a foreground only the labels are made.
  std::vector<SegmentClass> only_labels;
  std::vector<StageTiming> timings;
  segmentForeground(own, cloud, &only_labels, nullptr, &timings);
  EXPECT_EQ(only_labels, labels);
  ASSERT_EQ(timings.size(), 1u);
  EXPECT_STREQ(timings[0].name, "segmentation");
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
