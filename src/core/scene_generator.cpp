#include "urban_detection/core/scene_generator.h"

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
  p.half_extents = Eigen::Vector3d(0.5 * (x1 - x0) * std::sqrt(1.0 + sx * sx),
                                   0.5 * (y1 - y0) * std::sqrt(1.0 + sy * sy),
                                   0.5 * kSlabThickness);
  p.object_class = ObjectClass::kGround;
  return p;
}

Primitive withClass(Primitive p, ObjectClass c, float reflectivity) {
  p.object_class = c;
  p.reflectivity = reflectivity;
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
  Generator(const SceneParams& p, const DriveParams& d)
      : p_(p), d_(d), rng_(p.seed), spans_(spans(p)) {}

  Scene run() {
    background();
    vehicles();
    furniture();
    people();
    if (p_.objects.hard_cases) hardCases();
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
      scene_.addBackground(withClass(tiltedSlab(sp.x0, sp.x1, 0.0, w, 0.0, s, -c),
                                     ObjectClass::kGround, 0.12f));
      scene_.addBackground(withClass(tiltedSlab(sp.x0, sp.x1, -w, 0.0, 0.0, s, c),
                                     ObjectClass::kGround, 0.12f));
      if (sec.type == StreetSection::Type::kIntersection) {
        // Cross road at the main road's edge height, out to the terrain width.
        const double far = w + p_.sections[i].sidewalk_width_m + p_.terrain_width_m;
        for (int side : {-1, 1}) {
          const double y0 = side > 0 ? w : -far, y1 = side > 0 ? far : -w;
          scene_.addBackground(withClass(tiltedSlab(sp.x0, sp.x1, y0, y1, -c * w, s, 0.0),
                                         ObjectClass::kGround, 0.12f));
        }
        continue;
      }
      // Sidewalk + terrain on each side: its road-facing side is the curb.
      const double top = p_.curb_height_m - c * w;
      const double far = w + sec.sidewalk_width_m + p_.terrain_width_m;
      scene_.addBackground(withClass(tiltedSlab(sp.x0, sp.x1, w, far, top, s, 0.0),
                                     ObjectClass::kGround, 0.25f));
      scene_.addBackground(withClass(tiltedSlab(sp.x0, sp.x1, -far, -w, top, s, 0.0),
                                     ObjectClass::kGround, 0.25f));
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
      const double recess = rng_.chance(b.recess_probability) ? rng_.uniform(0.5, b.recess_max_m) : 0.0;
      const double height = rng_.uniform(b.height_min_m, b.height_max_m);
      const double y_front = facade + recess;
      const double zb = std::min(ground(x, side * y_front), ground(x + len, side * y_front)) - 1.0;
      const double zt = std::max(ground(x, side * y_front), ground(x + len, side * y_front)) + height;
      Primitive wall = makeBox(Eigen::Vector3d(x + 0.5 * len, side * (y_front + 0.5 * b.depth_m),
                                               0.5 * (zb + zt)),
                               Eigen::Vector3d(len, b.depth_m, zt - zb), 0.0);
      scene_.addBackground(withClass(wall, ObjectClass::kWall, 0.35f));
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
    const float refl = static_cast<float>(rng_.uniform(0.15, 0.7));  // paint colour
    std::vector<Primitive> parts;
    double l, wd, h;
    if (van) {
      l = rng_.uniform(4.8, 5.4), wd = 2.0, h = 2.2;
      parts.push_back(withClass(pl.box(0, 0, 0.3 + 0.5, l, wd, 1.0), ObjectClass::kVan, refl));
      parts.push_back(withClass(pl.box(-0.35, 0, 1.3 + 0.45, l - 0.8, wd - 0.1, 0.9),
                                ObjectClass::kVan, refl));
    } else {
      l = rng_.uniform(4.0, 4.7), wd = rng_.uniform(1.7, 1.85), h = 1.45;
      parts.push_back(withClass(pl.box(0, 0, 0.25 + 0.35, l, wd, 0.7), ObjectClass::kCar, refl));
      parts.push_back(withClass(pl.box(-0.2, 0, 0.95 + 0.25, 0.55 * l, wd - 0.15, 0.5),
                                ObjectClass::kCar, refl));
    }
    return add(van ? ObjectClass::kVan : ObjectClass::kCar, x, y, yaw, {l, wd, h}, v, parts);
  }

  std::uint32_t pedestrian(double x, double y, double yaw, const Eigen::Vector3d& v,
                           double scale = -1.0) {
    if (scale <= 0.0) scale = rng_.uniform(0.9, 1.08);
    const Placer pl = placer(x, y, yaw);
    const float refl = static_cast<float>(rng_.uniform(0.1, 0.5));
    std::vector<Primitive> parts;
    parts.push_back(withClass(pl.box(0, 0, 0.42 * scale, 0.28 * scale, 0.36 * scale, 0.84 * scale),
                              ObjectClass::kPedestrian, refl));
    Primitive torso = makeCylinder(pl.at(0, 0, 1.14 * scale), 0.2 * scale, 0.6 * scale);
    parts.push_back(withClass(torso, ObjectClass::kPedestrian, refl));
    Primitive head = makeEllipsoid(pl.at(0, 0, 1.57 * scale), Eigen::Vector3d::Constant(0.11 * scale));
    parts.push_back(withClass(head, ObjectClass::kPedestrian, refl));
    return add(ObjectClass::kPedestrian, x, y, yaw, Eigen::Vector3d(0.4, 0.4, 1.68) * scale, v,
               parts);
  }

  std::uint32_t cyclist(double x, double y, double yaw, const Eigen::Vector3d& v) {
    const Placer pl = placer(x, y, yaw);
    const float refl = static_cast<float>(rng_.uniform(0.2, 0.5));
    std::vector<Primitive> parts;
    parts.push_back(withClass(pl.box(0, 0, 0.5, 1.75, 0.12, 0.95), ObjectClass::kCyclist, refl));
    parts.push_back(withClass(pl.box(0.05, 0, 0.85, 0.3, 0.32, 0.4), ObjectClass::kCyclist, refl));
    Primitive torso = makeCylinder(pl.at(-0.05, 0, 1.3), 0.19, 0.55);
    parts.push_back(withClass(torso, ObjectClass::kCyclist, refl));
    Primitive head = makeEllipsoid(pl.at(0.05, 0, 1.7), Eigen::Vector3d::Constant(0.12));
    parts.push_back(withClass(head, ObjectClass::kCyclist, refl));
    return add(ObjectClass::kCyclist, x, y, yaw, {1.75, 0.4, 1.82}, v, parts);
  }

  std::uint32_t tree(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    const double trunk_h = rng_.uniform(2.4, 3.2);
    const double crown_r = rng_.uniform(1.4, 2.4);
    const double crown_h = rng_.uniform(1.5, 2.5);
    std::vector<Primitive> parts;
    parts.push_back(withClass(makeCylinder(pl.at(0, 0, 0.5 * trunk_h + 0.3), rng_.uniform(0.12, 0.2),
                                           trunk_h + 0.6),
                              ObjectClass::kTrunk, 0.3f));
    parts.push_back(withClass(makeEllipsoid(pl.at(0, 0, trunk_h + crown_h),
                                            Eigen::Vector3d(crown_r, crown_r, crown_h)),
                              ObjectClass::kVegetation, 0.45f));
    return add(ObjectClass::kVegetation, x, y, 0.0,
               {2 * crown_r, 2 * crown_r, trunk_h + 2.0 * crown_h}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t pole(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    const double h = rng_.uniform(4.5, 7.0);
    std::vector<Primitive> parts;
    parts.push_back(withClass(makeCylinder(pl.at(0, 0, 0.5 * h - 0.2), 0.08, h + 0.4),
                              ObjectClass::kPole, 0.4f));
    const double arm = y > 0 ? -0.6 : 0.6;  // lamp head over the road
    parts.push_back(withClass(pl.box(0, arm, h - 0.1, 0.35, 1.3, 0.18), ObjectClass::kPole, 0.4f));
    return add(ObjectClass::kPole, x, y, 0.0, {0.35, 1.5, h}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t sign(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    std::vector<Primitive> parts;
    parts.push_back(withClass(makeCylinder(pl.at(0, 0, 1.2), 0.04, 2.8), ObjectClass::kPole, 0.4f));
    // Plate facing the traffic (normal along x), retro-reflective.
    parts.push_back(withClass(pl.box(0.07, 0, 2.35, 0.06, 0.65, 0.65), ObjectClass::kSign, 0.95f));
    return add(ObjectClass::kSign, x, y, 0.0, {0.1, 0.65, 2.7}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t bin(double x, double y) {
    const Placer pl = placer(x, y, 0.0);
    std::vector<Primitive> parts;
    const double h = rng_.uniform(0.9, 1.2);
    parts.push_back(withClass(makeCylinder(pl.at(0, 0, 0.5 * h), 0.3, h), ObjectClass::kBin, 0.3f));
    return add(ObjectClass::kBin, x, y, 0.0, {0.6, 0.6, h}, Eigen::Vector3d::Zero(), parts);
  }

  std::uint32_t bench(double x, double y, double yaw) {
    const Placer pl = placer(x, y, yaw);
    std::vector<Primitive> parts;
    parts.push_back(withClass(pl.box(0, 0, 0.45, 1.8, 0.5, 0.08), ObjectClass::kBench, 0.3f));
    parts.push_back(withClass(pl.box(0, -0.22, 0.72, 1.8, 0.06, 0.45), ObjectClass::kBench, 0.3f));
    parts.push_back(withClass(pl.box(-0.75, 0, 0.21, 0.08, 0.45, 0.42), ObjectClass::kBench, 0.3f));
    parts.push_back(withClass(pl.box(0.75, 0, 0.21, 0.08, 0.45, 0.42), ObjectClass::kBench, 0.3f));
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
        const auto& s = sides[static_cast<std::size_t>(rng_.integer(0, static_cast<int>(sides.size()) - 1))];
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
      const SectionSpan& sp = *walks[static_cast<std::size_t>(rng_.integer(0, static_cast<int>(walks.size()) - 1))];
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
      const double y_walk = side * (sec.road_half_width_m + std::max(0.4, frac * sec.sidewalk_width_m));
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
  std::vector<SectionSpan> spans_;
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

double DriveParams::duration() const { return speed_mps > 0.0 ? length() / speed_mps : 0.0; }

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
  require(!p.sections.empty(), "scene.sections: at least one section is required");
  for (std::size_t i = 0; i < p.sections.size(); ++i) {
    const StreetSection& s = p.sections[i];
    const std::string n = "scene.sections[" + std::to_string(i) + "].";
    require(s.length_m >= 5.0 && s.length_m <= 2000.0, n + "length_m must be in [5, 2000] m");
    require(s.road_half_width_m >= 2.0 && s.road_half_width_m <= 20.0,
            n + "road_half_width_m must be in [2, 20] m");
    require(s.sidewalk_width_m >= 0.5 && s.sidewalk_width_m <= 20.0,
            n + "sidewalk_width_m must be in [0.5, 20] m");
  }
  require(std::abs(p.slope) <= 0.15, "scene.slope must be in [-0.15, 0.15]");
  require(p.camber >= 0.0 && p.camber <= 0.08, "scene.camber must be in [0, 0.08]");
  require(p.curb_height_m >= 0.0 && p.curb_height_m <= 0.4, "scene.curb_height_m must be in [0, 0.4] m");
  require(p.terrain_width_m >= 1.0 && p.terrain_width_m <= 200.0,
          "scene.terrain_width_m must be in [1, 200] m");
  const BuildingParams& b = p.buildings;
  require(b.length_min_m >= 2.0 && b.length_max_m >= b.length_min_m,
          "scene.buildings: need 2 <= length_min_m <= length_max_m");
  require(b.height_min_m >= 2.0 && b.height_max_m >= b.height_min_m,
          "scene.buildings: need 2 <= height_min_m <= height_max_m");
  require(b.gap_min_m > 0.0 && b.gap_max_m >= b.gap_min_m,
          "scene.buildings: need 0 < gap_min_m <= gap_max_m");
  require(b.depth_m >= 1.0 && b.recess_max_m >= 0.5, "scene.buildings: depth_m >= 1, recess_max_m >= 0.5");
  const StreetObjectParams& o = p.objects;
  require(o.parked_gap_min_m > 0.0 && o.parked_gap_max_m >= o.parked_gap_min_m,
          "scene.objects: need 0 < parked_gap_min_m <= parked_gap_max_m");
  require(o.moving_cars >= 0 && o.pedestrians >= 0 && o.cyclists >= 0 && o.signs >= 0 &&
              o.bins >= 0 && o.benches >= 0,
          "scene.objects: object counts must be >= 0");
  require(o.tree_spacing_m >= 3.0 && o.pole_spacing_m >= 3.0,
          "scene.objects: tree_spacing_m and pole_spacing_m must be >= 3 m");
  require(o.pedestrians <= 1000 && o.moving_cars <= 1000 && o.cyclists <= 1000,
          "scene.objects: at most 1000 objects of a kind");
}

void validate(const DriveParams& d) {
  require(d.waypoints.size() >= 2, "drive.waypoints: at least two [x, y] points are required");
  for (const auto& w : d.waypoints) {
    require(w.allFinite(), "drive.waypoints: coordinates must be finite");
  }
  require(d.length() > 0.0, "drive.waypoints: the path must have a non-zero length");
  require(d.speed_mps >= 0.0 && d.speed_mps <= 40.0, "drive.speed_mps must be in [0, 40] m/s");
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
