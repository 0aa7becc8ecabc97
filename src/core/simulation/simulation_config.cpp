#include "urban_detection/core/simulation/simulation_config.h"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace urban_detection {
namespace core {

namespace {

// Reads the keys of one YAML map into fields, rejecting unknown keys.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string where, const std::string& source)
      : node_(node), where_(std::move(where)), source_(source) {
    present_ = node_.IsDefined() && !node_.IsNull();
    if (present_ && !node_.IsMap()) fail("", "must be a map");
  }
  template <typename T>
  MapReader& get(const char* key, T* value) {
    seen_.insert(key);
    if (!present_ || !node_[key] || node_[key].IsNull()) return *this;
    try {
      *value = node_[key].as<T>();
    } catch (const YAML::Exception&) {
      fail(key, "has the wrong type");
    }
    return *this;
  }
  YAML::Node child(const char* key) {
    seen_.insert(key);
    if (!present_ || !node_[key] || node_[key].IsNull()) return YAML::Node();
    return node_[key];
  }
  void done() const {
    if (!present_) return;
    for (const auto& kv : node_) {
      const std::string k = kv.first.as<std::string>();
      if (!seen_.count(k)) fail(k, "is not a known key");
    }
  }
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::invalid_argument(source_ + ": " + where_ + (key.empty() ? "" : "." + key) + " " +
                                what);
  }

 private:
  YAML::Node node_;
  std::string where_;
  const std::string& source_;
  std::set<std::string> seen_;
  bool present_ = false;
};

