// The library work behind the command-line tools (urban_detection_eval, _train_classifier,
// _bench, _spark): report text and JSON, dataset and source opening, SPARK files and the KITTI
// truth of a detection for the camera-fusion precision.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "test_files.h"
#include "urban_detection/core/evaluation/bench_sources.h"
#include "urban_detection/core/evaluation/datasets.h"
#include "urban_detection/core/evaluation/detection_scoring.h"
#include "urban_detection/core/evaluation/feature_table.h"
#include "urban_detection/core/evaluation/kitti_box_quality.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/evaluation/tracking_eval.h"
#include "urban_detection/core/evaluation/training.h"
#include "urban_detection/core/spark/kitti_spark_eval.h"
#include "urban_detection/core/spark/spark_io.h"

namespace ud = urban_detection;
namespace core = urban_detection::core;

namespace {

core::DetectionScore score(std::size_t no, std::size_t tp, std::size_t fo) {
  core::DetectionScore s;
  s.no = no;
  s.tp = tp;
  s.mo = no - tp;
  s.fo = fo;
  s.detections = tp + fo;
  return s;
}

TEST(ToolLibrary, AppendfFormatsLikePrintf) {
  std::string out = "a";
  core::appendf(&out, "%-4s|%5.2f|%zu", "x", 3.14159, std::size_t{42});
  EXPECT_EQ(out, "ax   | 3.14|42");
  core::appendf(&out, "%s", "");
  EXPECT_EQ(out, "ax   | 3.14|42");
}

TEST(ToolLibrary, FeatureCsvHasAHeaderAndOneRowPerDetection) {
  const std::string path = ud_test::tempPath("features.csv");
  {
    core::FeatureCsvWriter csv(path, "frame,verdict");
    ASSERT_TRUE(csv.enabled());
    ASSERT_TRUE(csv.ok());
    core::ObjectFeatureVector v{};
    v[0] = 1.5f;
    v[1] = 0.1f;
    csv.row("000001,true", v);
  }
  std::ifstream in(path);
  std::string header, row, rest;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_FALSE(std::getline(in, rest));
  EXPECT_EQ(header, "frame,verdict," + std::string(core::featureName(0)) + "," +
                        core::featureName(1) +
                        header.substr(header.find(core::featureName(1)) +
                                      std::string(core::featureName(1)).size()));
  EXPECT_EQ(std::count(header.begin(), header.end(), ','), 1 + core::kNumObjectFeatures);
  EXPECT_EQ(row.rfind("000001,true,1.5,0.1,0,", 0), 0u);
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), 1 + core::kNumObjectFeatures);
  std::remove(path.c_str());
  const core::FeatureCsvWriter none("", "x");
  EXPECT_FALSE(none.enabled());
  EXPECT_TRUE(none.ok());
  const core::FeatureCsvWriter bad(ud_test::tempPath("no_dir/features.csv"), "x");
  EXPECT_FALSE(bad.ok());
}

TEST(ToolLibrary, TrainingScoreRowAndJson) {
  const core::DetectionScore s = score(10, 8, 2);  // P 0.8, R 0.8
  EXPECT_EQ(core::trainingScoreRow(s), "   10     2     2     0.800   0.800   0.800");
  EXPECT_EQ(core::trainingScoreJson(s),
            "{\"no\": 10, \"mo\": 2, \"fo\": 2, \"precision\": 0.8, \"recall\": 0.8, "
            "\"f_rate\": 0.8}");
}

TEST(ToolLibrary, ConfusionTableAndJson) {
  core::CategoryConfusion c{};
  c[0][0] = 5;
  c[0][1] = 2;
  c[1][0] = 7;
  const std::string table = core::confusionTable(c);
  // A header line and one line per label, each label's counts in its row.
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), core::kNumObjectCategories + 1);
  const std::string first = core::toString(static_cast<core::ObjectCategory>(0));
  const std::size_t row = table.find('\n' + std::string(14 - first.size(), ' ') + first);
  ASSERT_NE(row, std::string::npos);
  EXPECT_NE(table.find("            5            2", row), std::string::npos);
  const std::string json = core::confusionJson(c);
  EXPECT_EQ(json.substr(0, 10), "[[5, 2, 0,");
  EXPECT_NE(json.find("], [7, 0,"), std::string::npos);
  EXPECT_EQ(json.back(), ']');
}

