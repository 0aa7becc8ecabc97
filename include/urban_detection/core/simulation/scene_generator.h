/// \file scene_generator.h
/// Procedural, seeded generator of an urban street scene for the simulated HDL-64E drive
/// (ROS-free). The same parameters (and seed) always give the same scene.
///
/// The street runs along +x from `start_x_m`, as a sequence of sections (street or
/// intersection). World frame: x along the street, y to the left, z up; the road crown at x = 0
/// is at z = 0 and the road rises by `slope` per metre along x and falls by `camber` per metre
/// from the crown (y = 0) to the curbs. Street objects include on purpose the hard cases of the
/// paper's Fig. 4 / Fig. 7 (objects closer than one 0.6 m coarse cell, a pedestrian beside a car,
/// objects touching a wall, a narrow street whose facade is within 3 m of the sensor).
///
/// Vegetation (VegetationParams) makes the scene as hard as a real street, where most false
/// objects are hedges, bushes, grass and terrain steps: grass verges along the curb,
/// front gardens wherever the facade line has no building front (gaps, setbacks, open sides)
/// with a terrain step at the sidewalk's back edge, trimmed hedges and irregular bushes, shrubs
/// against the facades that stand on the sidewalk, and tree
/// crowns with low lobes overhanging parked cars and the walkway. Foliage is porous (sim_scene.h).
/// Vegetation is drawn from its own random stream (derived from `seed`), so switching it off or
/// changing its parameters leaves every other object of the scene where it was.
///
/// Materials (Primitive::reflectivity, mean and per-return spread, at 905 nm; the simulated
/// intensity is reflectivity x 255, the scale of KITTI's reflectance x 255):
/// - vehicles mix materials: body paint (one colour per vehicle, dark to light), window glass
///   (very low), and retro-reflective number plates and lamps (high), so a vehicle's returns
///   spread widely;
/// - people: clothing (one colour per person) with a moderate spread, skin on the head;
/// - foliage (crowns, hedges, bushes) is bright in the near infrared, with a moderate spread
///   from leaf orientation and the partial footprints of porous returns; grass likewise;
/// - walls (one value per building), road and sidewalk are uniform materials: narrow spreads;
/// - sign plates are retro-reflective (near the top of the scale).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/simulation/sim_scene.h"

