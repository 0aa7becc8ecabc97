// The field tables (core/common/param_fields.h): well formed, the source of validate()'s
// ranges and of the YAML reader's keys.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>

#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/simulation/simulation_config.h"
#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/camera_model.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {
namespace {

namespace fs = std::filesystem;

template <class Params>
class FieldTable : public ::testing::Test {};

using Structs =
    ::testing::Types<GridSegmenterParams, HoughWallRefinerParams, HierarchicalGridDetectorParams,
                     DistanceWeightParams, FarObjectMergerParams, KdTreeDetectorParams,
                     ObjectClassifierParams, TrackerParams, CameraFusionParams,
                     ImageLabelTransferParams, PipelineParams, ObjectFeatureParams,
                     ClassifierTrainingParams, SegmentationModelParams, CameraModelParams,
                     CameraStageParams, DecoderParams, SimulationConfig, StreetSection>;
TYPED_TEST_SUITE(FieldTable, Structs);

// Unique names, a description each, finite ordered ranges around the in-class default.
TYPED_TEST(FieldTable, IsWellFormedAndHoldsTheDefaults) {
  const TypeParam defaults;
  std::set<std::string> names;
  int fields = 0;
  forEachField(defaults, [&](const FieldInfo& info, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    ++fields;
    EXPECT_TRUE(names.insert(info.name).second) << "duplicate " << info.name;
    EXPECT_FALSE(info.description.empty()) << info.name;
    EXPECT_EQ(info.name.find(' '), std::string::npos) << info.name;
    if constexpr (kRangedField<T>) {
      EXPECT_TRUE(std::isfinite(info.min) && std::isfinite(info.max)) << info.name;
      EXPECT_LE(info.min, info.max) << info.name;
      EXPECT_GE(value, info.min) << info.name << ": default below its range";
      EXPECT_LE(value, info.max) << info.name << ": default above its range";
      if constexpr (std::is_integral_v<T>) {
        EXPECT_EQ(info.min, std::floor(info.min)) << info.name;
        EXPECT_EQ(info.max, std::floor(info.max)) << info.name;
      }
    } else if constexpr (kRangedArray<T>) {
      EXPECT_TRUE(std::isfinite(info.min) && std::isfinite(info.max)) << info.name;
      for (const double v : value) {
        EXPECT_TRUE(v >= info.min && v <= info.max) << info.name << ": default outside its range";
      }
    } else if constexpr (kPointList<T>) {
      EXPECT_TRUE(std::isfinite(info.min) && std::isfinite(info.max)) << info.name;
      for (const auto& point : value) {
        for (int k = 0; k < point.size(); ++k) {
          EXPECT_TRUE(point[k] >= info.min && point[k] <= info.max)
              << info.name << ": default outside its range";
        }
      }
    } else {
      EXPECT_TRUE(std::isinf(info.min) && std::isinf(info.max))
          << info.name << ": a range on a field that is not a number";
    }
    if constexpr (std::is_enum_v<T>) {
      EXPECT_FALSE(choiceName(info, value).empty()) << info.name << ": default has no name";
    } else {
      EXPECT_TRUE(info.choices.empty()) << info.name << ": choices on a field that is no enum";
    }
  });
  EXPECT_GT(fields, 0);
}

// Each number just outside its range is refused by validate() (so validate() checks every
// table range), naming the field; inside it is not refused for its range.
TYPED_TEST(FieldTable, ValidateRefusesEveryFieldOutsideItsRange) {
  const TypeParam defaults;
  int ranged = 0;
  forEachField(defaults, [&](const FieldInfo& info, const auto& default_value) {
    using T = std::decay_t<decltype(default_value)>;
    if constexpr (kRangedField<T>) {
      ++ranged;
      for (const double outside : {info.min - 1.0, info.max + 1.0}) {
        TypeParam p;
        forEachField(p, [&](const FieldInfo& i, auto& v) {
          using V = std::decay_t<decltype(v)>;
          if constexpr (kRangedField<V>) {
            if (i.name == info.name) v = static_cast<V>(outside);
          }
        });
        const std::string error = validate(p);
        EXPECT_NE(error.find("'" + info.name + "'"), std::string::npos)
            << info.name << " = " << outside << " gave: " << error;
        EXPECT_NE(error.find("out of range"), std::string::npos) << error;
      }
      if constexpr (std::is_floating_point_v<T>) {
        TypeParam p;
        forEachField(p, [&](const FieldInfo& i, auto& v) {
          using V = std::decay_t<decltype(v)>;
          if constexpr (std::is_floating_point_v<V>) {
            if (i.name == info.name) v = std::numeric_limits<V>::quiet_NaN();
          }
        });
        EXPECT_FALSE(validate(p).empty()) << info.name << " = NaN accepted";
      }
    }
  });
  // Each element of a fixed-size list, and an enum value without a name, likewise.
  forEachField(defaults, [&](const FieldInfo& info, const auto& default_value) {
    using T = std::decay_t<decltype(default_value)>;
    if constexpr (kRangedArray<T>) {
      ++ranged;
      for (std::size_t i = 0; i < default_value.size(); ++i) {
        TypeParam p;
        forEachField(p, [&](const FieldInfo& f, auto& v) {
          if constexpr (std::is_same_v<std::decay_t<decltype(v)>, T>) {
            if (f.name == info.name) v[i] = info.max + 1.0;
          }
        });
        const std::string error = validate(p);
        EXPECT_NE(error.find("'" + info.name + "[" + std::to_string(i) + "]'"), std::string::npos)
            << error;
      }
    } else if constexpr (std::is_enum_v<T>) {
      TypeParam p;
      forEachField(p, [&](const FieldInfo& f, auto& v) {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, T>) {
          if (f.name == info.name) v = static_cast<T>(info.choices.size());
        }
      });
      EXPECT_NE(validate(p).find("'" + info.name + "'"), std::string::npos) << validate(p);
    }
  });
  if (!std::is_same_v<TypeParam, DistanceWeightParams>) EXPECT_GT(ranged, 0);
}

