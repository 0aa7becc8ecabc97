#include "urban_detection/core/simulation/scene_generator.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace urban_detection {
namespace core {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSlabThickness = 0.5;  // [m] of ground slabs below their surface

// Deterministic across platforms (std::uniform_real_distribution is not specified exactly).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double a = 0.0, double b = 1.0) {
    return a + (b - a) * static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0);
  }
  bool chance(double p) { return uniform() < p; }
  int integer(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }

 private:
  std::uint64_t s_;
};

struct SectionSpan {
  const StreetSection* s;
  double x0, x1;
  int index;
};

std::vector<SectionSpan> spans(const SceneParams& p) {
  std::vector<SectionSpan> out;
  double x = p.start_x_m;
  for (std::size_t i = 0; i < p.sections.size(); ++i) {
    out.push_back({&p.sections[i], x, x + p.sections[i].length_m, static_cast<int>(i)});
    x += p.sections[i].length_m;
  }
  return out;
}

const SectionSpan& spanAt(const std::vector<SectionSpan>& sp, double x) {
  for (const auto& s : sp) {
    if (x < s.x1) return s;
  }
  return sp.back();
}

// A slab whose top face lies in the plane z = a + sx * x + sy * y over [x0,x1] x [y0,y1].
Primitive tiltedSlab(double x0, double x1, double y0, double y1, double a, double sx, double sy) {
  const Eigen::Vector3d ex = Eigen::Vector3d(1.0, 0.0, sx).normalized();
  const Eigen::Vector3d n = Eigen::Vector3d(-sx, -sy, 1.0).normalized();
  const Eigen::Vector3d ey = n.cross(ex).normalized();
  Primitive p;
  p.shape = PrimitiveShape::kBox;
  p.rotation.col(0) = ex;
  p.rotation.col(1) = ey;
  p.rotation.col(2) = n;
  const double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
  p.center = Eigen::Vector3d(xm, ym, a + sx * xm + sy * ym) - 0.5 * kSlabThickness * n;
  p.half_extents =
      Eigen::Vector3d(0.5 * (x1 - x0) * std::sqrt(1.0 + sx * sx),
                      0.5 * (y1 - y0) * std::sqrt(1.0 + sy * sy), 0.5 * kSlabThickness);
  p.object_class = ObjectClass::kGround;
  return p;
}

Primitive withClass(Primitive p, ObjectClass c, float reflectivity, float spread = 0.0f) {
  p.object_class = c;
  p.reflectivity = reflectivity;
  p.reflectivity_spread = spread;
  return p;
}

// Materials (reflectivity mean, per-return spread; the header's file comment says why).
struct Material {
  float mean, spread;
};
constexpr Material kRoad{0.25f, 0.04f};
constexpr Material kSidewalk{0.30f, 0.04f};
constexpr Material kGrass{0.36f, 0.07f};
constexpr Material kWallSpread{0.0f, 0.04f};  // mean drawn per building
constexpr Material kGlass{0.03f, 0.03f};
constexpr Material kPlate{0.90f, 0.06f};
constexpr Material kLamp{0.70f, 0.15f};
constexpr float kPaintSpread = 0.10f;  // curvature and gloss under one colour
constexpr float kClothSpread = 0.13f;
constexpr Material kSkin{0.45f, 0.06f};
constexpr Material kBicycle{0.35f, 0.15f};
constexpr Material kFoliage{0.38f, 0.13f};
constexpr Material kBark{0.35f, 0.08f};
constexpr Material kMetalPost{0.30f, 0.10f};
constexpr Material kSignPlate{0.95f, 0.04f};
constexpr Material kBinPlastic{0.30f, 0.05f};
constexpr Material kBenchWood{0.30f, 0.07f};

Primitive withMaterial(Primitive p, ObjectClass c, const Material& m) {
  return withClass(p, c, m.mean, m.spread);
}

Primitive porous(Primitive p, double transmission, double penetration_m) {
  p.transmission = static_cast<float>(transmission);
  p.penetration_m = static_cast<float>(penetration_m);
  return p;
}

// Local-to-world placement of an object's parts: the part offsets are in the object frame
// (x forward, y left, z up from the ground at the footprint centre).
struct Placer {
  Eigen::Vector3d base;
  double yaw;
  Eigen::Vector3d at(double fx, double fy, double fz) const {
    const double c = std::cos(yaw), s = std::sin(yaw);
    return base + Eigen::Vector3d(c * fx - s * fy, s * fx + c * fy, fz);
  }
  Primitive box(double fx, double fy, double fz, double lx, double ly, double lz) const {
    return makeBox(at(fx, fy, fz), Eigen::Vector3d(lx, ly, lz), yaw);
  }
};

class Generator {
 public:
  // Vegetation and materials draw from their own streams, so that they never move the other
  // objects of a seed.
  Generator(const SceneParams& p, const DriveParams& d)
      : p_(p),
        d_(d),
        rng_(p.seed),
        veg_(p.seed ^ 0x5645474554415445ULL),
        mat_(p.seed ^ 0x4D4154455249414CULL),
        spans_(spans(p)) {}

  Scene run() {
    background();
    vehicles();
    furniture();
    people();
    if (p_.objects.hard_cases) hardCases();
    if (p_.vegetation.enabled) vegetation();
    return std::move(scene_);
  }

 private:
  double ground(double x, double y) const { return groundHeight(p_, x, y); }

