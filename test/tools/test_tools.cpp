// The command-line contract of the measuring tools: urban_detection_bench,
// urban_detection_eval and urban_detection_seg_eval run on a short simulated drive (made here
// with urban_detection_simulate) and write the JSON keys that scripts and CI consume, with
// values that agree with each other.
// No timing is asserted (numbers come from benchmarks, not tests); the F-rate comparison is on
// the simulator's seeded drive, so it is deterministic.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>
#include <fstream>
#include <iterator>

#include <boost/property_tree/json_parser.hpp>
#include <boost/property_tree/ptree.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fs = std::filesystem;
namespace pt = boost::property_tree;

namespace {

const std::string kTools = UD_TOOL_DIR;
const std::string kConfig = std::string(UD_SOURCE_DIR) + "/config/";

// Runs `command` through the shell with stdout/stderr to `log`; returns the exit status.
int run(const std::string& command, const std::string& log) {
  const int status = std::system((command + " >" + log + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string configs() {
  std::string args;
  for (const char* stage : {"segmentation", "hierarchical_grid", "kdtree", "classification"}) {
    args += " --config " + kConfig + stage + ".yaml";
  }
  return args;
}

class ToolsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = (fs::temp_directory_path() / ("ud_test_tools_" + std::to_string(getpid()))).string();
    fs::create_directories(dir_);
    ASSERT_EQ(0, run(kTools + "/urban_detection_simulate --config " + kConfig +
                         "demo_drive.yaml --revolutions 4 --pcap " + dir_ + "/drive.pcap --gt " +
                         dir_ + "/drive.gt",
                     dir_ + "/simulate.log"))
        << "see " << dir_ << "/simulate.log";
  }
  static void TearDownTestSuite() {
    // Kept (with the tools' logs) when a test failed.
    if (!::testing::UnitTest::GetInstance()->current_test_suite()->Passed()) return;
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static pt::ptree readJson(const std::string& path) {
    pt::ptree tree;
    pt::read_json(path, tree);
    return tree;
  }
  // Runs the bench on the simulated drive with `options`; its JSON output is in *json.
  static void bench(const std::string& name, const std::string& options, pt::ptree* json) {
    const std::string path = dir_ + "/" + name + ".json";
    ASSERT_EQ(0, run(kTools + "/urban_detection_bench --pcap " + dir_ + "/drive.pcap" + configs() +
                         " " + options + " --json " + path,
                     dir_ + "/" + name + ".log"));
    *json = readJson(path);
  }
  static std::string dir_;
};
std::string ToolsTest::dir_;

void expectStage(const pt::ptree& json, const std::string& stage) {
  SCOPED_TRACE(stage);
  const auto node = json.get_child_optional("stages." + stage);
  ASSERT_TRUE(node) << "stage missing from the bench JSON";
  const double median = node->get<double>("median_ms"), p95 = node->get<double>("p95_ms");
  EXPECT_GT(median, 0.0);
  EXPECT_GE(p95, median);
}

// docs/parameters.md is what urban_detection_params prints from the field tables: a parameter
// added, removed or changed in a table without regenerating the page fails here.
TEST(ParamsTool, DocsParametersIsCurrent) {
  const std::string out =
      (fs::temp_directory_path() / ("ud_params_" + std::to_string(getpid()) + ".md")).string();
  ASSERT_EQ(0, std::system((kTools + "/urban_detection_params >" + out).c_str()));
  auto slurp = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const std::string printed = slurp(out),
                    page = slurp(std::string(UD_SOURCE_DIR) + "/docs/parameters.md");
  fs::remove(out);
  EXPECT_NE(printed.find("`hough/votes`"), std::string::npos);
  EXPECT_NE(printed.find("`far_merge/max_gap_m`"), std::string::npos);
  EXPECT_EQ(page, printed) << "regenerate: urban_detection_params > docs/parameters.md";
}

TEST_F(ToolsTest, BenchWritesStagesPipelineAndNoSpeedupWithoutKdTree) {
  pt::ptree b;
  ASSERT_NO_FATAL_FAILURE(bench("bench", "--repeat 1 --no-kdtree", &b));
  EXPECT_GE(b.get<int>("revolutions"), 1);
  EXPECT_EQ("true", b.get<std::string>("pipeline_includes_packet_decode"));
  for (const char* s : {"packet_decode", "segmentation", "hough_refinement",
                        "foreground_extraction", "hierarchical_detection", "markers"}) {
    expectStage(b, s);
  }
  EXPECT_FALSE(b.get_child_optional("stages.kdtree_detection"));
  EXPECT_GT(b.get<double>("pipeline_median_ms"), 0.0);
  EXPECT_GT(b.get<double>("pipeline_fps"), 0.0);
  EXPECT_GT(b.get<double>("mean_objects_hierarchical"), 0.0);
  EXPECT_EQ("null", b.get<std::string>("hier_vs_kdtree_speedup"));
  EXPECT_EQ("null", b.get<std::string>("hier_vs_kdtree_pcl_default_speedup"));
  EXPECT_GT(b.get<double>("peak_rss_mb"), 0.0);
}

TEST_F(ToolsTest, BenchMeasuresTheKdTreeOnTheSameRevolutions) {
  pt::ptree b;
  ASSERT_NO_FATAL_FAILURE(bench("bench_kd", "--repeat 1 --max-frames 1", &b));
  EXPECT_EQ(1, b.get<int>("revolutions"));
  expectStage(b, "kdtree_detection");
  const double ratio = b.get<double>("stages.kdtree_detection.median_ms") /
                       b.get<double>("stages.hierarchical_detection.median_ms");
  EXPECT_NEAR(ratio, b.get<double>("hier_vs_kdtree_speedup"), 1e-3 * ratio);
  EXPECT_GT(b.get<double>("mean_objects_kdtree"), 0.0);
  // The shipped unsorted search, and beside it PCL's default sorted one on the same foregrounds.
  expectStage(b, "kdtree_detection_pcl_default");
  const double ratio_default = b.get<double>("stages.kdtree_detection_pcl_default.median_ms") /
                               b.get<double>("stages.hierarchical_detection.median_ms");
  EXPECT_NEAR(ratio_default, b.get<double>("hier_vs_kdtree_pcl_default_speedup"),
              1e-3 * ratio_default);
}

TEST_F(ToolsTest, BenchRejectsUnknownArgumentsAndMissingInput) {
  EXPECT_EQ(2, run(kTools + "/urban_detection_bench --frobnicate", dir_ + "/bad.log"));
  EXPECT_EQ(2, run(kTools + "/urban_detection_bench --pcap " + dir_ + "/missing.pcap",
                   dir_ + "/bad2.log"));
}

TEST_F(ToolsTest, EvalScoresBothDetectorsConsistentlyAndHierBeatsKdTree) {
  const std::string json = dir_ + "/eval.json";
  ASSERT_EQ(0, run(kTools + "/urban_detection_eval --sim " + dir_ + "/drive.gt --pcap " + dir_ +
                       "/drive.pcap --detector both" + configs() + " --json " + json,
                   dir_ + "/eval.log"));
  const pt::ptree e = readJson(json);
  EXPECT_GE(e.get<int>("frames_evaluated"), 1);
  const pt::ptree& overall = e.get_child("overall");
  for (const char* key : {"no", "mo", "fo", "precision", "recall", "f_rate"}) {
    EXPECT_TRUE(overall.get_child_optional(key)) << key;
  }
  double f[2];
  int k = 0;
  for (const char* detector : {"hierarchical_grid", "kdtree"}) {
    SCOPED_TRACE(detector);
    const pt::ptree& s = e.get_child(std::string("by_detector.") + detector);
    const double no = s.get<double>("no"), mo = s.get<double>("mo"), fo = s.get<double>("fo");
    const double tp = s.get<double>("tp");
    ASSERT_GT(no, 0.0);
    EXPECT_EQ(no - mo, tp);
    const double p = tp / (tp + fo), r = tp / no;
    EXPECT_NEAR(p, s.get<double>("precision"), 1e-5);
    EXPECT_NEAR(r, s.get<double>("recall"), 1e-5);
    EXPECT_NEAR(2 * p * r / (p + r), s.get<double>("f_rate"), 1e-5);
    f[k++] = s.get<double>("f_rate");
  }
  // The target "above the kd-tree baseline on every dataset", on the seeded drive.
  EXPECT_GT(f[0], f[1]);
  // The first detector's score is the overall one.
  EXPECT_DOUBLE_EQ(f[0], overall.get<double>("f_rate"));
  // Accuracy floor on the seeded drive (deterministic: same pcap, same objects every run), a
  // little under what the shipped configuration scores: a change that loses objects or adds
  // false ones fails here. Raise it when the detector gets better.
  const pt::ptree& hier = e.get_child("by_detector.hierarchical_grid");
  EXPECT_GE(hier.get<double>("f_rate"), 0.58);
  EXPECT_GE(hier.get<double>("precision"), 0.90);
  EXPECT_GE(hier.get<double>("recall"), 0.42);
}

// urban_detection_seg_eval --sim: the segmentation figures against the simulator's
// exact per-point classes. The seeded 4-revolution drive passes a facade close to the sensor,
// which is what the Hough refinement is for.
TEST_F(ToolsTest, SegEvalScoresTheSimulatedDriveAndShowsWhatHoughAdds) {
  const std::string sim = " --sim " + dir_ + "/drive.gt --pcap " + dir_ + "/drive.pcap";
  const std::string json = dir_ + "/seg_eval.json";
  ASSERT_EQ(0, run(kTools + "/urban_detection_seg_eval" + sim + " --json " + json,
                   dir_ + "/seg_eval.log"));
  const pt::ptree e = readJson(json);
  EXPECT_EQ("sim", e.get<std::string>("dataset"));
  EXPECT_GE(e.get<int>("frames"), 3);
  const pt::ptree& on = e.get_child("hough_on");
  const pt::ptree& off = e.get_child("hough_off");
  // Both runs score the same points.
  for (const char* k : {"ground_points", "wall_points", "car_points", "person_points"}) {
    EXPECT_GT(on.get<long>(k), 0) << k;
    EXPECT_EQ(on.get<long>(k), off.get<long>(k)) << k;
  }
  const double p = on.get<double>("ground_precision"), r = on.get<double>("ground_recall");
  EXPECT_NEAR(2 * p * r / (p + r), on.get<double>("ground_f1"), 1e-5);
  // The segmentation targets, on this drive (measured 0.995 / 1.000 / 0.998 / 0.977).
  EXPECT_GE(on.get<double>("ground_f1"), 0.95);
  EXPECT_GE(on.get<double>("wall_not_foreground"), 0.95);
  EXPECT_GE(on.get<double>("car_foreground"), 0.95);
  EXPECT_GE(on.get<double>("person_foreground"), 0.95);
  // Without the refinement, a quarter of the facade is foreground (measured 0.755).
  EXPECT_LT(off.get<double>("wall_not_foreground"), on.get<double>("wall_not_foreground") - 0.1);

  // The figures follow the segmentation: with every cell clutter nothing is ground or
  // foreground.
  const std::string json2 = dir_ + "/seg_eval_clutter.json";
  ASSERT_EQ(0, run(kTools + "/urban_detection_seg_eval" + sim +
                       " --set min_points_per_cell=100000 --json " + json2,
                   dir_ + "/seg_eval_clutter.log"));
  const pt::ptree c = readJson(json2).get_child("hough_on");
  EXPECT_EQ(0.0, c.get<double>("ground_recall"));
  EXPECT_EQ(0.0, c.get<double>("car_foreground"));
  EXPECT_EQ(1.0, c.get<double>("wall_not_foreground"));
}

TEST_F(ToolsTest, SegEvalRejectsBadArgumentsAndMissingFiles) {
  const std::string tool = kTools + "/urban_detection_seg_eval";
  EXPECT_EQ(2, run(tool + " --sim " + dir_ + "/drive.gt", dir_ + "/se_bad1.log"));
  EXPECT_EQ(2, run(tool + " --frobnicate", dir_ + "/se_bad2.log"));
  EXPECT_EQ(2,
            run(tool + " --sim " + dir_ + "/drive.gt --pcap " + dir_ + "/drive.pcap --max-frames 0",
                dir_ + "/se_bad3.log"));
  EXPECT_EQ(1, run(tool + " --sim " + dir_ + "/missing.gt --pcap " + dir_ + "/drive.pcap",
                   dir_ + "/se_bad4.log"));
}

}  // namespace

// Tracking: eval --tracking writes the CLEAR-MOT keys, with counts that add up; the
// tracker on the ground-truth boxes does at least as well as on the detections; the bench times
// the tracker at 100 objects; a bad tracker config is refused with its reason.
TEST_F(ToolsTest, EvalTrackingWritesClearMotAndBenchTimesTheTracker) {
  const std::string path = dir_ + "/tracking.json";
  ASSERT_EQ(0, run(kTools + "/urban_detection_eval --tracking --sim " + dir_ + "/drive.gt --pcap " +
                       dir_ + "/drive.pcap" + configs() + " --tracker-config " + kConfig +
                       "object_tracker.yaml --json " + path,
                   dir_ + "/tracking.log"))
      << "see " << dir_ << "/tracking.log";
  const pt::ptree j = readJson(path);
  EXPECT_EQ(j.get<std::string>("dataset"), "sim");
  for (const char* who : {"tracker", "detector_alone", "tracker_on_ground_truth_boxes"}) {
    const pt::ptree& r = j.get_child(who);
    const double gt = r.get<double>("gt");
    EXPECT_GT(gt, 0.0) << who;
    EXPECT_EQ(r.get<double>("matches") + r.get<double>("misses"), gt) << who;
    const double mota = 1.0 - (r.get<double>("misses") + r.get<double>("false_positives") +
                               r.get<double>("id_switches")) /
                                  gt;
    EXPECT_NEAR(r.get<double>("mota"), mota, 1e-4) << who;
    EXPECT_LE(r.get<double>("mota"), r.get<double>("recall") + 1e-9) << who;
  }
  EXPECT_GE(j.get<double>("tracker_on_ground_truth_boxes.mota"), j.get<double>("tracker.mota"));

  pt::ptree b;
  bench("bench_tracker", "--no-kdtree", &b);
  EXPECT_GT(b.get<double>("stages.tracker_100_objects.median_ms"), 0.0);

  const std::string bad = dir_ + "/bad_tracker.yaml";
  { std::ofstream(bad) << "tracker:\n  birth_hits: 0\n"; }
  EXPECT_EQ(2, run(kTools + "/urban_detection_eval --tracking --sim " + dir_ + "/drive.gt --pcap " +
                       dir_ + "/drive.pcap --tracker-config " + bad,
                   dir_ + "/bad_tracker.log"));
  std::ifstream log(dir_ + "/bad_tracker.log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("birth_hits"), std::string::npos) << text;
}

// The documented `urban_detection_eval --tracking --kitti-tracking DIR` on a KITTI tracking
// layout written here: a flat road, a car driving away along x and a parked van beside the road
// (both labelled: Car and Van are scored as vehicles), a labelled pedestrian with no points
// (ignored) and a DontCare row. Classifier off (synthetic shapes): every confirmed track is a
// hypothesis.
TEST_F(ToolsTest, EvalKittiTrackingRunsOnAWrittenSequence) {
  const std::string root = dir_ + "/kitti_tracking";
  fs::create_directories(root + "/velodyne/0000");
  fs::create_directories(root + "/label_02");
  fs::create_directories(root + "/calib");
  {
    std::ofstream calib(root + "/calib/0000.txt");
    calib << "P2: 721.5 0 609.6 44.9 0 721.5 172.9 0.2 0 0 1 0.003\n"
             "R_rect 1 0 0 0 1 0 0 0 1\n"
             "Tr_velo_cam 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
  }
  const double sensor_h = 1.73;
  // Points on the faces of an upright box (velodyne frame, x forward, y left, z up).
  auto box = [](std::vector<float>* out, double cx, double cy, double l, double w, double h,
                double z0) {
    const double step = 0.06;
    auto add = [out](double x, double y, double z) {
      out->insert(out->end(),
                  {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), 0.3f});
    };
    for (double z = z0 + 0.1; z <= z0 + h; z += step) {
      for (double a = -0.5 * l; a <= 0.5 * l; a += step) {
        add(cx + a, cy - 0.5 * w, z);
        add(cx + a, cy + 0.5 * w, z);
      }
      for (double b = -0.5 * w; b <= 0.5 * w; b += step) {
        add(cx - 0.5 * l, cy + b, z);
        add(cx + 0.5 * l, cy + b, z);
      }
    }
  };
  std::ofstream labels(root + "/label_02/0000.txt");
  const int frames = 8;
  for (int f = 0; f < frames; ++f) {
    std::vector<float> pts;
    for (double x = -30.0; x <= 40.0; x += 0.25) {
      for (double y = -20.0; y <= 20.0; y += 0.25) {
        pts.insert(pts.end(), {static_cast<float>(x), static_cast<float>(y),
                               static_cast<float>(-sensor_h), 0.2f});
      }
    }
    const double car_x = 12.0 + 0.5 * f, car_y = 0.0, van_x = 18.0, van_y = -5.0;
    box(&pts, car_x, car_y, 4.0, 1.7, 1.5, -sensor_h);
    box(&pts, van_x, van_y, 5.0, 2.0, 2.0, -sensor_h);
    char name[64];
    std::snprintf(name, sizeof(name), "/velodyne/0000/%06d.bin", f);
    std::ofstream bin(root + name, std::ios::binary);
    bin.write(reinterpret_cast<const char*>(pts.data()),
              static_cast<std::streamsize>(pts.size() * sizeof(float)));
    // Label: frame id type trunc occl alpha bbox(4) h w l x y z (camera: x = -y_velo,
    // y = -z_velo (bottom), z = x_velo) rotation_y (-pi/2: along the LiDAR's x).
    labels << f << " 0 Car 0 0 0 500 150 700 250 1.5 1.7 4.0 " << -car_y << " " << sensor_h << " "
           << car_x << " -1.5708\n";
    labels << f << " 1 Van 0 0 0 800 150 900 250 2.0 2.0 5.0 " << -van_y << " " << sensor_h << " "
           << van_x << " -1.5708\n";
    labels << f << " 2 Pedestrian 0 0 0 300 150 320 250 1.7 0.6 0.8 3.0 " << sensor_h
           << " 30.0 -1.5708\n";
    labels << f << " -1 DontCare -1 -1 -10 0 0 100 100 -1000 -1000 -1000 -10 -1 -1 -10\n";
  }
  labels.close();
  const std::string path = dir_ + "/kitti_tracking.json";
  ASSERT_EQ(0, run(kTools + "/urban_detection_eval --tracking --kitti-tracking " + root +
                       configs() + " --classifier off --json " + path,
                   dir_ + "/kitti_tracking.log"))
      << "see " << dir_ << "/kitti_tracking.log";
  const pt::ptree j = readJson(path);
  EXPECT_EQ(j.get<std::string>("dataset"), "kitti_tracking");
  const pt::ptree& r = j.get_child("tracker");
  EXPECT_EQ(r.get<int>("frames"), frames);
  EXPECT_EQ(r.get<int>("gt_tracks"), 2);  // the car and the van; the empty pedestrian ignored
  EXPECT_EQ(r.get<int>("gt"), 2 * frames);
  EXPECT_EQ(r.get<int>("id_switches"), 0);
  // A track is confirmed on its third detection: at most two misses per object.
  EXPECT_GE(r.get<int>("matches"), 2 * (frames - 2));
  EXPECT_GE(r.get<double>("mota"), 0.7);
  // --kitti-tracking implies the tracking evaluation: the form without --tracking runs too.
  EXPECT_EQ(0, run(kTools + "/urban_detection_eval --kitti-tracking " + root + configs() +
                       " --classifier off --max-frames 2",
                   dir_ + "/kitti_tracking_short.log"));
}

// The shared data (UD_SHARED_DATA or ../shared/data beside the source), "" when absent.
std::string sharedData() {
  const char* env = std::getenv("UD_SHARED_DATA");
  const fs::path root = env ? fs::path(env) : fs::path(UD_SOURCE_DIR) / ".." / "shared" / "data";
  return fs::is_directory(root) ? fs::canonical(root).string() : std::string();
}

// urban_detection_spark's report on KITTI object frames with the box oracle (each labelled
// object's camera class is its own KITTI type): every scored object gets its class, and the
// precision table adds up (fusion can only keep fewer detections than the LiDAR alone).
TEST_F(ToolsTest, SparkKittiReportWithTheBoxOracleIsRightOnEveryObject) {
  const std::string data = sharedData();
  if (data.empty() || !fs::is_directory(data + "/kitti_object/velodyne")) {
    GTEST_SKIP() << "shared data not found (KITTI object frames): UD_SHARED_DATA";
  }
  const std::string path = dir_ + "/spark_kitti.json";
  ASSERT_EQ(0, run(kTools + "/urban_detection_spark kitti --kitti " + data +
                       "/kitti_object --box-oracle --config-dir " + kConfig + " --json " + path,
                   dir_ + "/spark_kitti.log"))
      << "see " << dir_ << "/spark_kitti.log";
  const pt::ptree j = readJson(path);
  EXPECT_EQ(j.get<int>("frames"), 6);
  int scored = 0;
  for (const auto& c : j.get_child("by_category")) {
    EXPECT_EQ(c.second.get<int>("correct"), c.second.get<int>("n"))
        << c.second.get<std::string>("category") << " " << c.second.get<std::string>("range");
    scored += c.second.get<std::string>("range") == "all" ? c.second.get<int>("n") : 0;
  }
  EXPECT_GE(scored, 7);  // the 7 vehicles and people in view, at least
  const int lidar_kept = j.get<int>("precision.lidar.kept");
  EXPECT_GT(lidar_kept, 0);
  for (const char* fused : {"fused_veto", "fused_relabel"}) {
    const pt::ptree& p = j.get_child(std::string("precision.") + fused);
    EXPECT_EQ(p.get<int>("kept") + p.get<int>("vetoed"), lidar_kept) << fused;
    EXPECT_LE(p.get<int>("true"), p.get<int>("kept")) << fused;
    EXPECT_NEAR(p.get<double>("precision"),
                p.get<int>("kept") ? double(p.get<int>("true")) / p.get<int>("kept") : 0.0, 1e-5);
  }
}

// urban_detection_spark synthetic, then run --render-only on it: the synthetic street and its
// path give one rendered image and one JSON record per view.
TEST_F(ToolsTest, SparkRendersTheSyntheticStreetAlongItsPath) {
  const std::string syn = dir_ + "/spark_syn", out = dir_ + "/spark_run";
  ASSERT_EQ(0,
            run(kTools + "/urban_detection_spark synthetic --out " + syn, dir_ + "/spark_syn.log"));
  ASSERT_TRUE(fs::exists(syn + "/scene.pcd"));
  ASSERT_EQ(0, run(kTools + "/urban_detection_spark run --cloud " + syn + "/scene.pcd --path " +
                       syn + "/path.json --render-only --out " + out,
                   dir_ + "/spark_run.log"))
      << "see " << dir_ << "/spark_run.log";
  const pt::ptree path = readJson(syn + "/path.json");
  std::size_t pngs = 0, records = 0;
  for (const auto& e : fs::directory_iterator(out + "/images")) {
    pngs += e.path().extension() == ".png";
    records += e.path().extension() == ".json";
  }
  EXPECT_GT(pngs, 0u);
  EXPECT_EQ(pngs, records);
  const pt::ptree first = readJson(out + "/images/img_00000.json");
  EXPECT_GT(first.get<int>("width_px"), 0);
  EXPECT_GT(first.get<double>("metres_per_pixel"), 0.0);
  EXPECT_NE(run(kTools + "/urban_detection_spark run --cloud " + syn + "/missing.pcd --path " +
                    syn + "/path.json --render-only --out " + out,
                dir_ + "/spark_missing.log"),
            0);
}

// urban_detection_train_classifier's leave-one-sequence-out protocol on three sequences of
// three SemanticKITTI scans each (links to the shared files): one fold per sequence, each
// held-out sequence scored with the classifier off and on (the classifier only removes
// detections: no more found objects, no more false ones), and the written model is one the
// eval loads and that names its training sequences.
TEST_F(ToolsTest, TrainClassifierFoldsLeaveEachSequenceOutAndWritesALoadableModel) {
  const std::string data = sharedData();
  const std::string sk = data + "/semantic_kitti/sequences";
  if (data.empty() || !fs::is_directory(sk + "/00/velodyne")) {
    GTEST_SKIP() << "shared data not found (SemanticKITTI): UD_SHARED_DATA";
  }
  const std::string root = dir_ + "/sk3";
  const std::vector<std::string> sequences = {"00", "01", "04"};
  for (const std::string& q : sequences) {
    for (const char* sub : {"velodyne", "labels"}) {
      fs::create_directories(root + "/sequences/" + q + "/" + sub);
    }
    for (const char* scan : {"000000", "000001", "000002"}) {
      fs::create_symlink(sk + "/" + q + "/velodyne/" + scan + ".bin",
                         root + "/sequences/" + q + "/velodyne/" + scan + ".bin");
      fs::create_symlink(sk + "/" + q + "/labels/" + scan + ".label",
                         root + "/sequences/" + q + "/labels/" + scan + ".label");
    }
  }
  const std::string model = dir_ + "/sk3_model.yml.gz", json = dir_ + "/sk3_train.json";
  ASSERT_EQ(0,
            run(kTools + "/urban_detection_train_classifier --semantic-kitti " + root + configs() +
                    " --trees 10 --no-kdtree --augment 0,0 --out " + model + " --json " + json,
                dir_ + "/sk3_train.log"))
      << "see " << dir_ << "/sk3_train.log";
  const pt::ptree j = readJson(json);
  EXPECT_EQ(j.get<int>("scans"), 9);
  const pt::ptree& folds = j.get_child("loso.hierarchical_grid.sequences");
  ASSERT_EQ(folds.size(), sequences.size());
  for (const std::string& q : sequences) {
    SCOPED_TRACE(q);
    const pt::ptree& f = folds.get_child(q);
    EXPECT_GT(f.get<int>("off.no"), 0);
    EXPECT_LE(f.get<int>("on.fo"), f.get<int>("off.fo"));
    EXPECT_LE(f.get<int>("on.no") - f.get<int>("on.mo"),
              f.get<int>("off.no") - f.get<int>("off.mo"));
  }
  ASSERT_TRUE(fs::exists(model));
  const std::string eval_log = dir_ + "/sk3_eval.log";
  ASSERT_EQ(0, run(kTools + "/urban_detection_eval --semantic-kitti " + root + "/sequences/04" +
                       configs() + " --classifier " + model,
                   eval_log))
      << "see " << eval_log;
  std::ifstream in(eval_log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("trained on"), std::string::npos) << text.substr(0, 2000);
}