TEST(FieldTables, NestedStructsAreNamedWithTheirPrefix) {
  std::set<std::string> names;
  const HierarchicalGridDetectorParams hier;
  forEachField(hier, [&](const FieldInfo& info, const auto&) { names.insert(info.name); });
  EXPECT_TRUE(names.count("psi_max_m"));
  EXPECT_TRUE(names.count("weight/coefficients"));
  EXPECT_TRUE(names.count("far_merge/max_gap_m"));
  names.clear();
  const GridSegmenterParams seg;
  forEachField(seg, [&](const FieldInfo& info, const auto&) { names.insert(info.name); });
  EXPECT_TRUE(names.count("hough/votes"));
  EXPECT_FALSE(names.count("votes"));
}

TEST(FieldTables, GridSegmenterRangesAreNamedInTheFilesWords) {
  GridSegmenterParams p;
  EXPECT_EQ(validate(p), "");
  p.cell_size_m = 0.0;
  EXPECT_EQ(validate(p), "parameter 'cell_size_m' = 0 is out of range: accepted [0.05, 5] m");
  p = GridSegmenterParams();
  p.hough.min_tall_fraction = 1.5;
  EXPECT_NE(validate(p).find("'hough/min_tall_fraction'"), std::string::npos);
}

TEST(FieldTables, CrossFieldRulesStayInValidate) {
  KdTreeDetectorParams kd;
  kd.min_cluster_size = 50;
  kd.max_cluster_size = 10;  // each in range, together not
  EXPECT_NE(validate(kd).find("max_cluster_size"), std::string::npos);
  HierarchicalGridDetectorParams h;
  h.far_merge.max_width_m = 6.0;  // wider than max_length_m (5)
  EXPECT_NE(validate(h).find("far_merge: parameter 'max_width_m'"), std::string::npos)
      << validate(h);
  h = HierarchicalGridDetectorParams();
  h.weight.coefficients.clear();
  EXPECT_NE(validate(h).find("weight: coefficients"), std::string::npos) << validate(h);
  h = HierarchicalGridDetectorParams();
  h.weight.full_density_distance_m = 90.0;  // beyond max_distance_m (80)
  EXPECT_NE(validate(h).find("full_density_distance_m"), std::string::npos) << validate(h);
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("ud_param_fields_" + name);
  std::ofstream(p.string()) << text;
  return p.string();
}

