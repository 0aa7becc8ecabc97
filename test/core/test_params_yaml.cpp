// Offline loading of config/*.yaml into the core params structs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "urban_detection/core/params_yaml.h"

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

}  // namespace
}  // namespace core
}  // namespace urban_detection