  // ---- background: road, sidewalks and terrain, buildings ----------------------------------
  void background() {
    const double s = p_.slope, c = p_.camber;
    for (std::size_t i = 0; i < spans_.size(); ++i) {
      const SectionSpan& sp = spans_[i];
      const StreetSection& sec = *sp.s;
      const double w = sec.road_half_width_m;
      // Road: two halves falling from the crown.
      scene_.addBackground(
          withMaterial(tiltedSlab(sp.x0, sp.x1, 0.0, w, 0.0, s, -c), ObjectClass::kGround, kRoad));
      scene_.addBackground(
          withMaterial(tiltedSlab(sp.x0, sp.x1, -w, 0.0, 0.0, s, c), ObjectClass::kGround, kRoad));
      if (sec.type == StreetSection::Type::kIntersection) {
        // Cross road at the main road's edge height, out to the terrain width.
        const double far = w + p_.sections[i].sidewalk_width_m + p_.terrain_width_m;
        for (int side : {-1, 1}) {
          const double y0 = side > 0 ? w : -far, y1 = side > 0 ? far : -w;
          scene_.addBackground(withMaterial(tiltedSlab(sp.x0, sp.x1, y0, y1, -c * w, s, 0.0),
                                            ObjectClass::kGround, kRoad));
        }
        continue;
      }
      // Sidewalk + terrain on each side: its road-facing side is the curb.
      const double top = p_.curb_height_m - c * w;
      const double far = w + sec.sidewalk_width_m + p_.terrain_width_m;
      scene_.addBackground(withMaterial(tiltedSlab(sp.x0, sp.x1, w, far, top, s, 0.0),
                                        ObjectClass::kGround, kSidewalk));
      scene_.addBackground(withMaterial(tiltedSlab(sp.x0, sp.x1, -far, -w, top, s, 0.0),
                                        ObjectClass::kGround, kSidewalk));
      const bool prev_cross = i > 0 && spans_[i - 1].s->type == StreetSection::Type::kIntersection;
      const bool next_cross =
          i + 1 < spans_.size() && spans_[i + 1].s->type == StreetSection::Type::kIntersection;
      const double bx0 = sp.x0 + (prev_cross ? 3.0 : 0.0);
      const double bx1 = sp.x1 - (next_cross ? 3.0 : 0.0);
      if (sec.buildings_left) buildings(bx0, bx1, w + sec.sidewalk_width_m, 1, sp.index);
      if (sec.buildings_right) buildings(bx0, bx1, w + sec.sidewalk_width_m, -1, sp.index);
    }
  }

  void buildings(double x0, double x1, double facade, int side, int section) {
    const BuildingParams& b = p_.buildings;
    double x = x0;
    while (x < x1 - 1.0) {
      const double len = std::min(rng_.uniform(b.length_min_m, b.length_max_m), x1 - x);
      const double recess =
          rng_.chance(b.recess_probability) ? rng_.uniform(0.5, b.recess_max_m) : 0.0;
      const double height = rng_.uniform(b.height_min_m, b.height_max_m);
      const double y_front = facade + recess;
      const double zb = std::min(ground(x, side * y_front), ground(x + len, side * y_front)) - 1.0;
      const double zt =
          std::max(ground(x, side * y_front), ground(x + len, side * y_front)) + height;
      Primitive wall = makeBox(
          Eigen::Vector3d(x + 0.5 * len, side * (y_front + 0.5 * b.depth_m), 0.5 * (zb + zt)),
          Eigen::Vector3d(len, b.depth_m, zt - zb), 0.0);
      const float plaster = static_cast<float>(mat_.uniform(0.25, 0.5));
      scene_.addBackground(withClass(wall, ObjectClass::kWall, plaster, kWallSpread.spread));
      facades_.push_back({x, x + len, side * y_front, side, section});
      x += len;
      if (rng_.chance(b.gap_probability)) x += rng_.uniform(b.gap_min_m, b.gap_max_m);
    }
  }

  // ---- objects -------------------------------------------------------------------------------
  std::uint32_t add(ObjectClass cls, double x, double y, double yaw, const Eigen::Vector3d& size,
                    const Eigen::Vector3d& velocity, std::vector<Primitive> parts) {
    SceneObject o;
    o.object_class = cls;
    o.position = Eigen::Vector3d(x, y, ground(x, y));
    o.yaw_rad = yaw;
    o.size = size;
    o.velocity = velocity;
    return scene_.addObject(o, parts);
  }

  Placer placer(double x, double y, double yaw) const {
    return Placer{Eigen::Vector3d(x, y, ground(x, y)), yaw};
  }

  std::uint32_t car(double x, double y, double yaw, bool van, const Eigen::Vector3d& v) {
    const Placer pl = placer(x, y, yaw);
    const float refl = static_cast<float>(rng_.uniform(0.03, 0.6));  // paint colour
    const ObjectClass cls = van ? ObjectClass::kVan : ObjectClass::kCar;
    std::vector<Primitive> parts;
    double l, wd, h, z_plate, z_lamp;
    if (van) {
      l = rng_.uniform(4.8, 5.4), wd = 2.0, h = 2.2;
      parts.push_back(withClass(pl.box(0, 0, 0.3 + 0.5, l, wd, 1.0), cls, refl, kPaintSpread));
      // Upper body: windscreen and front side windows (glass) ahead of a painted box.
      const double lu = l - 0.8, glass = 0.9;
      parts.push_back(
          withClass(pl.box(-0.35 - 0.5 * glass, 0, 1.3 + 0.45, lu - glass, wd - 0.1, 0.9), cls,
                    refl, kPaintSpread));
      parts.push_back(withMaterial(
          pl.box(-0.35 + 0.5 * (lu - glass), 0, 1.3 + 0.45, glass, wd - 0.1, 0.9), cls, kGlass));
      z_plate = 0.55, z_lamp = 1.0;
    } else {
      l = rng_.uniform(4.0, 4.7), wd = rng_.uniform(1.7, 1.85), h = 1.45;
      parts.push_back(withClass(pl.box(0, 0, 0.25 + 0.35, l, wd, 0.7), cls, refl, kPaintSpread));
      // Cabin: windows (glass) under a painted roof.
      parts.push_back(
          withMaterial(pl.box(-0.2, 0, 0.95 + 0.22, 0.55 * l, wd - 0.15, 0.44), cls, kGlass));
      parts.push_back(withClass(pl.box(-0.2, 0, 1.39 + 0.03, 0.55 * l, wd - 0.15, 0.06), cls, refl,
                                kPaintSpread));
      z_plate = 0.45, z_lamp = 0.75;
    }
    // Number plates and lamps front and rear, standing 2 cm proud of the body.
    for (double end : {-1.0, 1.0}) {
      const double fx = end * (0.5 * l + 0.01);
      parts.push_back(withMaterial(pl.box(fx, 0, z_plate, 0.04, 0.52, 0.12), cls, kPlate));
      for (double s : {-1.0, 1.0}) {
        parts.push_back(
            withMaterial(pl.box(fx, s * (0.5 * wd - 0.22), z_lamp, 0.04, 0.3, 0.14), cls, kLamp));
      }
    }
    return add(cls, x, y, yaw, {l, wd, h}, v, parts);
  }