SimulationConfig parse(const YAML::Node& root, const std::string& source) {
  SimulationConfig c;
  MapReader top(root, "", source);
  top.get("seed", &c.scene.seed);

  MapReader sc(top.child("scene"), "scene", source);
  sc.get("start_x_m", &c.scene.start_x_m)
      .get("slope", &c.scene.slope)
      .get("camber", &c.scene.camber)
      .get("curb_height_m", &c.scene.curb_height_m)
      .get("terrain_width_m", &c.scene.terrain_width_m);
  const YAML::Node sections = sc.child("sections");
  if (!sections.IsNull()) {
    if (!sections.IsSequence()) sc.fail("sections", "must be a list");
    c.scene.sections.clear();
    for (std::size_t i = 0; i < sections.size(); ++i) {
      StreetSection s;
      std::string type = "street";
      MapReader r(sections[i], "scene.sections[" + std::to_string(i) + "]", source);
      r.get("type", &type)
          .get("length_m", &s.length_m)
          .get("road_half_width_m", &s.road_half_width_m)
          .get("sidewalk_width_m", &s.sidewalk_width_m)
          .get("buildings_left", &s.buildings_left)
          .get("buildings_right", &s.buildings_right)
          .get("parking", &s.parking)
          .get("furniture", &s.furniture);
      r.done();
      if (type == "street") {
        s.type = StreetSection::Type::kStreet;
      } else if (type == "intersection") {
        s.type = StreetSection::Type::kIntersection;
      } else {
        r.fail("type", "must be 'street' or 'intersection'");
      }
      c.scene.sections.push_back(s);
    }
  }
  BuildingParams& b = c.scene.buildings;
  MapReader br(sc.child("buildings"), "scene.buildings", source);
  br.get("depth_m", &b.depth_m)
      .get("height_min_m", &b.height_min_m)
      .get("height_max_m", &b.height_max_m)
      .get("length_min_m", &b.length_min_m)
      .get("length_max_m", &b.length_max_m)
      .get("gap_probability", &b.gap_probability)
      .get("gap_min_m", &b.gap_min_m)
      .get("gap_max_m", &b.gap_max_m)
      .get("recess_probability", &b.recess_probability)
      .get("recess_max_m", &b.recess_max_m);
  br.done();
  StreetObjectParams& o = c.scene.objects;
  MapReader orr(sc.child("objects"), "scene.objects", source);
  orr.get("parked_gap_min_m", &o.parked_gap_min_m)
      .get("parked_gap_max_m", &o.parked_gap_max_m)
      .get("parked_skip_probability", &o.parked_skip_probability)
      .get("van_fraction", &o.van_fraction)
      .get("moving_cars", &o.moving_cars)
      .get("moving_car_speed_mps", &o.moving_car_speed_mps)
      .get("lane_offset_m", &o.lane_offset_m)
      .get("pedestrians", &o.pedestrians)
      .get("group_probability", &o.group_probability)
      .get("standing_probability", &o.standing_probability)
      .get("cyclists", &o.cyclists)
      .get("tree_spacing_m", &o.tree_spacing_m)
      .get("pole_spacing_m", &o.pole_spacing_m)
      .get("signs", &o.signs)
      .get("bins", &o.bins)
      .get("benches", &o.benches)
      .get("hard_cases", &o.hard_cases);
  orr.done();
  VegetationParams& v = c.scene.vegetation;
  MapReader vr(sc.child("vegetation"), "scene.vegetation", source);
  vr.get("enabled", &v.enabled)
      .get("verge_probability", &v.verge_probability)
      .get("verge_offset_m", &v.verge_offset_m)
      .get("verge_width_m", &v.verge_width_m)
      .get("verge_step_max_m", &v.verge_step_max_m)
      .get("verge_bush_spacing_m", &v.verge_bush_spacing_m)
      .get("terrain_tile_m", &v.terrain_tile_m)
      .get("terrain_roughness_m", &v.terrain_roughness_m)
      .get("terrain_tilt_deg", &v.terrain_tilt_deg)
      .get("garden_depth_m", &v.garden_depth_m)
      .get("garden_step_max_m", &v.garden_step_max_m)
      .get("hedge_probability", &v.hedge_probability)
      .get("hedge_height_min_m", &v.hedge_height_min_m)
      .get("hedge_height_max_m", &v.hedge_height_max_m)
      .get("hedge_width_min_m", &v.hedge_width_min_m)
      .get("hedge_width_max_m", &v.hedge_width_max_m)
      .get("hedge_gap_spacing_m", &v.hedge_gap_spacing_m)
      .get("bush_spacing_m", &v.bush_spacing_m)
      .get("facade_shrub_spacing_m", &v.facade_shrub_spacing_m)
      .get("bush_height_min_m", &v.bush_height_min_m)
      .get("bush_height_max_m", &v.bush_height_max_m)
      .get("garden_tree_spacing_m", &v.garden_tree_spacing_m)
      .get("canopy_lobes_min", &v.canopy_lobes_min)
      .get("canopy_lobes_max", &v.canopy_lobes_max)
      .get("canopy_overhang_max_m", &v.canopy_overhang_max_m)
      .get("canopy_clearance_min_m", &v.canopy_clearance_min_m)
      .get("canopy_clearance_max_m", &v.canopy_clearance_max_m)
      .get("hedge_transmission", &v.hedge_transmission)
      .get("hedge_penetration_m", &v.hedge_penetration_m)
      .get("bush_transmission", &v.bush_transmission)
      .get("bush_penetration_m", &v.bush_penetration_m)
      .get("crown_transmission", &v.crown_transmission)
      .get("crown_penetration_m", &v.crown_penetration_m);
  vr.done();
  sc.done();

  MapReader dr(top.child("drive"), "drive", source);
  dr.get("speed_mps", &c.drive.speed_mps);
  const YAML::Node wp = dr.child("waypoints");
  if (!wp.IsNull()) {
    if (!wp.IsSequence()) dr.fail("waypoints", "must be a list of [x, y]");
    c.drive.waypoints.clear();
    for (const auto& p : wp) {
      if (!p.IsSequence() || p.size() != 2) dr.fail("waypoints", "entries must be [x, y]");
      try {
        c.drive.waypoints.emplace_back(p[0].as<double>(), p[1].as<double>());
      } catch (const YAML::Exception&) {
        dr.fail("waypoints", "entries must be numbers");
      }
    }
  }
  dr.done();

  MapReader sr(top.child("sensor"), "sensor", source);
  SimSensorParams& s = c.sensor;
  sr.get("rpm", &s.rpm)
      .get("height_m", &s.height_m)
      .get("range_noise_m", &s.range_noise_m)
      .get("dropout_probability", &s.dropout_probability)
      .get("min_range_m", &s.min_range_m)
      .get("max_range_m", &s.max_range_m)
      .get("start_stamp_s", &s.start_stamp_s)
      .get("cut_angle_deg", &s.cut_angle_deg)
      .get("noise_seed", &s.noise_seed)
      .get("calibration", &c.calibration_file);
  sr.done();
  top.done();

  try {
    validate(c.scene);
    validate(c.drive);
    validate(c.sensor);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return c;
}

}  // namespace

SimulationConfig parseSimulationConfig(const std::string& yaml_text,
                                       const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(source_name + ": YAML syntax error: " + e.what());
  }
  if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  return parse(root, source_name);
}

SimulationConfig loadSimulationConfig(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open simulation config");
  std::stringstream ss;
  ss << in.rdbuf();
  SimulationConfig c = parseSimulationConfig(ss.str(), path);
  if (!c.calibration_file.empty() && c.calibration_file.front() != '/') {
    const std::size_t slash = path.find_last_of('/');
    if (slash != std::string::npos)
      c.calibration_file = path.substr(0, slash + 1) + c.calibration_file;
  }
  return c;
}

}  // namespace core
}  // namespace urban_detection