TEST(ToolLibrary, MotLineNamesTheRunAndItsCounts) {
  core::ClearMotResult r;
  r.frames = 12;
  r.gt = 30;
  r.matches = 27;
  r.misses = 3;
  r.false_positives = 1;
  r.id_switches = 2;
  const std::string line = core::motLine("tracker", r);
  EXPECT_EQ(line.rfind("tracker ", 0), 0u);
  EXPECT_NE(line.find("frames   12  GT     30"), std::string::npos);
  EXPECT_NE(line.find("FN 3  FP 1  IDSW 2"), std::string::npos);
  EXPECT_EQ(line.back(), '\n');
}

TEST(ToolLibrary, TrackingEvaluationReportsAMissingDataset) {
  core::TrackingEvalParams p;
  core::TrackingEvalInput in;
  in.kitti_tracking_dir = ud_test::tempPath("no_such_kitti_tracking");
  std::string text, json, error;
  EXPECT_FALSE(core::runTrackingEvaluation(p, in, &text, &json, &error));
  EXPECT_FALSE(error.empty());
  core::TrackingEvalInput sim;
  sim.sim_gt = ud_test::tempPath("no.gt");
  sim.sim_pcap = ud_test::tempPath("no.pcap");
  sim.calibration_path = ud_test::tempPath("no_calibration.yaml");
  error.clear();
  EXPECT_FALSE(core::runTrackingEvaluation(p, sim, &text, &json, &error));
  EXPECT_FALSE(error.empty());
}

TEST(ToolLibrary, EvalReportOfOneDetector) {
  core::EvaluationParams ep;
  ep.min_points = 30;
  core::DetectorScoring scoring(ep);
  core::EvalRunSummary s;
  s.dataset = "sim";
  s.path = "drive \"1\".pcap";
  s.frames_evaluated = 3;
  s.frames_failed = 1;
  s.params = ep;
  s.configs = {"a.yaml"};
  s.detectors = {"hierarchical_grid"};
  s.scoring = {&scoring};
  s.foreground["road"] = 4;
  const std::string tables = core::scoreTables(s);
  EXPECT_NE(tables.find("small objects (< 30 points) count only when matched (--min-points 30)"),
            std::string::npos);
  EXPECT_NE(tables.find("sim             hierarchical_grid  off              3"),
            std::string::npos);
  EXPECT_NE(tables.find("off, N=1"), std::string::npos);
  EXPECT_EQ(tables.find("on, N=1"), std::string::npos);  // classifier off: two rows
  s.classifier = true;
  s.classifier_model = "model.yml.gz";
  EXPECT_NE(core::scoreTables(s).find("on, N=1"), std::string::npos);
  const std::string lines = core::diagnosticsLines(s, true);
  EXPECT_NE(lines.find("hierarchical_grid: classifier rejected by content {}"), std::string::npos);
  EXPECT_NE(lines.find("hierarchical_grid: false parts of GT objects by kind"), std::string::npos);
  EXPECT_EQ(core::diagnosticsLines(s, false).find("false parts"), std::string::npos);

  const std::string json = core::evalReportJson(s, "    {\"frame\": \"0\"}", "");
  EXPECT_NE(json.find("\"path\": \"drive \\\"1\\\".pcap\""), std::string::npos);
  EXPECT_NE(json.find("\"frames_evaluated\": 3,\n  \"frames_failed\": 1"), std::string::npos);
  EXPECT_NE(json.find("\"classifier\": \"model.yml.gz\""), std::string::npos);
  EXPECT_NE(json.find("\"configs\": [\"a.yaml\"]"), std::string::npos);
  EXPECT_NE(json.find("\"foreground_points_by_class\": {\"road\": 4}"), std::string::npos);
  EXPECT_EQ(json.find("box_quality"), std::string::npos);
  EXPECT_NE(core::evalReportJson(s, "", "{}").find("\"box_quality\": {}"), std::string::npos);
  s.classifier = false;
  EXPECT_NE(core::evalReportJson(s, "", "").find("\"classifier\": null"), std::string::npos);
}