namespace urban_detection {
namespace core {

/// One piece of the street along x.
struct StreetSection {
  enum class Type { kStreet, kIntersection };
  Type type = Type::kStreet;
  double length_m = 60.0;          // [m] along x; for an intersection: width of the cross road
  double road_half_width_m = 6.0;  // [m] crown to curb
  double sidewalk_width_m = 3.5;   // [m] curb to facade line (street only)
  bool buildings_left = true;      // facades on the +y side (street only)
  bool buildings_right = true;     // facades on the -y side (street only)
  bool parking = true;             // rows of parked cars along both curbs (street only)
  bool furniture = true;           // trees, poles, signs, bins, benches (street only)
};

/// Buildings along a street section.
struct BuildingParams {
  double depth_m = 12.0;            // [m] from the facade back
  double height_min_m = 7.0;        // [m]
  double height_max_m = 18.0;       // [m]
  double length_min_m = 8.0;        // [m] along the street
  double length_max_m = 24.0;       // [m]
  double gap_probability = 0.25;    // [-] chance of a gap (alley) after a building
  double gap_min_m = 2.0;           // [m]
  double gap_max_m = 5.0;           // [m]
  double recess_probability = 0.3;  // [-] chance a building is set back from the facade line
  double recess_max_m = 2.0;        // [m] largest setback
};

/// Street objects.
struct StreetObjectParams {
  double parked_gap_min_m = 0.35;         // [m] smallest gap between parked cars
  double parked_gap_max_m = 2.5;          // [m] largest gap
  double parked_skip_probability = 0.15;  // [-] chance a parking slot stays empty
  double van_fraction = 0.2;              // [-] share of vans among vehicles
  int moving_cars = 4;                    // vehicles driving in the two lanes
  double moving_car_speed_mps = 10.0;     // [m/s] oncoming traffic speed
  double lane_offset_m = 1.7;             // [m] |y| of the traffic lanes' centre lines
  int pedestrians = 14;                   // pedestrians (singles and groups)
  double group_probability = 0.35;        // [-] chance a pedestrian starts a group of 2-4
  double standing_probability = 0.3;      // [-] chance a pedestrian (group) stands still
  int cyclists = 2;                       // cyclists riding beside the parked cars
  double tree_spacing_m = 14.0;           // [m] mean spacing of trees on each sidewalk
  double pole_spacing_m = 30.0;           // [m] mean spacing of lamp posts on each sidewalk
  int signs = 4;                          // traffic signs
  int bins = 6;                           // waste bins
  int benches = 3;                        // benches
  bool hard_cases = true;                 // add the paper's Fig. 4 / 7 hard cases
};

/// Vegetation and natural ground (see the file comment). Lengths are along the street (x),
/// depths across it; heights are above the local sidewalk or road surface.
struct VegetationParams {
  bool enabled = true;  // false: the scene without any of the below (crowns stay solid)
  // Grass verges: a strip of terrain beside the curb on streets with furniture.
  double verge_probability = 0.7;      // [0..1] chance a street side has a verge
  double verge_offset_m = 0.2;         // [m] paved edge between the curb and the verge
  double verge_width_m = 1.0;          // [m] across the street (sidewalks >= verge + 1.5 m only)
  double verge_step_max_m = 0.08;      // [m] largest height of a verge above the sidewalk
  double verge_bush_spacing_m = 12.0;  // [m] mean spacing of small shrubs in a verge
  // Terrain (verges and gardens) is tiled; each tile is slightly raised and tilted.
  double terrain_tile_m = 1.0;        // [m] side of a terrain tile
  double terrain_roughness_m = 0.04;  // [m] largest random extra height of a tile
  double terrain_tilt_deg = 2.0;      // [deg] largest random tilt of a tile
  // Front gardens behind the sidewalk, where no building front stands on the facade line.
  double garden_depth_m = 4.0;          // [m] depth of a garden (a setback: up to the building)
  double garden_step_max_m = 0.3;       // [m] largest terrain step at the sidewalk's back edge
  double hedge_probability = 0.75;      // [0..1] chance a garden stretch is lined with a hedge
  double hedge_height_min_m = 0.8;      // [m]
  double hedge_height_max_m = 1.8;      // [m]
  double hedge_width_min_m = 0.5;       // [m]
  double hedge_width_max_m = 1.0;       // [m]
  double hedge_gap_spacing_m = 12.0;    // [m] mean hedge length between entrance gaps
  double bush_spacing_m = 4.0;          // [m] mean spacing of bushes along a garden
  double facade_shrub_spacing_m = 8.0;  // [m] mean spacing of shrubs planted against facades
                                        //     that stand on the sidewalk (sidewalks >= 2 m)
  double bush_height_min_m = 0.5;       // [m]
  double bush_height_max_m = 2.0;       // [m]
  double garden_tree_spacing_m = 16.0;  // [m] mean spacing of trees in deep gardens
  // Tree crowns: lobes of foliage hanging over the road and the walkway.
  int canopy_lobes_min = 2;             // [-] per tree
  int canopy_lobes_max = 4;             // [-] per tree
  double canopy_overhang_max_m = 3.2;   // [m] farthest reach of a lobe's edge from the trunk
  double canopy_clearance_min_m = 2.5;  // [m] lowest leaves above the ground under them
  double canopy_clearance_max_m = 3.2;  // [m]
  // Porosity per material: chance a ray passes through, mean depth of a return inside.
  double hedge_transmission = 0.12;   // [0..1]
  double hedge_penetration_m = 0.12;  // [m]
  double bush_transmission = 0.3;     // [0..1]
  double bush_penetration_m = 0.2;    // [m]
  double crown_transmission = 0.45;   // [0..1]
  double crown_penetration_m = 0.4;   // [m]
};

/// The ego drive the scene is generated for (moving objects are placed so that they meet the
/// ego vehicle during the drive, and never drive through it).
struct DriveParams {
  /// [m] polyline in the world xy plane followed at constant speed (>= 2 points).
  std::vector<Eigen::Vector2d> waypoints{Eigen::Vector2d(0.0, -1.9), Eigen::Vector2d(200.0, -1.9)};
  double speed_mps = 8.0;  // [m/s] platform speed (0 = standing)