  std::uint32_t pedestrian(double x, double y, double yaw, const Eigen::Vector3d& v,
                           double scale = -1.0) {
    if (scale <= 0.0) scale = rng_.uniform(0.9, 1.08);
    const Placer pl = placer(x, y, yaw);
    const float refl = static_cast<float>(rng_.uniform(0.2, 0.6));   // upper clothing
    const float legs = static_cast<float>(mat_.uniform(0.15, 0.6));  // trousers, skirt
    std::vector<Primitive> parts;
    parts.push_back(withClass(pl.box(0, 0, 0.42 * scale, 0.28 * scale, 0.36 * scale, 0.84 * scale),
                              ObjectClass::kPedestrian, legs, kClothSpread));
    Primitive torso = makeCylinder(pl.at(0, 0, 1.14 * scale), 0.2 * scale, 0.6 * scale);
    parts.push_back(withClass(torso, ObjectClass::kPedestrian, refl, kClothSpread));
    Primitive head =
        makeEllipsoid(pl.at(0, 0, 1.57 * scale), Eigen::Vector3d::Constant(0.11 * scale));
    parts.push_back(withMaterial(head, ObjectClass::kPedestrian, kSkin));
    return add(ObjectClass::kPedestrian, x, y, yaw, Eigen::Vector3d(0.4, 0.4, 1.68) * scale, v,
               parts);
  }

  std::uint32_t cyclist(double x, double y, double yaw, const Eigen::Vector3d& v) {
    const Placer pl = placer(x, y, yaw);
    const float refl = static_cast<float>(rng_.uniform(0.2, 0.5));
    std::vector<Primitive> parts;
    parts.push_back(
        withMaterial(pl.box(0, 0, 0.5, 1.75, 0.12, 0.95), ObjectClass::kCyclist, kBicycle));
    parts.push_back(withClass(pl.box(0.05, 0, 0.85, 0.3, 0.32, 0.4), ObjectClass::kCyclist, refl,
                              kClothSpread));
    Primitive torso = makeCylinder(pl.at(-0.05, 0, 1.3), 0.19, 0.55);
    parts.push_back(withClass(torso, ObjectClass::kCyclist, refl, kClothSpread));
    Primitive head = makeEllipsoid(pl.at(0.05, 0, 1.7), Eigen::Vector3d::Constant(0.12));
    parts.push_back(withMaterial(head, ObjectClass::kCyclist, kSkin));
    return add(ObjectClass::kCyclist, x, y, yaw, {1.75, 0.4, 1.82}, v, parts);
  }

  // A street tree: its size is drawn from the main stream as before the vegetation, its lobes
  // from the vegetation stream.
  std::uint32_t tree(double x, double y) {
    const double trunk_h = rng_.uniform(2.4, 3.2);
    const double crown_r = rng_.uniform(1.4, 2.4);
    const double crown_h = rng_.uniform(1.5, 2.5);
    const double trunk_r = rng_.uniform(0.12, 0.2);
    // Street trees stand at the curb: their low lobes hang over the parked cars.
    return treeObject(x, y, trunk_h, trunk_r, crown_r, crown_h,
                      Eigen::Vector2d(0.0, y > 0 ? -1.0 : 1.0));
  }