TEST(ToolLibrary, BoxQualityTablesWithoutSamplesHaveOnlyHeaders) {
  core::KittiBoxQuality q(ud_test::tempPath("no_kitti"), core::BoxFittingParams());
  const std::string t = q.tables();
  EXPECT_NE(t.find("matched detections (the pipeline)"), std::string::npos);
  EXPECT_NE(t.find("box fitting alone"), std::string::npos);
  EXPECT_EQ(std::count(t.begin(), t.end(), '\n'), 6);  // two blank + title + header lines
}

TEST(ToolLibrary, EvalDatasetSourceNamesItsPath) {
  core::EvalDatasetSource s;
  s.sim_gt = "drive.gt";
  s.sim_pcap = "drive.pcap";
  EXPECT_EQ(s.path(), "drive.pcap");
  s.semantic_kitti_dir = "skitti";
  EXPECT_EQ(s.path(), "skitti");
  s.kitti_object_dir = "kitti";
  EXPECT_EQ(s.path(), "kitti");
  const std::string dir = ud_test::tempPath("empty_kitti");
  std::filesystem::create_directories(dir);
  s.kitti_object_dir = dir;
  const std::unique_ptr<core::Dataset> ds = core::openEvalDataset(s);
  ASSERT_TRUE(ds);
  EXPECT_EQ(ds->name(), "kitti_object");
  core::EvalDatasetSource bad;
  bad.sim_gt = "x.gt";
  bad.sim_pcap = "x.pcap";
  bad.calibration_path = ud_test::tempPath("missing_calibration.yaml");
  EXPECT_ANY_THROW(core::openEvalDataset(bad));
  std::filesystem::remove_all(dir);
}

TEST(ToolLibrary, RevolutionSourcesOfFoldersAndPcap) {
  const std::string dir = ud_test::tempPath("sweeps");
  std::filesystem::create_directories(dir);
  EXPECT_TRUE(core::openRevolutionSources({dir}, {dir}, "", "").empty());  // no files: warned
  { std::ofstream(dir + "/000000.bin") << ""; }
  const auto sources = core::openRevolutionSources({dir}, {dir}, "", "");
  ASSERT_EQ(sources.size(), 1u);  // the .bin folder only
  EXPECT_NE(sources[0]->describe().find(dir), std::string::npos);
  EXPECT_ANY_THROW(core::openRevolutionSources({}, {}, dir + "/x.pcap", dir + "/missing.yaml"));
  std::filesystem::remove_all(dir);
}

TEST(ToolLibrary, SparkColouredCloudRoundTrip) {
  ud::CloudXYZIRT cloud;
  cloud.push_back(ud::makePoint(1.0f, 2.0f, 3.0f));
  cloud.push_back(ud::makePoint(4.0f, 5.0f, 6.0f));
  cloud.push_back(ud::makePoint(7.0f, 8.0f, 9.0f));
  const std::vector<cv::Vec3b> rgb = {cv::Vec3b(10, 20, 30), cv::Vec3b(40, 50, 60)};
  const std::string path = ud_test::tempPath("coloured.pcd");
  ASSERT_TRUE(core::writeColouredCloud(path, cloud, rgb, {2, 0}));
  ud::CloudXYZIRT back;
  std::vector<cv::Vec3b> back_rgb;
  std::string error;
  ASSERT_TRUE(core::readSparkCloud(path, &back, &back_rgb, &error)) << error;
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].x, 7.0f);
  EXPECT_EQ(back[1].z, 3.0f);
  ASSERT_EQ(back_rgb.size(), 2u);
  EXPECT_EQ(back_rgb[0], cv::Vec3b(128, 128, 128));  // no colour given: grey
  EXPECT_EQ(back_rgb[1], cv::Vec3b(10, 20, 30));
  std::remove(path.c_str());
  EXPECT_FALSE(core::readSparkCloud(path, &back, &back_rgb, &error));
  EXPECT_NE(error.find(path), std::string::npos);
}