  /// Length of the polyline [m].
  double length() const;
  /// Duration of the drive [s] (length / speed; 0 for a standing platform).
  double duration() const;
  /// Position [m] and heading [rad] at time t_s (clamped to the ends of the path).
  void at(double t_s, Eigen::Vector2d* xy, double* yaw_rad) const;
};

/// Everything the generator needs.
struct SceneParams {
  std::uint64_t seed = 42;
  double start_x_m = -40.0;       // [m] x of the street's first section start
  double slope = 0.015;           // [-] rise of the road per metre along x
  double camber = 0.02;           // [-] fall of the road per metre from the crown to the curb
  double curb_height_m = 0.14;    // [m] sidewalk above the road edge
  double terrain_width_m = 30.0;  // [m] ground beyond the sidewalks (under buildings, in alleys)
  std::vector<StreetSection> sections = defaultSections();
  BuildingParams buildings;
  StreetObjectParams objects;
  VegetationParams vegetation;

  /// The default street: a two-side street, an intersection, a one-side street with a square,
  /// a narrow street (facades 2.8 m from the right lane), and a last two-side street.
  static std::vector<StreetSection> defaultSections();
};

// ---- field tables (core/common/param_fields.h): names, units, ranges, meanings -------------
// Cross-field rules (min <= max pairs, at least one section, a path of non-zero length) are
// checked by validate().

template <>
struct ParamFields<StreetSection> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo::choice("type", {"street", "intersection"}, "kind of section"), p.type);
    f(FieldInfo("length_m", "m", 5, 2000,
                "length along x; for an intersection: width of the cross road"),
      p.length_m);
    f(FieldInfo("road_half_width_m", "m", 2, 20, "crown to curb"), p.road_half_width_m);
    f(FieldInfo("sidewalk_width_m", "m", 0.5, 20, "curb to facade line (street only)"),
      p.sidewalk_width_m);
    f(FieldInfo("buildings_left", "facades on the +y side (street only)"), p.buildings_left);
    f(FieldInfo("buildings_right", "facades on the -y side (street only)"), p.buildings_right);
    f(FieldInfo("parking", "rows of parked cars along both curbs (street only)"), p.parking);
    f(FieldInfo("furniture", "trees, poles, signs, bins, benches (street only)"), p.furniture);
  }
};

template <>
struct ParamFields<BuildingParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("depth_m", "m", 1, 100, "depth from the facade back"), p.depth_m);
    f(FieldInfo("height_min_m", "m", 2, 300, "lowest building"), p.height_min_m);
    f(FieldInfo("height_max_m", "m", 2, 300, "highest building (>= height_min_m)"), p.height_max_m);
    f(FieldInfo("length_min_m", "m", 2, 1000, "shortest building along the street"),
      p.length_min_m);
    f(FieldInfo("length_max_m", "m", 2, 1000, "longest building (>= length_min_m)"),
      p.length_max_m);
    f(FieldInfo("gap_probability", "", 0, 1, "chance of a gap (alley) after a building"),
      p.gap_probability);
    f(FieldInfo("gap_min_m", "m", 0.01, 100, "narrowest gap"), p.gap_min_m);
    f(FieldInfo("gap_max_m", "m", 0.01, 100, "widest gap (>= gap_min_m)"), p.gap_max_m);
    f(FieldInfo("recess_probability", "", 0, 1,
                "chance a building is set back from the facade line"),
      p.recess_probability);
    f(FieldInfo("recess_max_m", "m", 0.5, 50, "largest setback"), p.recess_max_m);
  }
};

