// The evaluation library the tools are front ends of (core/evaluation): report helpers, the
// dataset helpers, another system's detections, the diagnostics of missed and false objects,
// the per-detector scoring, the output digest, the benchmark sources, the synthetic decode
// scene and the tracker's timing case, on small cases with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "test_files.h"
#include "urban_detection/core/evaluation/bench_sources.h"
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/detection_diagnostics.h"
#include "urban_detection/core/evaluation/detection_scoring.h"
#include "urban_detection/core/evaluation/external_detections.h"
#include "urban_detection/core/evaluation/output_digest.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/evaluation/tracker_bench.h"
#include "urban_detection/core/simulation/synthetic_scene.h"

namespace ud = urban_detection::core;
namespace fs = std::filesystem;

namespace {

urban_detection::PointXYZIRT point(float x, float y, float z) {
  urban_detection::PointXYZIRT p;
  p.x = x;
  p.y = y;
  p.z = z;
  p.intensity = 0.0f;
  p.ring = 0;
  p.time = 0.0f;
  return p;
}

// A dataset of one frame whose point classes are named "c0", "c1", ...
class NamedClasses : public ud::Dataset {
 public:
  std::string name() const override { return "named"; }
  Status next(ud::Frame*, std::string*) override { return Status::kEnd; }
  std::string className(std::uint16_t c) const override { return "c" + std::to_string(c); }
};

// A dataset of files whose odd frames cannot be read.
class OddFramesFail : public ud::IndexedDataset {
 public:
  std::string name() const override { return "odd"; }
  std::size_t size() const override { return 5; }
  bool load(std::size_t i, ud::Frame* f, std::string* error) override {
    f->id = std::to_string(i);
    if (i % 2) *error = "frame " + f->id;
    return i % 2 == 0;
  }
  std::string className(std::uint16_t) const override { return "?"; }
};

}  // namespace