TEST(ToolLibrary, SparkClassColoursNamesAndLists) {
  const ud_test::TempFile file(".txt", "255 0 0\nnot a colour\n0,128,255\n");
  std::vector<cv::Vec3b> colours;
  std::string error;
  ASSERT_TRUE(core::classColours(file.path(), &colours, &error));
  ASSERT_EQ(colours.size(), 256u);
  EXPECT_EQ(colours[0], cv::Vec3b(0, 0, 255));  // BGR
  EXPECT_EQ(colours[1], cv::Vec3b(255, 128, 0));
  EXPECT_EQ(colours[255], cv::Vec3b(0, 0, 0));
  EXPECT_FALSE(core::classColours(ud_test::tempPath("none.txt"), &colours, &error));
  ASSERT_TRUE(core::classColours("", &colours, &error));
  EXPECT_EQ(colours[1], cv::Vec3b(67, 151, 117));  // the palette
  cv::Mat labels(1, 2, CV_8U);
  labels.at<uchar>(0, 0) = 1;
  labels.at<uchar>(0, 1) = 255;
  const cv::Mat shown = core::colourMask(labels, colours);
  EXPECT_EQ(shown.at<cv::Vec3b>(0, 0), colours[1]);
  EXPECT_EQ(shown.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(core::sparkClassName({"road", ""}, 0), "road");
  EXPECT_EQ(core::sparkClassName({"road", ""}, 1), "class_1");
  EXPECT_EQ(core::sparkClassName({"road"}, 7), "class_7");
  EXPECT_EQ(core::sparkClassName({"road"}, -1), "unknown");
  EXPECT_EQ(core::splitCommaList("car,,person,"), (std::vector<std::string>{"car", "person"}));
  EXPECT_TRUE(core::splitCommaList("").empty());
}

TEST(ToolLibrary, SparkModelOptions) {
  core::CameraStageParams stage;
  std::string colours, error;
  int asked = 0;
  auto apply = [&](const std::string& option, const std::string& v) {
    return core::applyCameraModelOption(
        option,
        [&] {
          ++asked;
          return v;
        },
        &stage, &colours, &error);
  };
  EXPECT_EQ(apply("--model", "net.onnx"), 1);
  EXPECT_EQ(stage.model.network.model_path, "net.onnx");
  EXPECT_EQ(apply("--input-size", "512x256"), 1);
  EXPECT_EQ(stage.model.network.input_width_px, 512);
  EXPECT_EQ(stage.model.network.input_height_px, 256);
  EXPECT_EQ(apply("--mean", "0.5,1,2"), 1);
  EXPECT_EQ(stage.model.network.mean[2], 2.0);
  EXPECT_EQ(apply("--keep", "car,,person"), 1);
  EXPECT_EQ(stage.model.keep_classes, (std::vector<std::string>{"car", "person"}));
  EXPECT_EQ(apply("--colours", "c.txt"), 1);
  EXPECT_EQ(colours, "c.txt");
  EXPECT_EQ(asked, 5);
  EXPECT_EQ(apply("--bgr", ""), 1);  // a flag: no value taken
  EXPECT_FALSE(stage.model.network.input_rgb);
  EXPECT_EQ(asked, 5);
  EXPECT_EQ(apply("--stride", "4"), 0);  // not a model option: left to the tool
  EXPECT_EQ(asked, 5);
  EXPECT_EQ(apply("--scale", "1,2"), -1);
  EXPECT_NE(error.find("--scale"), std::string::npos);
  EXPECT_EQ(apply("--mean", "1,x,2"), -1);
  EXPECT_EQ(stage.model.network.mean[2], 2.0);  // unchanged
  EXPECT_EQ(apply("--input-size", "big"), -1);
}

TEST(ToolLibrary, SparkPrecisionCounts) {
  core::SparkPrecisionCounts c;
  core::KittiDetectionTruth car;
  car.scored = car.is_true = true;
  car.truth = core::ObjectCategory::kVehicle;
  core::KittiDetectionTruth none;
  none.scored = true;
  c.add(core::ObjectCategory::kVehicle, car);     // true, class right
  c.add(core::ObjectCategory::kPedestrian, car);  // true, class wrong
  c.add(core::ObjectCategory::kVehicle, none);    // false
  c.add(core::ObjectCategory::kNonObject, car);   // vetoed a true one
  EXPECT_EQ(c.kept, 3);
  EXPECT_EQ(c.true_objects, 2);
  EXPECT_EQ(c.class_correct, 1);
  EXPECT_EQ(c.vetoed, 1);
  EXPECT_EQ(c.vetoed_true, 1);
  EXPECT_EQ(c.json(),
            "{\"kept\": 3, \"true\": 2, \"class_correct\": 1, \"vetoed\": 1, \"vetoed_true\": 1, "
            "\"precision\": 0.666667, \"class_precision\": 0.333333}");
}

TEST(ToolLibrary, KittiTruthOfDetectionsAndTheBoxOracle) {
  const std::string dir = std::string(UD_SHARED_DATA) + "/kitti_object";
  core::KittiSparkFrame f;
  std::string error;
  if (!core::loadKittiSparkFrame(dir, "000003", true, &f, &error))
    GTEST_SKIP() << "KITTI object frames not found under " << dir << ": " << error;
  const std::vector<int> owners = core::kittiPointOwners(f);
  ASSERT_EQ(owners.size(), f.cloud.size());
  // A detection made of one labelled car's own points is true, of that car's category.
  int car = -1;
  for (std::size_t k = 0; k < f.labels.size() && car < 0; ++k)
    if (f.labels[k].type == "Car" && core::kittiBoxPoints(f, f.labels[k]).size() > 50)
      car = static_cast<int>(k);
  ASSERT_GE(car, 0);
  core::DetectedObject o;
  for (const std::size_t i : core::kittiBoxPoints(f, f.labels[car]))
    o.indices.push_back(static_cast<std::uint32_t>(i));
  const core::KittiDetectionTruth t = core::kittiDetectionTruth(f, owners, o);
  EXPECT_TRUE(t.scored);
  EXPECT_TRUE(t.is_true);
  EXPECT_EQ(t.label, car);
  EXPECT_EQ(t.truth, core::ObjectCategory::kVehicle);
  // Points behind the sensor are out of the camera's view: not scored.
  core::DetectedObject behind;
  for (std::size_t i = 0; i < f.cloud.size() && behind.indices.size() < 100; ++i)
    if (f.cloud[i].x < -5.0f) behind.indices.push_back(static_cast<std::uint32_t>(i));
  EXPECT_FALSE(core::kittiDetectionTruth(f, owners, behind).scored);
  // The oracle paints the car's 2-D box with the index of its type.
  const cv::Mat mask = core::kittiBoxOracleMask(f, {"background", "Car"});
  ASSERT_EQ(mask.size(), f.image.size());
  const auto& b = f.labels[car].bbox;
  EXPECT_EQ(
      mask.at<uchar>(static_cast<int>(0.5 * (b[1] + b[3])), static_cast<int>(0.5 * (b[0] + b[2]))),
      1);
  EXPECT_EQ(cv::countNonZero(core::kittiBoxOracleMask(f, {"background"})), 0);
}

}  // namespace