template <>
struct ParamFields<StreetObjectParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("parked_gap_min_m", "m", 0.01, 50, "smallest gap between parked cars"),
      p.parked_gap_min_m);
    f(FieldInfo("parked_gap_max_m", "m", 0.01, 50, "largest gap (>= parked_gap_min_m)"),
      p.parked_gap_max_m);
    f(FieldInfo("parked_skip_probability", "", 0, 1, "chance a parking slot stays empty"),
      p.parked_skip_probability);
    f(FieldInfo("van_fraction", "", 0, 1, "share of vans among vehicles"), p.van_fraction);
    f(FieldInfo("moving_cars", "", 0, 1000, "vehicles driving in the two lanes"), p.moving_cars);
    f(FieldInfo("moving_car_speed_mps", "m/s", 0, 50, "oncoming traffic speed"),
      p.moving_car_speed_mps);
    f(FieldInfo("lane_offset_m", "m", 0, 20, "|y| of the traffic lanes' centre lines"),
      p.lane_offset_m);
    f(FieldInfo("pedestrians", "", 0, 1000, "pedestrians (singles and groups)"), p.pedestrians);
    f(FieldInfo("group_probability", "", 0, 1, "chance a pedestrian starts a group of 2-4"),
      p.group_probability);
    f(FieldInfo("standing_probability", "", 0, 1, "chance a pedestrian (group) stands still"),
      p.standing_probability);
    f(FieldInfo("cyclists", "", 0, 1000, "cyclists riding beside the parked cars"), p.cyclists);
    f(FieldInfo("tree_spacing_m", "m", 3, 1000, "mean spacing of trees on each sidewalk"),
      p.tree_spacing_m);
    f(FieldInfo("pole_spacing_m", "m", 3, 1000, "mean spacing of lamp posts on each sidewalk"),
      p.pole_spacing_m);
    f(FieldInfo("signs", "", 0, 1000, "traffic signs"), p.signs);
    f(FieldInfo("bins", "", 0, 1000, "waste bins"), p.bins);
    f(FieldInfo("benches", "", 0, 1000, "benches"), p.benches);
    f(FieldInfo("hard_cases", "add the paper's Fig. 4 / 7 hard cases"), p.hard_cases);
  }
};

template <>
struct ParamFields<VegetationParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("enabled", "false: the scene without vegetation (crowns stay solid)"), p.enabled);
    f(FieldInfo("verge_probability", "", 0, 1, "chance a street side has a grass verge"),
      p.verge_probability);
    f(FieldInfo("verge_offset_m", "m", 0, 2, "paved edge between the curb and the verge"),
      p.verge_offset_m);
    f(FieldInfo("verge_width_m", "m", 0.3, 5,
                "verge width across the street (sidewalks >= verge + 1.5 m only)"),
      p.verge_width_m);
    f(FieldInfo("verge_step_max_m", "m", 0, 0.3, "largest height of a verge above the sidewalk"),
      p.verge_step_max_m);
    f(FieldInfo("verge_bush_spacing_m", "m", 2, 1000, "mean spacing of small shrubs in a verge"),
      p.verge_bush_spacing_m);
    f(FieldInfo("terrain_tile_m", "m", 0.25, 5, "side of a terrain tile (raised and tilted)"),
      p.terrain_tile_m);
    f(FieldInfo("terrain_roughness_m", "m", 0, 0.2, "largest random extra height of a tile"),
      p.terrain_roughness_m);
    f(FieldInfo("terrain_tilt_deg", "deg", 0, 10, "largest random tilt of a tile"),
      p.terrain_tilt_deg);
    f(FieldInfo("garden_depth_m", "m", 0.5, 20,
                "depth of a front garden (a setback: up to the building)"),
      p.garden_depth_m);
    f(FieldInfo("garden_step_max_m", "m", 0, 0.5,
                "largest terrain step at the sidewalk's back edge"),
      p.garden_step_max_m);
    f(FieldInfo("hedge_probability", "", 0, 1, "chance a garden stretch is lined with a hedge"),
      p.hedge_probability);
    f(FieldInfo("hedge_height_min_m", "m", 0.3, 4, "lowest hedge"), p.hedge_height_min_m);
    f(FieldInfo("hedge_height_max_m", "m", 0.3, 4, "highest hedge (>= hedge_height_min_m)"),
      p.hedge_height_max_m);
    f(FieldInfo("hedge_width_min_m", "m", 0.3, 3, "thinnest hedge"), p.hedge_width_min_m);
    f(FieldInfo("hedge_width_max_m", "m", 0.3, 3, "thickest hedge (>= hedge_width_min_m)"),
      p.hedge_width_max_m);
    f(FieldInfo("hedge_gap_spacing_m", "m", 2, 1000, "mean hedge length between entrance gaps"),
      p.hedge_gap_spacing_m);
    f(FieldInfo("bush_spacing_m", "m", 1, 1000, "mean spacing of bushes along a garden"),
      p.bush_spacing_m);
    f(FieldInfo("facade_shrub_spacing_m", "m", 1, 1000,
                "mean spacing of shrubs against facades on the sidewalk (sidewalks >= 2 m)"),
      p.facade_shrub_spacing_m);
    f(FieldInfo("bush_height_min_m", "m", 0.2, 4, "lowest bush"), p.bush_height_min_m);
    f(FieldInfo("bush_height_max_m", "m", 0.2, 4, "highest bush (>= bush_height_min_m)"),
      p.bush_height_max_m);
    f(FieldInfo("garden_tree_spacing_m", "m", 4, 1000, "mean spacing of trees in deep gardens"),
      p.garden_tree_spacing_m);
    f(FieldInfo("canopy_lobes_min", "", 0, 12, "fewest low crown lobes per tree"),
      p.canopy_lobes_min);
    f(FieldInfo("canopy_lobes_max", "", 0, 12, "most lobes per tree (>= canopy_lobes_min)"),
      p.canopy_lobes_max);
    f(FieldInfo("canopy_overhang_max_m", "m", 1, 8,
                "farthest reach of a lobe's edge from the trunk"),
      p.canopy_overhang_max_m);
    f(FieldInfo("canopy_clearance_min_m", "m", 1, 8, "lowest leaves above the ground under them"),
      p.canopy_clearance_min_m);
    f(FieldInfo("canopy_clearance_max_m", "m", 1, 8,
                "highest lowest-leaves (>= canopy_clearance_min_m)"),
      p.canopy_clearance_max_m);
    f(FieldInfo("hedge_transmission", "", 0, 1, "chance a ray passes through a hedge"),
      p.hedge_transmission);
    f(FieldInfo("hedge_penetration_m", "m", 0, 2, "mean depth of a return inside a hedge"),
      p.hedge_penetration_m);
    f(FieldInfo("bush_transmission", "", 0, 1, "chance a ray passes through a bush"),
      p.bush_transmission);
    f(FieldInfo("bush_penetration_m", "m", 0, 2, "mean depth of a return inside a bush"),
      p.bush_penetration_m);
    f(FieldInfo("crown_transmission", "", 0, 1, "chance a ray passes through a tree crown"),
      p.crown_transmission);
    f(FieldInfo("crown_penetration_m", "m", 0, 2, "mean depth of a return inside a crown"),
      p.crown_penetration_m);
  }
};