TEST(EvaluationReport, OrderStatisticsAndJson) {
  EXPECT_DOUBLE_EQ(ud::median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(ud::median({4.0, 1.0, 2.0, 3.0}), 2.5);
  EXPECT_TRUE(std::isnan(ud::median({})));
  // Nearest rank: the ceil(q * n)-th smallest.
  const std::vector<double> v = {5, 1, 4, 2, 3, 10, 9, 8, 7, 6};
  EXPECT_DOUBLE_EQ(ud::percentile(v, 0.9), 9.0);
  EXPECT_DOUBLE_EQ(ud::percentile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(ud::percentile(v, 1.0), 10.0);
  EXPECT_DOUBLE_EQ(ud::percentile(v, 0.25), 3.0);
  EXPECT_TRUE(std::isnan(ud::percentile({}, 0.5)));
  EXPECT_EQ(ud::jsonNumber(0.5), "0.5");
  EXPECT_EQ(ud::jsonNumber(1.0 / 3.0), "0.333333");
  EXPECT_EQ(ud::jsonNumber(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(ud::jsonNumber(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(ud::jsonEscape("a\"b\\c\nd"), "a\\\"b\\\\c\\u000ad");
  EXPECT_EQ(ud::jsonEscape("plain/path_0.bin"), "plain/path_0.bin");
}

TEST(EvaluationReport, PlotNeedsARangeAndWritesAPng) {
  const std::string png = ud_test::tempPath("plot.png");
  ud::Series s;
  s.x = {0.0, 1.0, 2.0};
  s.y = {0.0, 0.5, 1.0};
  s.label = "line";
  EXPECT_TRUE(ud::plotSeries(png, "title", "x", {s}, 0.0, 1.0));
  EXPECT_GT(fs::file_size(png), 1000u);
  std::remove(png.c_str());
  EXPECT_FALSE(ud::plotSeries(png, "title", "x", {s}, 1.0, 1.0));  // no y range
  s.x = {1.0, 1.0, 1.0};
  EXPECT_FALSE(ud::plotSeries(png, "title", "x", {s}, 0.0, 1.0));  // no x range
  EXPECT_FALSE(fs::exists(png));
}

TEST(EvaluationDatasets, GroupsAndMostCommon) {
  EXPECT_EQ(ud::frameGroup("08/000123", "semantic_kitti"), "08");
  EXPECT_EQ(ud::frameGroup("rev12", "sim"), "sim");
  EXPECT_EQ(ud::mostCommon({}), "?");
  EXPECT_EQ(ud::mostCommon({{"a", 2}, {"b", 5}, {"c", 5}}), "b");  // first on ties
}

TEST(EvaluationDatasets, IndexedDatasetSkipsUnreadableFramesAndEnds) {
  OddFramesFail ds;
  ud::Frame f;
  std::vector<ud::Dataset::Status> seen;
  std::string error;
  for (int k = 0; k < 7; ++k) seen.push_back(ds.next(&f, &error));
  using S = ud::Dataset::Status;
  EXPECT_EQ(seen, (std::vector<S>{S::kFrame, S::kSkipped, S::kFrame, S::kSkipped, S::kFrame,
                                  S::kEnd, S::kEnd}));
  EXPECT_EQ(error, "frame 3");
}

TEST(EvaluationDatasets, DetectionContentNamesWhatMostPointsAre) {
  ud::Frame f;
  for (int i = 0; i < 10; ++i) f.cloud.push_back(point(static_cast<float>(i), 0.0f, 0.0f));
  f.gt.reset(10);
  f.gt.objects.push_back({"car", 7, false, 0});
  for (int i = 0; i < 3; ++i) f.gt.object_of_point[i] = 0;
  f.point_class = {0, 0, 0, 4, 4, 5, 5, 5, 5, 1};
  NamedClasses ds;
  ud::DetectedObject d;
  d.indices = {0, 1, 2, 3, 4};  // three car points, two of class 4
  EXPECT_EQ(ud::detectionContent(f, ds, d), "part_of_car");
  d.indices = {2, 5, 6, 7, 8, 42};  // index 42 is outside the cloud: not counted
  EXPECT_EQ(ud::detectionContent(f, ds, d), "c5");
}

TEST(EvaluationDatasets, SweepsAreListedInOrderAndReadByExtension) {
  const std::string dir = ud_test::tempPath("sweeps");
  fs::create_directories(dir);
  const float xyzi[8] = {1, 2, 3, 0.5f, 4, 5, 6, 0.25f};
  for (const char* name : {"b.bin", "a.bin"}) {
    std::ofstream(dir + "/" + name, std::ios::binary)
        .write(reinterpret_cast<const char*>(xyzi), sizeof xyzi);
  }
  std::ofstream(dir + "/notes.txt") << "not a sweep";
  const std::vector<std::string> files = ud::listSweeps(dir);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(fs::path(files[0]).filename(), "a.bin");
  EXPECT_EQ(fs::path(files[1]).filename(), "b.bin");
  EXPECT_EQ(ud::listSweeps(files[1]), std::vector<std::string>{files[1]});
  urban_detection::CloudXYZIRT cloud;
  std::string error;
  ASSERT_TRUE(ud::readSweep(files[0], &cloud, &error)) << error;
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_FLOAT_EQ(cloud[1].y, 5.0f);
  EXPECT_FALSE(ud::readSweep(dir + "/missing.pcd", &cloud, &error));
  fs::remove_all(dir);
}

TEST(ExternalDetections, InstancesOfTheLabelFileBecomeDetections) {
  const std::string dir = ud_test::tempPath("external");
  fs::create_directories(dir + "/sequences/08/predictions");
  ud::Frame f;
  f.id = "08/000001";
  for (int i = 0; i < 6; ++i) f.cloud.push_back(point(static_cast<float>(i), 1.0f, 0.0f));
  const std::uint32_t labels[6] = {0, 7, 7, 0, 3, 7};
  std::ofstream(dir + "/sequences/08/predictions/000001.label", std::ios::binary)
      .write(reinterpret_cast<const char*>(labels), sizeof labels);
  ud::ExternalDetections ext(dir);
  std::string error;
  ASSERT_TRUE(ext.load(f, &error)) << error;
  std::vector<ud::DetectedObject> objects;
  ext.detect(urban_detection::LabeledCloud(), &objects);
  ASSERT_EQ(objects.size(), 2u);  // in order of first appearance: instance 7, then 3
  EXPECT_EQ(objects[0].id, 1u);
  EXPECT_EQ(objects[0].indices, (std::vector<std::uint32_t>{1, 2, 5}));
  EXPECT_NEAR(objects[0].centroid.x(), (1 + 2 + 5) / 3.0, 1e-6);
  EXPECT_FLOAT_EQ(objects[0].min_pt.x(), 1.0f);
  EXPECT_FLOAT_EQ(objects[0].max_pt.x(), 5.0f);
  EXPECT_FLOAT_EQ(objects[0].obb_size.x(), 4.0f);
  EXPECT_EQ(objects[1].indices, (std::vector<std::uint32_t>{4}));
  // One label too few: refused with the reason.
  f.cloud.push_back(point(9.0f, 0.0f, 0.0f));
  EXPECT_FALSE(ext.load(f, &error));
  EXPECT_NE(error.find("not one uint32 per point"), std::string::npos) << error;
  f.id = "000002";
  EXPECT_FALSE(ext.load(f, &error));
  EXPECT_NE(error.find("no label file"), std::string::npos) << error;
  fs::remove_all(dir);
}

TEST(DetectionDiagnostics, CausesOfMissesAndContentOfFalseDetections) {
  // Object 0 (car): points 0-9, all foreground, swallowed by one big detection with 30 wall
  // points (IoU 0.25: missed, merged with the wall). Object 1 (person): points 40-49,
  // segmented as ground. Object 2 (cyclist): points 50-59, foreground, in no detection.
  ud::Frame f;
  f.id = "f";
  for (int i = 0; i < 60; ++i) f.cloud.push_back(point(10.0f + 0.1f * i, 0.0f, 0.0f));
  f.gt.reset(60);
  f.gt.objects = {{"car", 1, false, 0}, {"person", 2, false, 0}, {"cyclist", 3, false, 0}};
  f.point_class.assign(60, 9);  // "c9": the wall
  for (int i = 0; i < 10; ++i) {
    f.gt.object_of_point[i] = 0;
    f.gt.object_of_point[40 + i] = 1;
    f.gt.object_of_point[50 + i] = 2;
  }
  f.gt.finalize(1);
  std::vector<ud::SegmentClass> seg(60, ud::SegmentClass::kShort);
  for (int i = 40; i < 50; ++i) seg[i] = ud::SegmentClass::kGround;
  std::vector<ud::DetectedObject> dets(1);
  for (std::uint32_t i = 0; i < 40; ++i) dets[0].indices.push_back(i);
  ud::DetectionEvaluator ev;
  ud::FrameMatch m;
  ev.evaluate(f.gt, dets, &m);
  ASSERT_EQ(m.verdict[0], ud::DetectionVerdict::kFalse);
  NamedClasses ds;
  ud::DetectionDiagnostics diag;
  ud::diagnose(f, ds, seg, dets, m, {}, "test", &diag, nullptr);
  EXPECT_EQ(diag.missed_by_cause,
            (std::map<std::string, std::size_t>{{"detector:merged_with(c9)", 1},
                                                {"segmentation:not_foreground(ground)", 1},
                                                {"detector:dropped(small_or_noise)", 1}}));
  EXPECT_EQ(diag.false_by_class, (std::map<std::string, std::size_t>{{"c9", 1}}));
  EXPECT_TRUE(diag.false_fragments.empty());
  // The cyclist's points in a detection the classifier rejected: the classifier's miss.
  std::vector<ud::DetectedObject> rejected(1);
  for (std::uint32_t i = 50; i < 60; ++i) rejected[0].indices.push_back(i);
  ud::DetectionDiagnostics diag2;
  ud::diagnose(f, ds, seg, dets, m, rejected, "test", &diag2, nullptr);
  EXPECT_EQ(diag2.missed_by_cause.count("classifier:rejected_as_non_object"), 1u);
  EXPECT_EQ(diag2.missed_by_cause.count("detector:dropped(small_or_noise)"), 0u);
}

TEST(SyntheticScene, RaysHitTheGroundTheWallsAndTheBox) {
  const ud::SyntheticSceneParams s;
  const float origin[3] = {0.0f, 0.0f, 0.0f};
  const float down[3] = {0.0f, 0.0f, -1.0f};
  EXPECT_NEAR(ud::castRay(s, origin, down), s.sensor_height_m, 1e-9);
  const float forward[3] = {1.0f, 0.0f, 0.0f};
  EXPECT_NEAR(ud::castRay(s, origin, forward), s.street_half_length_m, 1e-9);
  const float at_box[3] = {0.0f, 3.0f, -1.0f};  // beside the box, at its height
  EXPECT_NEAR(ud::castRay(s, at_box, forward), s.box_min[0], 1e-9);
  const float up[3] = {0.0f, 0.0f, 1.0f};
  EXPECT_TRUE(std::isinf(ud::castRay(s, origin, up)));
}

TEST(SyntheticScene, EveryBeamOfARevolutionReturns) {
  const ud::Calibration cal = ud::Calibration::nominalHdl64eS2();
  const ud::PacketEncoder encoder(cal);
  const std::vector<ud::RawPacket> packets = ud::scanScene(encoder, ud::SyntheticSceneParams(), 20);
  ASSERT_EQ(packets.size(), 20u);
  ud::PacketDecoder decoder(cal, ud::DecoderParams());
  urban_detection::CloudXYZIRT cloud;
  for (const ud::RawPacket& p : packets) {
    ASSERT_EQ(decoder.decode(p.data(), p.size(), 0.0, &cloud, nullptr), ud::PacketStatus::kOk);
  }
  EXPECT_EQ(cloud.size(), 20u * 384u);
  EXPECT_TRUE(ud::readKittiBinXyz(ud_test::tempPath("absent.bin")).empty());
}

TEST(TrackerBench, TimesBoxFittingAndTheTrackerEveryRevolution) {
  std::map<std::string, int> calls;
  ud::benchTracker(8, 5, [&](const char* stage, const std::function<void()>& call) {
    ++calls[stage];
    call();
  });
  EXPECT_EQ(calls, (std::map<std::string, int>{{"box_fitting_100_objects", 5},
                                               {"tracker_100_objects", 5}}));
}

TEST(DetectorScoring, PipelineAndDetectorAloneScoredApart) {
  // Two cars of 10 points; the detector finds both, the classifier then drops the second.
  ud::Frame f;
  f.id = "07/000001";
  for (int i = 0; i < 20; ++i) f.cloud.push_back(point(5.0f + 0.1f * i, 0.0f, 0.0f));
  f.gt.reset(20);
  f.gt.objects = {{"car", 1, false, 0}, {"car", 2, false, 0}};
  f.point_class.assign(20, 0);
  for (int i = 0; i < 20; ++i) f.gt.object_of_point[i] = i / 10;
  f.gt.finalize(1);
  std::vector<ud::DetectedObject> found(2);
  for (std::uint32_t i = 0; i < 20; ++i) found[i / 10].indices.push_back(i);
  found[0].category = ud::ObjectCategory::kPedestrian;  // a wrong class, counted as a pair
  const std::vector<ud::DetectedObject> kept = {found[0]}, rejected = {found[1]};
  ud::EvaluationParams ep;
  ep.min_points = 1;
  ud::DetectorScoring s(ep);
  const std::vector<float> range = ud::gtObjectRanges(f.gt, f.cloud);
  ud::FrameMatch m;
  s.addDetectorAlone(f.gt, found, range, &m);
  const std::vector<ud::SegmentClass> seg(20, ud::SegmentClass::kShort);
  NamedClasses ds;
  s.add(f, ds, seg, kept, rejected, range, true, "test", nullptr, &m);
  EXPECT_EQ(s.detectorAlone().total().mo, 0u);
  EXPECT_EQ(s.scored().total().no, 2u);
  EXPECT_EQ(s.scored().total().mo, 1u);
  EXPECT_EQ(s.byGroup().at("07").mo, 1u);
  EXPECT_EQ(s.classifierRejected(), (std::map<std::string, std::size_t>{{"part_of_car", 1}}));
  EXPECT_EQ(s.classPairs(), (std::map<std::string, std::size_t>{{"vehicle->pedestrian", 1}}));
  EXPECT_EQ(s.diagnostics().missed_by_cause,
            (std::map<std::string, std::size_t>{{"classifier:rejected_as_non_object", 1}}));
  const std::string json = s.jsonMembers();
  EXPECT_EQ(json.rfind("\"no\": 2, \"mo\": 1, \"fo\": 0", 0), 0u) << json;
  EXPECT_NE(json.find("\"by_sequence\": {\"07\": {\"no\": 2"), std::string::npos) << json;
  EXPECT_EQ(ud::countsJson({{"a\"b", 2}, {"c", 3}}), "{\"a\\\"b\": 2, \"c\": 3}");
}

TEST(OutputDigest, ChangesWithAnyOutputBitAndNotWithoutOne) {
  // A detector that returns fixed objects, the second call's yaw optionally perturbed.
  class Fixed : public ud::ObjectDetector {
   public:
    explicit Fixed(float yaw) : yaw_(yaw) {}
    std::string name() const override { return "fixed"; }
    void detect(const urban_detection::LabeledCloud&,
                std::vector<ud::DetectedObject>* objects) override {
      objects->assign(2, ud::DetectedObject());
      (*objects)[0].id = 1;
      (*objects)[0].indices = {1, 2, 3};
      (*objects)[1].id = 2;
      (*objects)[1].obb_yaw_rad = yaw_;
    }

   private:
    float yaw_;
  };
  const std::vector<urban_detection::LabeledCloud> frames(3);
  Fixed a(0.5f), b(0.5f), c(std::nextafter(0.5f, 1.0f));
  const std::uint64_t da = ud::detectionsDigest(&a, frames);
  EXPECT_EQ(da, ud::detectionsDigest(&b, frames));
  EXPECT_NE(da, ud::detectionsDigest(&c, frames));
  EXPECT_NE(da, ud::detectionsDigest(&a, std::vector<urban_detection::LabeledCloud>(2)));
  ud::Fnv1aDigest empty;
  EXPECT_EQ(empty.value(), 14695981039346656037ull);  // the FNV-1a offset basis
  empty.add(std::uint8_t{'a'});
  EXPECT_EQ(empty.value(), 0xaf63dc4c8601ec8cull);  // FNV-1a 64 of "a"
}

TEST(BenchSources, FilesAreReadInOrderAndRewound) {
  const std::string dir = ud_test::tempPath("bench_src");
  fs::create_directories(dir);
  const float one[4] = {1, 2, 3, 0}, two[8] = {1, 2, 3, 0, 4, 5, 6, 0};
  std::ofstream(dir + "/a.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(one), sizeof one);
  std::ofstream(dir + "/b.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(two), sizeof two);
  ud::FileRevolutionSource src(dir, ud::listSweeps(dir), false);
  urban_detection::CloudXYZIRT cloud;
  double ms = 0.0, cpu_ms = 0.0;
  std::vector<std::size_t> sizes;
  while (src.next(&cloud, &ms, &cpu_ms)) sizes.push_back(cloud.size());
  EXPECT_EQ(sizes, (std::vector<std::size_t>{1, 2}));
  EXPECT_LT(ms, 0.0);  // no packets decoded
  src.rewind();
  ASSERT_TRUE(src.next(&cloud, &ms, &cpu_ms));
  EXPECT_EQ(cloud.size(), 1u);
  EXPECT_NE(src.describe().find("2 KITTI .bin scans"), std::string::npos);
  std::map<std::string, std::vector<double>> wall, cpu;
  double wall_total = 0.0;
  ud::StageTimer t;
  t.stop("stage", &wall, &cpu, &wall_total);
  ASSERT_EQ(wall["stage"].size(), 1u);
  EXPECT_GE(wall["stage"][0], 0.0);
  EXPECT_DOUBLE_EQ(wall_total, wall["stage"][0]);
  EXPECT_GE(ud::threadCpuMs(), 0.0);
  fs::remove_all(dir);
}
