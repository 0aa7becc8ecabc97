// The dynamic_reconfigure .cfg files against the field tables (core/common/param_fields.h): every
// .cfg entry names a field of its struct, the .cfg defaults are the struct's, and a Config filled
// from a struct gives the struct back. A renamed field or a .cfg typo fails here instead of a
// reconfigure entry silently doing nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "urban_detection/GridSegmentationConfig.h"
#include "urban_detection/HierarchicalGridDetectorConfig.h"
#include "urban_detection/KdTreeDetectorConfig.h"
#include "urban_detection/ObjectClassifierConfig.h"
#include "urban_detection/ObjectMarkersConfig.h"
#include "urban_detection/ObjectTrackerConfig.h"
#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/tracking/tracker.h"
#include "urban_detection/ros/object_markers.h"
#include "urban_detection/ros/object_tracking.h"
#include "urban_detection/ros/packet_params.h"
#include "urban_detection/ros/tunable_fields.h"

namespace urban_detection {
namespace {

template <class Config, class Params>
struct Pair {
  using ConfigType = Config;
  using ParamsType = Params;
};

template <class T>
class ConfigFields : public ::testing::Test {};

using Pairs = ::testing::Types<
    Pair<urban_detection::GridSegmentationConfig, core::GridSegmenterParams>,
    Pair<urban_detection::HierarchicalGridDetectorConfig, core::HierarchicalGridDetectorParams>,
    Pair<urban_detection::KdTreeDetectorConfig, core::KdTreeDetectorParams>,
    Pair<urban_detection::ObjectClassifierConfig, core::ObjectClassifierParams>,
    Pair<urban_detection::ObjectMarkersConfig, ros_conv::ObjectMarkerParams>,
    Pair<urban_detection::ObjectTrackerConfig, core::TrackerParams>>;
TYPED_TEST_SUITE(ConfigFields, Pairs);

// Every entry of a Config message, by name, as text (bools, ints, doubles and strings).
std::vector<std::pair<std::string, std::string>> entries(const dynamic_reconfigure::Config& m) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& e : m.bools) out.emplace_back(e.name, e.value ? "true" : "false");
  for (const auto& e : m.ints) out.emplace_back(e.name, std::to_string(e.value));
  for (const auto& e : m.doubles) out.emplace_back(e.name, std::to_string(e.value));
  for (const auto& e : m.strs) out.emplace_back(e.name, e.value);
  return out;
}

TYPED_TEST(ConfigFields, EveryCfgEntryNamesATableField) {
  using Config = typename TypeParam::ConfigType;
  using Params = typename TypeParam::ParamsType;
  const auto unmatched = ros_conv::unmatchedConfigEntries<Config, Params>();
  EXPECT_TRUE(unmatched.empty()) << "first .cfg entry naming no field: " << unmatched.front();
}

TYPED_TEST(ConfigFields, CfgDefaultsAreTheStructDefaults) {
  using Config = typename TypeParam::ConfigType;
  using Params = typename TypeParam::ParamsType;
  dynamic_reconfigure::Config from_struct, cfg_default;
  ros_conv::toConfig<Config>(Params{}).__toMessage__(from_struct);
  Config::__getDefault__().__toMessage__(cfg_default);
  EXPECT_EQ(entries(from_struct), entries(cfg_default));
}