template <>
struct ParamFields<DriveParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("waypoints", "m", -1e6, 1e6,
                "[x, y] polyline followed at constant speed (>= 2 points, non-zero length)"),
      p.waypoints);
    f(FieldInfo("speed_mps", "m/s", 0, 40, "platform speed (0 = standing)"), p.speed_mps);
  }
};

/// The scene's table has no `seed` (it sits at the top of a simulation config, see
/// simulation_config.h).
template <>
struct ParamFields<SceneParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo("start_x_m", "m", -1e6, 1e6, "x of the street's first section start"), p.start_x_m);
    f(FieldInfo("slope", "", -0.15, 0.15, "rise of the road per metre along x"), p.slope);
    f(FieldInfo("camber", "", 0, 0.08, "fall of the road per metre from the crown to the curb"),
      p.camber);
    f(FieldInfo("curb_height_m", "m", 0, 0.4, "sidewalk above the road edge"), p.curb_height_m);
    f(FieldInfo("terrain_width_m", "m", 1, 200,
                "ground beyond the sidewalks (under buildings, in alleys)"),
      p.terrain_width_m);
    f(FieldInfo("sections", "street sections in order along +x (at least one)"), p.sections);
    forEachField(p.buildings, "buildings", f);
    forEachField(p.objects, "objects", f);
    forEachField(p.vegetation, "vegetation", f);
  }
};

/// "" or the first field of `section` outside its table range.
inline std::string validate(const StreetSection& section) {
  return checkFieldRanges(section);
}

/// Builds the scene. Throws std::invalid_argument naming the field if a parameter is invalid.
Scene generateScene(const SceneParams& scene, const DriveParams& drive);

/// Height [m] of the paved ground (road, sidewalk, the ground beyond) at (x, y) of the
/// generated street: the surface the objects stand on and the platform drives on. Terrain tiles
/// (verges, gardens) lie up to a few decimetres above it.
double groundHeight(const SceneParams& scene, double x_m, double y_m);

/// Checks the parameters; throws std::invalid_argument naming the field and accepted range.
void validate(const SceneParams& scene);
void validate(const DriveParams& drive);

}  // namespace core
}  // namespace urban_detection
