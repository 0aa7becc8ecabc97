// Offline loading of config/*.yaml into the core params structs.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>

#include "urban_detection/core/params/params_yaml.h"

namespace urban_detection {
namespace core {
namespace {

namespace fs = std::filesystem;

std::string writeTemp(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("ud_params_yaml_" + name);
  std::ofstream(p.string()) << text;
  return p.string();
}

TEST(ParamsYaml, OverridesOnlyGivenFields) {
  const std::string f = writeTemp("a.yaml", "cell_size_m: 0.7\nhough:\n  votes: 20\n");
  GridSegmenterParams p;
  std::string err;
  ASSERT_TRUE(loadGridSegmenterParamsYaml(f, "", &p, &err)) << err;
  EXPECT_DOUBLE_EQ(p.cell_size_m, 0.7);
  EXPECT_EQ(p.hough.votes, 20);
  const GridSegmenterParams d;
  EXPECT_DOUBLE_EQ(p.tall_min_height_m, d.tall_min_height_m);
  EXPECT_DOUBLE_EQ(p.hough.min_line_length_m, d.hough.min_line_length_m);
  fs::remove(f);
}

TEST(ParamsYaml, SectionOfACombinedFile) {
  const std::string f =
      writeTemp("b.yaml", "segmentation:\n  min_points_per_cell: 6\ndetection:\n  x: 1\n");
  GridSegmenterParams p;
  std::string err;
  ASSERT_TRUE(loadGridSegmenterParamsYaml(f, "segmentation", &p, &err)) << err;
  EXPECT_EQ(p.min_points_per_cell, 6);
  fs::remove(f);
}

TEST(ParamsYaml, RejectsTyposWrongTypesAndMissingFiles) {
  GridSegmenterParams p;
  std::string err;
  const std::string typo = writeTemp("c.yaml", "cell_size: 0.7\n");
  EXPECT_FALSE(loadGridSegmenterParamsYaml(typo, "", &p, &err));
  EXPECT_NE(err.find("cell_size: unknown parameter"), std::string::npos) << err;
  const std::string type = writeTemp("d.yaml", "hough:\n  votes: many\n");
  EXPECT_FALSE(loadGridSegmenterParamsYaml(type, "", &p, &err));
  EXPECT_NE(err.find("hough/votes"), std::string::npos) << err;
  EXPECT_FALSE(loadGridSegmenterParamsYaml("/nonexistent/x.yaml", "", &p, &err));
  const std::string list = writeTemp("e.yaml", "- 1\n- 2\n");
  EXPECT_FALSE(loadGridSegmenterParamsYaml(list, "", &p, &err));
  fs::remove(typo);
  fs::remove(type);
  fs::remove(list);
}

TEST(ParamsYaml, ShippedSegmentationConfigLoads) {
  const std::string f = std::string(UD_SOURCE_DIR) + "/config/segmentation.yaml";
  GridSegmenterParams p;
  std::string err;
  EXPECT_TRUE(loadGridSegmenterParamsYaml(f, "", &p, &err)) << err;
}

TEST(ParamsYaml, DetectionFileAndAutoDetection) {
  const std::string det = writeTemp(
      "f.yaml",
      "hierarchical_grid:\n  coarse_cell_m: 0.5\n  weight:\n    max_weight: 7.0\n"
      "  far_merge:\n    max_gap_m: 0.8\n"
      "kdtree:\n  cluster_tolerance_m: 0.3\n  sorted_search: true\nmarkers:\n  lifetime_s: 0.2\n");
  GridSegmenterParams seg;
  HierarchicalGridDetectorParams hier;
  KdTreeDetectorParams kd;
  std::string err;
  ASSERT_TRUE(loadPipelineParamsYaml(det, &seg, &hier, &kd, &err)) << err;
  EXPECT_DOUBLE_EQ(hier.coarse_cell_m, 0.5);
  EXPECT_DOUBLE_EQ(hier.weight.max_weight, 7.0);
  EXPECT_DOUBLE_EQ(hier.far_merge.max_gap_m, 0.8);
  EXPECT_DOUBLE_EQ(hier.far_merge.min_range_m, FarObjectMergerParams().min_range_m);
  EXPECT_DOUBLE_EQ(kd.cluster_tolerance_m, 0.3);
  EXPECT_TRUE(kd.sorted_search);
  EXPECT_DOUBLE_EQ(seg.cell_size_m, GridSegmenterParams().cell_size_m);  // untouched
  // A segmentation file goes to the segmenter only.
  const std::string s = writeTemp("g.yaml", "cell_size_m: 0.4\n");
  ASSERT_TRUE(loadPipelineParamsYaml(s, &seg, &hier, &kd, &err)) << err;
  EXPECT_DOUBLE_EQ(seg.cell_size_m, 0.4);
  EXPECT_DOUBLE_EQ(hier.coarse_cell_m, 0.5);
  // A combined file.
  const std::string c = writeTemp("h.yaml",
                                  "segmentation:\n  cell_size_m: 0.6\ndetection:\n  kdtree:\n"
                                  "    min_cluster_size: 9\n");
  ASSERT_TRUE(loadPipelineParamsYaml(c, &seg, &hier, &kd, &err)) << err;
  EXPECT_DOUBLE_EQ(seg.cell_size_m, 0.6);
  EXPECT_EQ(kd.min_cluster_size, 9);
  // Typos inside a detector map are errors.
  const std::string bad = writeTemp("i.yaml", "kdtree:\n  cluster_tolerance: 0.3\n");
  EXPECT_FALSE(loadPipelineParamsYaml(bad, &seg, &hier, &kd, &err));
  EXPECT_NE(err.find("kdtree/cluster_tolerance: unknown parameter"), std::string::npos) << err;
  for (const auto& f : {det, s, c, bad}) fs::remove(f);
}

TEST(ParamsYaml, ShippedDetectionConfigsLoad) {
  for (const char* stage : {"hierarchical_grid", "kdtree"}) {
    const std::string f = std::string(UD_SOURCE_DIR) + "/config/" + stage + ".yaml";
    HierarchicalGridDetectorParams hier;
    KdTreeDetectorParams kd;
    std::string err;
    EXPECT_TRUE(loadPipelineParamsYaml(f, nullptr, &hier, &kd, &err)) << f << ": " << err;
  }
}

// Each stage's file holds that stage's sections only: a nodelet loads its own file into its
// private namespace, and nothing without effect lands there.
TEST(ParamsYaml, EachStageFileHoldsOnlyItsOwnSections) {
  const std::map<std::string, std::set<std::string>> sections = {
      {"hierarchical_grid", {"hierarchical_grid"}},
      {"kdtree", {"kdtree"}},
      {"classification", {"box_fitting", "classifier"}},
      {"markers", {"markers"}},
  };
  for (const auto& kv : sections) {
    const YAML::Node y =
        YAML::LoadFile(std::string(UD_SOURCE_DIR) + "/config/" + kv.first + ".yaml");
    std::set<std::string> keys;
    for (const auto& entry : y) keys.insert(entry.first.as<std::string>());
    EXPECT_EQ(keys, kv.second) << kv.first;
  }
  EXPECT_FALSE(fs::exists(std::string(UD_SOURCE_DIR) + "/config/detection.yaml"));
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