// The YAML reader binds the table's keys: every field, nested maps, and only those.
TEST(FieldTables, YamlReaderTakesEveryTableKeyAndRejectsOthers) {
  std::ostringstream yaml;
  yaml << "hierarchical_grid:\n";
  const HierarchicalGridDetectorParams defaults;
  std::string group;
  forEachField(defaults, [&](const FieldInfo& info, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    const std::size_t slash = info.name.find('/');
    const std::string g = slash == std::string::npos ? "" : info.name.substr(0, slash);
    const std::string key = info.name.substr(slash == std::string::npos ? 0 : slash + 1);
    if (g != group && !g.empty()) yaml << "  " << g << ":\n";
    group = g;
    yaml << (g.empty() ? "  " : "    ") << key << ": ";
    if constexpr (std::is_same_v<T, bool>) {
      yaml << (value ? "false" : "true") << "\n";  // every flag flipped
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      yaml << "[1.0, 0.5]\n";
    } else if constexpr (kRangedField<T>) {
      yaml << static_cast<T>(info.min) << "\n";  // every number at its lower bound
    }
  });
  const std::string f = writeTemp("all.yaml", yaml.str());
  HierarchicalGridDetectorParams p;
  std::string err;
  EXPECT_TRUE(loadHierarchicalGridParamsYaml(f, &p, &err)) << err << "\n" << yaml.str();
  forEachField(p, [&](const FieldInfo& info, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (kRangedField<T>) {
      EXPECT_EQ(value, static_cast<T>(info.min)) << info.name << " not read from the file";
    } else if constexpr (std::is_same_v<T, bool>) {
      bool d = false;
      forEachField(defaults, [&](const FieldInfo& i, const auto& v) {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, bool>) {
          if (i.name == info.name) d = v;
        }
      });
      EXPECT_NE(value, d) << info.name << " not read from the file";
    }
  });
  EXPECT_EQ(p.weight.coefficients, (std::vector<double>{1.0, 0.5}));
  fs::remove(f);

  const std::string stray =
      writeTemp("stray.yaml", "hierarchical_grid:\n  far_merge:\n    gap: 1\n");
  EXPECT_FALSE(loadHierarchicalGridParamsYaml(stray, &p, &err));
  EXPECT_NE(err.find("far_merge/gap: unknown parameter"), std::string::npos) << err;
  const std::string flat = writeTemp("flat.yaml", "hierarchical_grid:\n  weight: 3\n");
  EXPECT_FALSE(loadHierarchicalGridParamsYaml(flat, &p, &err));
  EXPECT_NE(err.find("expected a map"), std::string::npos) << err;
  const std::string range = writeTemp("range.yaml", "kdtree:\n  cluster_tolerance_m: 50\n");
  KdTreeDetectorParams kd;
  EXPECT_FALSE(loadKdTreeParamsYaml(range, &kd, &err));
  EXPECT_NE(err.find("'cluster_tolerance_m' = 50 is out of range"), std::string::npos) << err;
  fs::remove(stray);
  fs::remove(flat);
  fs::remove(range);
}

TEST(FieldTables, MarkdownRowsCarryDefaultRangeAndUnit) {
  const std::string md = fieldTableMarkdown(KdTreeDetectorParams());
  EXPECT_NE(md.find("| `cluster_tolerance_m` | 0.4 | [0.01, 10] | m | points closer"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| `sorted_search` | false | | | "), std::string::npos) << md;
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