  // Trunk, crown and (with vegetation) porous lobes; `toward` is the unit xy direction about
  // half of the lobes lean to.
  std::uint32_t treeObject(double x, double y, double trunk_h, double trunk_r, double crown_r,
                           double crown_h, const Eigen::Vector2d& toward) {
    const VegetationParams& v = p_.vegetation;
    const Placer pl = placer(x, y, 0.0);
    std::vector<Primitive> parts;
    parts.push_back(
        withMaterial(makeCylinder(pl.at(0, 0, 0.5 * trunk_h + 0.3), trunk_r, trunk_h + 0.6),
                     ObjectClass::kTrunk, kBark));
    Primitive crown = withMaterial(
        makeEllipsoid(pl.at(0, 0, trunk_h + crown_h), Eigen::Vector3d(crown_r, crown_r, crown_h)),
        ObjectClass::kVegetation, kFoliage);
    if (v.enabled) {
      parts.push_back(porous(crown, v.crown_transmission, v.crown_penetration_m));
      // Lobes: about half lean towards `toward`, the rest anywhere; each reaches at most
      // canopy_overhang_max_m from the trunk and keeps its lowest leaves canopy_clearance above
      // the ground under it.
      const int n = veg_.integer(v.canopy_lobes_min, v.canopy_lobes_max);
      const double lean = std::atan2(toward.y(), toward.x());
      for (int k = 0; k < n; ++k) {
        const double az = k % 2 == 0 ? lean + veg_.uniform(-0.9, 0.9) : veg_.uniform(-kPi, kPi);
        const double a = veg_.uniform(0.8, 1.4);   // horizontal semi-axis
        const double c = veg_.uniform(0.45, 0.8);  // vertical semi-axis
        const double reach = std::max(0.0, v.canopy_overhang_max_m - a);
        const double d = veg_.uniform(std::min(0.5 * crown_r, reach), reach);
        const double lx = x + d * std::cos(az), ly = y + d * std::sin(az);
        const double bottom =
            ground(lx, ly) + veg_.uniform(v.canopy_clearance_min_m, v.canopy_clearance_max_m);
        Primitive lobe =
            makeEllipsoid(Eigen::Vector3d(lx, ly, bottom + c), Eigen::Vector3d(a, a, c));
        lobe.rotation = Eigen::AngleAxisd(az, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        lobe.half_extents.y() = a * veg_.uniform(0.7, 1.0);
        parts.push_back(porous(withMaterial(lobe, ObjectClass::kVegetation, kFoliage),
                               v.crown_transmission, v.crown_penetration_m));
      }
    } else {
      parts.push_back(crown);
    }
    Eigen::AlignedBox3d box;
    for (const Primitive& q : parts) box.extend(q.bounds());
    const double gz = ground(x, y);
    return add(ObjectClass::kVegetation, x, y, 0.0,
               {box.sizes().x(), box.sizes().y(), box.max().z() - gz}, Eigen::Vector3d::Zero(),
               parts);
  }

  std::uint32_t pole(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    const double h = rng_.uniform(4.5, 7.0);
    std::vector<Primitive> parts;
    parts.push_back(withMaterial(makeCylinder(pl.at(0, 0, 0.5 * h - 0.2), 0.08, h + 0.4),
                                 ObjectClass::kPole, kMetalPost));
    const double arm = y > 0 ? -0.6 : 0.6;  // lamp head over the road
    parts.push_back(
        withMaterial(pl.box(0, arm, h - 0.1, 0.35, 1.3, 0.18), ObjectClass::kPole, kMetalPost));
    return add(ObjectClass::kPole, x, y, 0.0, {0.35, 1.5, h}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t sign(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    std::vector<Primitive> parts;
    parts.push_back(
        withMaterial(makeCylinder(pl.at(0, 0, 1.2), 0.04, 2.8), ObjectClass::kPole, kMetalPost));
    // Plate facing the traffic (normal along x), retro-reflective.
    parts.push_back(
        withMaterial(pl.box(0.07, 0, 2.35, 0.06, 0.65, 0.65), ObjectClass::kSign, kSignPlate));
    return add(ObjectClass::kSign, x, y, 0.0, {0.1, 0.65, 2.7}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t bin(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    std::vector<Primitive> parts;
    const double h = rng_.uniform(0.9, 1.2);
    parts.push_back(
        withMaterial(makeCylinder(pl.at(0, 0, 0.5 * h), 0.3, h), ObjectClass::kBin, kBinPlastic));
    return add(ObjectClass::kBin, x, y, 0.0, {0.6, 0.6, h}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t bench(double x, double y, double yaw) {
    const Placer pl = placer(x, y, yaw);
    std::vector<Primitive> parts;
    parts.push_back(
        withMaterial(pl.box(0, 0, 0.45, 1.8, 0.5, 0.08), ObjectClass::kBench, kBenchWood));
    parts.push_back(
        withMaterial(pl.box(0, -0.22, 0.72, 1.8, 0.06, 0.45), ObjectClass::kBench, kBenchWood));
    parts.push_back(
        withMaterial(pl.box(-0.75, 0, 0.21, 0.08, 0.45, 0.42), ObjectClass::kBench, kBenchWood));
    parts.push_back(
        withMaterial(pl.box(0.75, 0, 0.21, 0.08, 0.45, 0.42), ObjectClass::kBench, kBenchWood));
    return add(ObjectClass::kBench, x, y, yaw, {1.8, 0.5, 0.95}, Eigen::Vector3d::Zero(), parts);
  }

  // ---- placement -----------------------------------------------------------------------------
  bool free(double x, double y, double r) {
    for (const auto& o : placed_) {
      if (std::hypot(o.x() - x, o.y() - y) < r + o.z()) return false;
    }
    return true;
  }
  void occupy(double x, double y, double r) { placed_.emplace_back(x, y, r); }

  void vehicles() {
    const StreetObjectParams& o = p_.objects;
    for (const SectionSpan& sp : spans_) {
      const StreetSection& sec = *sp.s;
      if (sec.type != StreetSection::Type::kStreet || !sec.parking) continue;
      for (int side : {-1, 1}) {
        const double yaw = side < 0 ? 0.0 : kPi;
        double x = sp.x0 + 2.0;
        int slot = 0;
        while (true) {
          const bool van = rng_.chance(o.van_fraction);
          const double len = van ? 5.4 : 4.7;  // room for the longest of its kind
          if (x + len > sp.x1 - 2.0) break;
          const double width = van ? 2.0 : 1.85;
          const double y = side * (sec.road_half_width_m - 0.25 - 0.5 * width);
          if (!rng_.chance(o.parked_skip_probability)) {
            const std::uint32_t id = car(x + 0.5 * len, y, yaw, van, Eigen::Vector3d::Zero());
            parked_.push_back(id);
          }
          double gap = rng_.uniform(o.parked_gap_min_m, o.parked_gap_max_m);
          // Hard case (Fig. 4a): some bumper-to-bumper neighbours closer than a coarse cell.
          if (o.hard_cases && slot % 4 == 2) gap = o.parked_gap_min_m;
          x += len + gap;
          ++slot;
        }
      }
    }
    // Moving traffic: oncoming (+y lane, -x) and ahead of the ego (-y lane, faster than it).
    const double t_end = std::max(1.0, d_.duration());
    const Eigen::Vector2d ego0 = d_.waypoints.front();
    for (int i = 0; i < o.moving_cars; ++i) {
      const bool oncoming = i % 2 == 0;
      const bool van = rng_.chance(o.van_fraction);
      double vx, x0, y;
      if (oncoming) {
        vx = -o.moving_car_speed_mps * rng_.uniform(0.8, 1.1);
        // Meets the ego somewhere during the drive.
        const double t_meet = rng_.uniform(0.1, 0.9) * t_end;
        Eigen::Vector2d ego;
        double yaw;
        d_.at(t_meet, &ego, &yaw);
        x0 = ego.x() - vx * t_meet;
        y = o.lane_offset_m;
      } else {
        vx = d_.speed_mps + rng_.uniform(2.0, 4.0);
        x0 = ego0.x() + rng_.uniform(12.0, 40.0) + 12.0 * i;
        y = -o.lane_offset_m;
      }
      car(x0, y, vx > 0 ? 0.0 : kPi, van, Eigen::Vector3d(vx, 0.0, p_.slope * vx));
    }
    // Cyclists beside the parked cars, kept inside the wide part of the street for the drive.
    double wide_end = spans_.back().x1;
    for (const SectionSpan& sp : spans_) {
      if (sp.s->road_half_width_m < 4.5) {
        wide_end = sp.x0;
        break;
      }
    }
    for (int i = 0; i < o.cyclists; ++i) {
      const double v = rng_.uniform(3.5, 5.0);
      const double room = wide_end - 2.0 - v * t_end - (p_.start_x_m + 2.0);
      if (room <= 0.0) break;
      const double x0 = p_.start_x_m + 2.0 + rng_.uniform(0.0, room);
      const double y = -(spans_.front().s->road_half_width_m - 3.05);
      cyclist(x0, y, 0.0, Eigen::Vector3d(v, 0.0, p_.slope * v));
    }
  }

  void furniture() {
    const StreetObjectParams& o = p_.objects;
    std::vector<std::pair<const SectionSpan*, int>> sides;
    for (const SectionSpan& sp : spans_) {
      const StreetSection& sec = *sp.s;
      if (sec.type != StreetSection::Type::kStreet || !sec.furniture) continue;
      for (int side : {-1, 1}) {
        sides.emplace_back(&sp, side);
        const double w = sec.road_half_width_m;
        const double y_curb = side * (w + 0.7);  // curb zone line
        // Lamp posts, then trees between them.
        for (double x = sp.x0 + rng_.uniform(3.0, o.pole_spacing_m); x < sp.x1 - 3.0;
             x += o.pole_spacing_m * rng_.uniform(0.8, 1.2)) {
          if (!free(x, y_curb, 0.5)) continue;
          pole(x, side * (w + 0.45));
          occupy(x, y_curb, 0.5);
        }
        for (double x = sp.x0 + rng_.uniform(2.0, o.tree_spacing_m); x < sp.x1 - 2.0;
             x += o.tree_spacing_m * rng_.uniform(0.7, 1.3)) {
          if (!free(x, y_curb, 2.5)) continue;
          tree(x, y_curb);
          occupy(x, y_curb, 1.0);
        }
      }
    }
    if (sides.empty()) return;
    auto pick = [&](double zone_from_curb, double r, double* x, double* y, int* side,
                    const SectionSpan** span) {
      for (int tries = 0; tries < 40; ++tries) {
        const auto& s =
            sides[static_cast<std::size_t>(rng_.integer(0, static_cast<int>(sides.size()) - 1))];
        const double w = s.first->s->road_half_width_m;
        const double xx = rng_.uniform(s.first->x0 + 3.0, s.first->x1 - 3.0);
        const double yy = s.second * (w + zone_from_curb);
        if (!free(xx, yy, r)) continue;
        *x = xx, *y = yy, *side = s.second, *span = s.first;
        return true;
      }
      return false;
    };
    double x, y;
    int side;
    const SectionSpan* sp;
    for (int i = 0; i < o.signs; ++i) {
      if (!pick(0.35, 0.6, &x, &y, &side, &sp)) continue;
      sign(x, y);
      occupy(x, y, 0.5);
    }
    for (int i = 0; i < o.bins; ++i) {
      if (!pick(0.6, 0.8, &x, &y, &side, &sp)) continue;
      bin(x, y);
      occupy(x, y, 0.4);
    }
    for (int i = 0; i < o.benches; ++i) {
      if (!pick(0.9, 1.2, &x, &y, &side, &sp)) continue;
      // Benches face the road from the curb zone.
      bench(x, y, side > 0 ? kPi : 0.0);
      occupy(x, y, 1.0);
    }
  }

  void people() {
    const StreetObjectParams& o = p_.objects;
    const double t_end = std::max(1.0, d_.duration());
    std::vector<const SectionSpan*> walks;
    for (const SectionSpan& sp : spans_) {
      if (sp.s->type == StreetSection::Type::kStreet) walks.push_back(&sp);
    }
    if (walks.empty()) return;
    int placed = 0;
    while (placed < o.pedestrians) {
      const SectionSpan& sp =
          *walks[static_cast<std::size_t>(rng_.integer(0, static_cast<int>(walks.size()) - 1))];
      const StreetSection& sec = *sp.s;
      const int side = rng_.chance(0.5) ? 1 : -1;
      const int n = rng_.chance(o.group_probability) ? rng_.integer(2, 4) : 1;
      const double len = sp.x1 - sp.x0 - 4.0;
      double v = rng_.chance(o.standing_probability) ? 0.0 : rng_.uniform(0.9, 1.6);
      v = std::min(v, 0.9 * len / t_end);  // stay on this section's sidewalk
      const double dir = rng_.chance(0.5) ? 1.0 : -1.0;
      const double travel = v * t_end;
      const double x0 = dir > 0 ? rng_.uniform(sp.x0 + 2.0, sp.x1 - 2.0 - travel - 1.5 * n)
                                : rng_.uniform(sp.x0 + 2.0 + travel + 1.5 * n, sp.x1 - 2.0);
      // Walking lines: one per direction, so that walkers rarely cross each other; furniture
      // stays at the curb and against the facades.
      const double frac = dir > 0 ? 0.45 : 0.75;
      const double y_walk =
          side * (sec.road_half_width_m + std::max(0.4, frac * sec.sidewalk_width_m));
      const Eigen::Vector3d vel(dir * v, 0.0, p_.slope * dir * v);
      const bool wide = sec.sidewalk_width_m > 2.0;
      for (int k = 0; k < n && placed < o.pedestrians; ++k, ++placed) {
        // Group members side by side (0.45 m apart, outwards) or one behind the other.
        const double along = (wide ? (k / 2) * rng_.uniform(0.7, 1.0) : 0.8 * k) * -dir;
        const double across = wide ? (k % 2) * 0.45 * side : 0.0;
        pedestrian(x0 + along, y_walk + across, dir > 0 ? 0.0 : kPi, vel);
      }
    }
  }

  // ---- vegetation and terrain ------------------------------------------------------
  // xy footprint of every object over the whole drive (moving ones swept), for keeping
  // vegetation clear of them.
  void collectFootprints() {
    const double t_end = std::max(1.0, d_.duration());
    for (const SceneObject& o : scene_.objects) {
      Eigen::AlignedBox3d b = scene_.objectBounds(o.instance_id, 0.0);
      if (o.velocity.norm() > 0.0) b.extend(scene_.objectBounds(o.instance_id, t_end));
      footprints_.emplace_back(b.min().head<2>(), b.max().head<2>());
    }
  }
  bool clear(const Eigen::AlignedBox2d& box, double margin) const {
    for (const auto& f : footprints_) {
      const double dx = std::max({0.0, f.min().x() - box.max().x(), box.min().x() - f.max().x()});
      const double dy = std::max({0.0, f.min().y() - box.max().y(), box.min().y() - f.max().y()});
      if (std::hypot(dx, dy) < margin) return false;
    }
    return true;
  }
  void reserve(const Eigen::AlignedBox2d& box) { footprints_.push_back(box); }
  static Eigen::AlignedBox2d boxXY(double x0, double x1, double y0, double y1) {
    return Eigen::AlignedBox2d(Eigen::Vector2d(std::min(x0, x1), std::min(y0, y1)),
                               Eigen::Vector2d(std::max(x0, x1), std::max(y0, y1)));
  }

  // Terrain tiles over [x0, x1] x [y0, y1] (y0 < y1), `step` above the paved ground, each
  // slightly raised and tilted (the grass and soil of a verge or a garden).
  void terrain(double x0, double x1, double y0, double y1, double step) {
    const VegetationParams& v = p_.vegetation;
    const double tile = v.terrain_tile_m;
    const int nx = std::max(1, static_cast<int>(std::round((x1 - x0) / tile)));
    const int ny = std::max(1, static_cast<int>(std::round((y1 - y0) / tile)));
    const double lx = (x1 - x0) / nx, ly = (y1 - y0) / ny;
    const double max_tilt = std::tan(v.terrain_tilt_deg * kPi / 180.0);
    for (int i = 0; i < nx; ++i) {
      for (int j = 0; j < ny; ++j) {
        const double ax = x0 + i * lx, bx = ax + lx, ay = y0 + j * ly, by = ay + ly;
        const double xm = 0.5 * (ax + bx), ym = 0.5 * (ay + by);
        const double top = ground(xm, ym) + step + veg_.uniform(0.0, v.terrain_roughness_m);
        const double sx = p_.slope + veg_.uniform(-max_tilt, max_tilt);
        const double sy = veg_.uniform(-max_tilt, max_tilt);
        scene_.addBackground(
            withMaterial(tiltedSlab(ax, bx, ay, by, top - sx * xm - sy * ym, sx, sy),
                         ObjectClass::kTerrain, kGrass));
      }
    }
  }

  // A bush of height h standing at (x, y) on ground raised by `step`, reaching at most r from
  // (x, y): two or three overlapping ellipsoids of different sizes (an irregular outline).
  std::uint32_t bush(double x, double y, double h, double r, double step) {
    const VegetationParams& v = p_.vegetation;
    const double gz = ground(x, y) + step;
    std::vector<Primitive> parts;
    const int n = veg_.integer(2, 3);
    for (int k = 0; k < n; ++k) {
      const double hk = k == 0 ? h : h * veg_.uniform(0.55, 0.85);
      const double off = k == 0 ? 0.0 : r * veg_.uniform(0.2, 0.45);
      const double rk = k == 0 ? r : (r - off) * veg_.uniform(0.6, 1.0);
      const double az = veg_.uniform(-kPi, kPi);
      // Sunk a little into the ground, the top at hk.
      const double cz = 0.5 * hk - 0.05;
      Primitive e =
          makeEllipsoid(Eigen::Vector3d(x + off * std::cos(az), y + off * std::sin(az), gz + cz),
                        Eigen::Vector3d(rk, rk * veg_.uniform(0.75, 1.0), 0.5 * hk + 0.05));
      e.rotation = Eigen::AngleAxisd(az, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      parts.push_back(porous(withMaterial(e, ObjectClass::kVegetation, kFoliage),
                             v.bush_transmission, v.bush_penetration_m));
    }
    Eigen::AlignedBox3d box;
    for (const Primitive& q : parts) box.extend(q.bounds());
    reserve(Eigen::AlignedBox2d(box.min().head<2>(), box.max().head<2>()));
    return add(ObjectClass::kVegetation, x, y, 0.0,
               {box.sizes().x(), box.sizes().y(), box.max().z() - ground(x, y)},
               Eigen::Vector3d::Zero(), parts);
  }

  // A trimmed hedge along x over [x0, x1] whose street-facing side is at |y| = y_front on
  // `side`, `width` deep, `height` tall above ground raised by `step`. Built of segments whose
  // height and width wander by a few centimetres; segments that would touch an object are left
  // out (the hedge then has a gap).
  void hedge(double x0, double x1, double y_front, int side, double width, double height,
             double step) {
    const VegetationParams& v = p_.vegetation;
    std::vector<Primitive> parts;
    double seg_x0 = x0;
    auto flush = [&]() {
      if (parts.empty()) return;
      Eigen::AlignedBox3d box;
      for (const Primitive& q : parts) box.extend(q.bounds());
      const Eigen::Vector3d c = box.center();
      add(ObjectClass::kVegetation, c.x(), c.y(), 0.0,
          {box.sizes().x(), box.sizes().y(), box.max().z() - ground(c.x(), c.y())},
          Eigen::Vector3d::Zero(), parts);
      parts.clear();
    };
    while (seg_x0 < x1 - 0.3) {
      const double seg_x1 = std::min(x1, seg_x0 + veg_.uniform(1.5, 3.5));
      const double w = std::max(0.3, width + veg_.uniform(-0.05, 0.05));
      const double h = std::max(0.3, height + veg_.uniform(-0.06, 0.06));
      const double ya = side * y_front, yb = side * (y_front + w);
      const Eigen::AlignedBox2d fp = boxXY(seg_x0, seg_x1, ya, yb);
      if (clear(fp, 0.1)) {
        const double xm = 0.5 * (seg_x0 + seg_x1), ym = 0.5 * (ya + yb);
        const double gz = ground(xm, ym);
        const double z0 = gz - 0.05, z1 = gz + step + h;
        // Along the slope the segment's bottom follows the lower end.
        const double dz = 0.5 * std::abs(p_.slope) * (seg_x1 - seg_x0);
        Primitive b = makeBox(Eigen::Vector3d(xm, ym, 0.5 * (z0 - dz + z1)),
                              Eigen::Vector3d(seg_x1 - seg_x0, w, z1 - (z0 - dz)), 0.0);
        parts.push_back(porous(withMaterial(b, ObjectClass::kVegetation, kFoliage),
                               v.hedge_transmission, v.hedge_penetration_m));
      } else {
        flush();  // an object stands here: the hedge is interrupted
      }
      seg_x0 = seg_x1;
    }
    flush();
    reserve(boxXY(x0, x1, side * y_front, side * (y_front + width)));
  }

  // A tree in a garden, its lobes leaning over the walkway.
  void gardenTree(double x, double y, int side) {
    const double trunk_h = veg_.uniform(2.6, 3.4);
    const double crown_r = veg_.uniform(1.8, 2.8);
    const double crown_h = veg_.uniform(1.5, 2.5);
    const double trunk_r = veg_.uniform(0.12, 0.22);
    treeObject(x, y, trunk_h, trunk_r, crown_r, crown_h, Eigen::Vector2d(0.0, -side));
    reserve(boxXY(x - 0.5, x + 0.5, y - 0.5, y + 0.5));
  }

  // A garden stretch [x0, x1] behind the sidewalk's back edge |y| = edge, `depth` deep.
  void garden(double x0, double x1, double edge, double depth, int side) {
    const VegetationParams& v = p_.vegetation;
    const double step = veg_.uniform(0.0, v.garden_step_max_m);
    terrain(x0, x1, side > 0 ? edge : -(edge + depth), side > 0 ? edge + depth : -edge, step);
    double front = edge;  // where the garden's free depth starts
    if (depth >= v.hedge_width_min_m + 0.1 && veg_.chance(v.hedge_probability)) {
      const double width =
          std::min(veg_.uniform(v.hedge_width_min_m, v.hedge_width_max_m), depth - 0.1);
      const double height = veg_.uniform(v.hedge_height_min_m, v.hedge_height_max_m);
      // Runs between entrance gaps.
      double x = x0 + 0.1;
      while (x < x1 - 0.6) {
        const double run_end =
            std::min(x1 - 0.1, x + v.hedge_gap_spacing_m * veg_.uniform(0.5, 1.5));
        hedge(x, run_end, edge + 0.05, side, width, height, step);
        x = run_end + veg_.uniform(1.0, 1.6);
      }
      front = edge + 0.05 + width;
    }
    const double room = edge + depth - front;  // free depth behind the hedge (or the edge)
    // Bushes: in front gardens wider than a bush, behind the hedge if any; an overgrown bush may
    // reach over the sidewalk's edge when there is no hedge.
    for (double x = x0 + veg_.uniform(0.3, v.bush_spacing_m); x < x1 - 0.3;
         x += v.bush_spacing_m * veg_.uniform(0.5, 1.5)) {
      const double h = veg_.uniform(v.bush_height_min_m, v.bush_height_max_m);
      const double r = std::min(1.2, veg_.uniform(0.35, 0.6) * h + 0.15);
      const double lo = front + std::min(0.7 * r, 0.5 * room), hi = front + room - 0.3 * r;
      if (room < 0.6 || hi < lo) continue;
      const double y = side * veg_.uniform(lo, hi);
      if (!clear(boxXY(x - r, x + r, y - r, y + r), 0.15)) continue;
      bush(x, y, h, r, step);
    }
    if (depth >= 2.5 && x1 - x0 >= 4.0) {
      for (double x = x0 + veg_.uniform(1.5, 0.5 * v.garden_tree_spacing_m); x < x1 - 1.5;
           x += v.garden_tree_spacing_m * veg_.uniform(0.6, 1.4)) {
        const double y = side * (edge + veg_.uniform(1.5, std::min(depth - 0.5, 3.5)));
        if (!clear(boxXY(x - 0.5, x + 0.5, y - 0.5, y + 0.5), 0.3)) continue;
        gardenTree(x, y, side);
      }
    }
  }

  // Shrubs against a facade whose front (|y| = front) stands on the sidewalk.
  void facadeShrubs(double x0, double x1, double front, int side) {
    const VegetationParams& v = p_.vegetation;
    for (double x = x0 + veg_.uniform(0.5, v.facade_shrub_spacing_m); x < x1 - 0.5;
         x += v.facade_shrub_spacing_m * veg_.uniform(0.5, 1.5)) {
      const double r = veg_.uniform(0.3, 0.45);
      const double y = side * (front - r);
      if (!clear(boxXY(x - r, x + r, y - r, y + r), 0.15)) continue;
      bush(x, y, veg_.uniform(0.5, 1.2), r, 0.0);
    }
  }

  void vegetation() {
    const VegetationParams& v = p_.vegetation;
    collectFootprints();
    for (std::size_t i = 0; i < spans_.size(); ++i) {
      const SectionSpan& sp = spans_[i];
      const StreetSection& sec = *sp.s;
      if (sec.type != StreetSection::Type::kStreet) continue;
      const double w = sec.road_half_width_m, edge = w + sec.sidewalk_width_m;
      for (int side : {-1, 1}) {
        // Grass verge beside the curb, with a few shrubs between the street furniture.
        if (sec.furniture && sec.sidewalk_width_m >= v.verge_offset_m + v.verge_width_m + 1.5 &&
            veg_.chance(v.verge_probability)) {
          const double a = w + v.verge_offset_m, b = a + v.verge_width_m;
          const double vx0 = sp.x0 + 0.5, vx1 = sp.x1 - 0.5;
          terrain(vx0, vx1, side > 0 ? a : -b, side > 0 ? b : -a,
                  veg_.uniform(0.0, v.verge_step_max_m));
          for (double x = vx0 + veg_.uniform(1.0, v.verge_bush_spacing_m); x < vx1 - 1.0;
               x += v.verge_bush_spacing_m * veg_.uniform(0.5, 1.5)) {
            const double r = 0.5 * v.verge_width_m - 0.05;
            const double y = side * 0.5 * (a + b);
            if (r < 0.2 || !clear(boxXY(x - r, x + r, y - r, y + r), 0.3)) continue;
            bush(x, y, veg_.uniform(0.5, 1.0), r, 0.0);
          }
        }
        // Gardens wherever no building front stands on the facade line: open sides, gaps
        // between buildings, the corners at intersections, and setbacks (up to the building).
        const bool built = side > 0 ? sec.buildings_left : sec.buildings_right;
        const double gx0 = sp.x0 + 1.0, gx1 = sp.x1 - 1.0;
        double cursor = gx0;
        if (built) {
          for (const Facade& f : facades_) {
            if (f.section != sp.index || f.side != side) continue;
            if (f.x0 - cursor >= 1.5) garden(cursor, f.x0, edge, v.garden_depth_m, side);
            const double recess = std::abs(f.y) - edge;
            const double fx0 = std::max(f.x0, gx0), fx1 = std::min(f.x1, gx1);
            if (recess >= 0.5 && fx1 - fx0 >= 1.5) {
              garden(fx0, fx1, edge, recess - 0.05, side);
            } else if (recess < 0.5 && sec.sidewalk_width_m >= 2.0) {
              facadeShrubs(fx0, fx1, std::abs(f.y), side);
            }
            cursor = std::max(cursor, f.x1);
          }
        }
        if (gx1 - cursor >= 1.5) garden(cursor, gx1, edge, v.garden_depth_m, side);
      }
    }
  }

  // Fig. 4 / Fig. 7: close objects the coarse grid merges.
  void hardCases() {
    // A pedestrian 0.3 m beside the traffic side of parked cars (getting in).
    for (std::size_t k = 1; k < parked_.size(); k += 7) {
      const SceneObject& c = scene_.objects[parked_[k] - 1];
      const double side = c.position.y() > 0 ? 1.0 : -1.0;
      const double y = c.position.y() - side * (0.5 * c.size.y() + 0.3 + 0.2);
      pedestrian(c.position.x() + 0.6, y, side > 0 ? kPi : 0.0, Eigen::Vector3d::Zero());
    }
    // Objects touching a facade (distance 0) and 0.4 m from each other.
    int done = 0;
    for (const Facade& f : facades_) {
      if (f.x1 - f.x0 < 8.0 || done >= 3) continue;
      const double x = 0.5 * (f.x0 + f.x1);
      const double y_bin = f.y - f.side * 0.3;
      if (!free(x, y_bin, 0.3)) continue;
      bin(x, y_bin);
      // Bench against the wall 0.4 m beside the bin (back touching the facade).
      const double y_bench = f.y - f.side * 0.25;
      bench(x + 0.3 + 0.4 + 0.9, y_bench, f.side > 0 ? kPi : 0.0);
      occupy(x + 0.8, y_bin, 1.3);
      ++done;
    }
    // A group of three standing 0.4 m apart at the curb.
    for (const SectionSpan& sp : spans_) {
      if (sp.s->type != StreetSection::Type::kStreet || sp.s->sidewalk_width_m < 2.0) continue;
      const double y = -(sp.s->road_half_width_m + 1.15);
      for (double x = sp.x0 + 0.5 * (sp.x1 - sp.x0); x < sp.x1 - 5.0; x += 1.0) {
        if (!free(x, y, 0.3) || !free(x + 1.6, y, 0.3)) continue;
        for (int k = 0; k < 3; ++k) {
          pedestrian(x + k * 0.8, y, kPi / 2, Eigen::Vector3d::Zero());  // 0.8 - 0.4 = 0.4 m gap
        }
        occupy(x + 0.8, y, 1.2);
        break;
      }
      break;
    }
  }

  struct Facade {
    double x0, x1, y;
    int side, section;
  };
  const SceneParams& p_;
  const DriveParams& d_;
  Rng rng_;
  Rng veg_;  // vegetation and terrain
  Rng mat_;  // materials that are not drawn with their object
  std::vector<SectionSpan> spans_;
  std::vector<Eigen::AlignedBox2d> footprints_;  // xy of objects, to keep vegetation clear
  Scene scene_;
  std::vector<Facade> facades_;
  std::vector<std::uint32_t> parked_;
  std::vector<Eigen::Vector3d> placed_;  // x, y, radius of placed furniture
};

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

double DriveParams::length() const {
  double l = 0.0;
  for (std::size_t i = 1; i < waypoints.size(); ++i) l += (waypoints[i] - waypoints[i - 1]).norm();
  return l;
}

double DriveParams::duration() const {
  return speed_mps > 0.0 ? length() / speed_mps : 0.0;
}

void DriveParams::at(double t_s, Eigen::Vector2d* xy, double* yaw_rad) const {
  double s = std::max(0.0, speed_mps * t_s);
  for (std::size_t i = 1; i < waypoints.size(); ++i) {
    const Eigen::Vector2d seg = waypoints[i] - waypoints[i - 1];
    const double l = seg.norm();
    if (l <= 0.0) continue;
    *yaw_rad = std::atan2(seg.y(), seg.x());
    if (s <= l || i + 1 == waypoints.size()) {
      *xy = waypoints[i - 1] + seg * (std::min(s, l) / l);
      return;
    }
    s -= l;
  }
  *xy = waypoints.front();
  *yaw_rad = 0.0;
}

std::vector<StreetSection> SceneParams::defaultSections() {
  std::vector<StreetSection> s(5);
  s[0].length_m = 70.0;
  s[1].type = StreetSection::Type::kIntersection;
  s[1].length_m = 14.0;
  s[2].length_m = 50.0;
  s[2].sidewalk_width_m = 5.0;
  s[2].buildings_right = false;
  s[3].length_m = 45.0;
  s[3].road_half_width_m = 2.7;
  s[3].sidewalk_width_m = 0.8;
  s[3].parking = false;
  s[3].furniture = false;
  s[4].length_m = 80.0;
  return s;
}

void validate(const SceneParams& p) {
  const std::string range =
      checkFieldRanges(p, [](const std::string& name) { return "scene/" + name; });
  require(range.empty(), range);
  require(!p.sections.empty(), "scene/sections: at least one section is required");
  const BuildingParams& b = p.buildings;
  require(b.length_max_m >= b.length_min_m, "scene/buildings: need length_min_m <= length_max_m");
  require(b.height_max_m >= b.height_min_m, "scene/buildings: need height_min_m <= height_max_m");
  require(b.gap_max_m >= b.gap_min_m, "scene/buildings: need gap_min_m <= gap_max_m");
  const StreetObjectParams& o = p.objects;
  require(o.parked_gap_max_m >= o.parked_gap_min_m,
          "scene/objects: need parked_gap_min_m <= parked_gap_max_m");
  const VegetationParams& v = p.vegetation;
  require(v.hedge_height_max_m >= v.hedge_height_min_m,
          "scene/vegetation: need hedge_height_min_m <= hedge_height_max_m");
  require(v.hedge_width_max_m >= v.hedge_width_min_m,
          "scene/vegetation: need hedge_width_min_m <= hedge_width_max_m");
  require(v.bush_height_max_m >= v.bush_height_min_m,
          "scene/vegetation: need bush_height_min_m <= bush_height_max_m");
  require(v.canopy_lobes_max >= v.canopy_lobes_min,
          "scene/vegetation: need canopy_lobes_min <= canopy_lobes_max");
  require(v.canopy_clearance_max_m >= v.canopy_clearance_min_m,
          "scene/vegetation: need canopy_clearance_min_m <= canopy_clearance_max_m");
}

void validate(const DriveParams& d) {
  const std::string range =
      checkFieldRanges(d, [](const std::string& name) { return "drive/" + name; });
  require(range.empty(), range);
  require(d.waypoints.size() >= 2, "drive/waypoints: at least two [x, y] points are required");
  require(d.length() > 0.0, "drive/waypoints: the path must have a non-zero length");
}

Scene generateScene(const SceneParams& scene, const DriveParams& drive) {
  validate(scene);
  validate(drive);
  return Generator(scene, drive).run();
}

double groundHeight(const SceneParams& p, double x, double y) {
  const std::vector<SectionSpan> sp = spans(p);
  const SectionSpan& s = spanAt(sp, x);
  const double w = s.s->road_half_width_m;
  const double base = p.slope * x;
  if (std::abs(y) <= w) return base - p.camber * std::abs(y);
  if (s.s->type == StreetSection::Type::kIntersection) return base - p.camber * w;
  return base - p.camber * w + p.curb_height_m;
}

}  // namespace core
}  // namespace urban_detection