TYPED_TEST(ConfigFields, RoundTripThroughAConfigKeepsEveryListedField) {
  using Config = typename TypeParam::ConfigType;
  using Params = typename TypeParam::ParamsType;
  // Change every field the .cfg lists, go through the Config, and compare field by field.
  Params changed{};
  std::vector<std::string> listed;
  dynamic_reconfigure::Config msg;
  Config::__getDefault__().__toMessage__(msg);
  for (const auto& e : entries(msg)) listed.push_back(e.first);
  int touched = 0;
  core::forEachField(changed, [&](const core::FieldInfo& info, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if (std::find(listed.begin(), listed.end(), ros_conv::configName(info.name)) == listed.end()) {
      return;
    }
    if constexpr (std::is_same_v<T, bool>) {
      field = !field;
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double>) {
      field = static_cast<T>(info.max > 1e6 ? field + 1 : (field + info.max) / 2);
    }
    ++touched;
  });
  EXPECT_EQ(touched, static_cast<int>(listed.size()));
  const Params back = ros_conv::fromConfig(ros_conv::toConfig<Config>(changed), Params{});
  core::forEachField(changed, [&](const core::FieldInfo& info, const auto& field) {
    core::forEachField(back, [&](const core::FieldInfo& other, const auto& value) {
      if constexpr (std::is_same_v<std::decay_t<decltype(field)>, std::decay_t<decltype(value)>>) {
        if (other.name == info.name) {
          EXPECT_EQ(value, field) << info.name;
        }
      }
    });
  });
}

// The keys of map `section` in config/`file`, in order, against the table of Params: the ROS
// layer's YAML files bind exactly their tables (the core ones are covered by test_core's
// params_yaml tests).
template <class Params>
void expectYamlKeysAreTheTable(const std::string& file, const std::string& section) {
  YAML::Node node = YAML::LoadFile(std::string(UD_SOURCE_DIR) + "/config/" + file);
  if (section.empty()) {  // the whole file
    YAML::Node root;
    root["root"] = node;
    node = root;
  }
  const std::string key = section.empty() ? "root" : section;
  ASSERT_TRUE(node[key].IsMap()) << file << ": " << section;
  std::vector<std::string> table;
  const Params defaults;
  core::forEachField(defaults,
                     [&](const core::FieldInfo& info, const auto&) { table.push_back(info.name); });
  std::vector<std::string> keys;
  for (const auto& kv : node[key]) keys.push_back(kv.first.as<std::string>());
  EXPECT_EQ(keys, table) << file << ": " << section;
}

TEST(ConfigFiles, RosLayerYamlKeysAreTableFields) {
  expectYamlKeysAreTheTable<ros_conv::ObjectMarkerParams>("markers.yaml", "markers");
  expectYamlKeysAreTheTable<core::TrackerParams>("object_tracker.yaml", "tracker");
  expectYamlKeysAreTheTable<ros_conv::TrackMarkerParams>("object_tracker.yaml", "markers");
  expectYamlKeysAreTheTable<ros_conv::PacketSourceParams>("packet_source.yaml", "");
  expectYamlKeysAreTheTable<ros_conv::PacketToCloudParams>("packet_to_cloud.yaml", "");
}

// The packet nodelets' rules beyond the ranges, as validate() (and so loadFields) applies them.
TEST(PacketParams, FormatAndCrossFieldRules) {
  ros_conv::PacketSourceParams source;
  EXPECT_EQ(validate(source), "");
  source.device_ip = "192.168.3.300";
  EXPECT_NE(validate(source).find("'device_ip' = '192.168.3.300' is not an IPv4 address"),
            std::string::npos)
      << validate(source);
  source = ros_conv::PacketSourceParams();
  source.frame_id.clear();
  EXPECT_NE(validate(source).find("'frame_id' must not be empty"), std::string::npos);
  source = ros_conv::PacketSourceParams();
  source.rpm = 1500.0;
  EXPECT_EQ(validate(source),
            "parameter 'rpm' = 1500 is out of range: accepted [300, 1200] rev/min");
  ros_conv::PacketToCloudParams cloud;
  EXPECT_EQ(validate(cloud), "");
  cloud.decoder.min_range_m = 50.0;
  cloud.decoder.max_range_m = 40.0;  // each in range, together not
  EXPECT_NE(validate(cloud).find("accepted min_range < max_range"), std::string::npos)
      << validate(cloud);
  cloud = ros_conv::PacketToCloudParams();
  cloud.max_packets_per_scan = 0;
  EXPECT_NE(validate(cloud).find("'max_packets_per_scan' = 0 is out of range"), std::string::npos);
}

}  // namespace
}  // namespace urban_detection
