#include "urban_detection/core/simulation/sim_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace urban_detection {
namespace core {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Entry parameter of the ray into the slab |o + t d| <= h along one axis, updating the
// running interval [t_near, t_far]; false if the interval becomes empty.
inline bool clipSlab(double o, double d, double h, double* t_near, double* t_far) {
  if (std::abs(d) < 1e-15) return std::abs(o) <= h;
  const double inv = 1.0 / d;
  double t1 = (-h - o) * inv;
  double t2 = (h - o) * inv;
  if (t1 > t2) std::swap(t1, t2);
  *t_near = std::max(*t_near, t1);
  *t_far = std::min(*t_far, t2);
  return *t_near <= *t_far;
}

}  // namespace

Eigen::AlignedBox3d Primitive::bounds(double t_s) const {
  const Eigen::Vector3d c = center + velocity * t_s;
  Eigen::Vector3d h = half_extents;
  if (shape == PrimitiveShape::kCylinder) h.y() = h.x();
  // Extent of the rotated local box along each world axis; for the ellipsoid this bounds the
  // exact (smaller) extent.
  const Eigen::Vector3d e = rotation.cwiseAbs() * h;
  return Eigen::AlignedBox3d(c - e, c + e);
}

namespace {

// The body of Primitive::span, inlined into intersect() (the ray caster's inner loop).
inline bool spanOf(const Primitive& p, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                   double t_s, double* t_in, double* t_out) {
  const Eigen::Vector3d o = p.rotation.transpose() * (origin - p.center - p.velocity * t_s);
  const Eigen::Vector3d d = p.rotation.transpose() * dir;
  const Eigen::Vector3d& h = p.half_extents;
  double t_near = -kInf, t_far = kInf;
  switch (p.shape) {
    case PrimitiveShape::kBox: {
      if (!clipSlab(o.x(), d.x(), h.x(), &t_near, &t_far)) return false;
      if (!clipSlab(o.y(), d.y(), h.y(), &t_near, &t_far)) return false;
      if (!clipSlab(o.z(), d.z(), h.z(), &t_near, &t_far)) return false;
      break;
    }
    case PrimitiveShape::kCylinder: {
      if (!clipSlab(o.z(), d.z(), h.z(), &t_near, &t_far)) return false;
      const double a = d.x() * d.x() + d.y() * d.y();
      const double b = o.x() * d.x() + o.y() * d.y();  // half of the usual b
      const double c = o.x() * o.x() + o.y() * o.y() - h.x() * h.x();
      if (a < 1e-15) {
        if (c > 0.0) return false;
      } else {
        const double disc = b * b - a * c;
        if (disc < 0.0) return false;
        const double s = std::sqrt(disc);
        t_near = std::max(t_near, (-b - s) / a);
        t_far = std::min(t_far, (-b + s) / a);
        if (t_near > t_far) return false;
      }
      break;
    }
    case PrimitiveShape::kEllipsoid: {
      const Eigen::Vector3d os = o.cwiseQuotient(h);
      const Eigen::Vector3d ds = d.cwiseQuotient(h);
      const double a = ds.squaredNorm();
      const double b = os.dot(ds);
      const double c = os.squaredNorm() - 1.0;
      const double disc = b * b - a * c;
      if (disc < 0.0 || a < 1e-30) return false;
      const double s = std::sqrt(disc);
      t_near = (-b - s) / a;
      t_far = (-b + s) / a;
      break;
    }
  }
  *t_in = t_near;
  *t_out = t_far;
  return true;
}

}  // namespace

bool Primitive::span(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_s,
                     double* t_in, double* t_out) const {
  return spanOf(*this, origin, dir, t_s, t_in, t_out);
}

double Primitive::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_s,
                            double t_min) const {
  double t_in, t_out;
  if (!spanOf(*this, origin, dir, t_s, &t_in, &t_out)) return -1.0;
  return t_in > t_min ? t_in : -1.0;
}

bool Primitive::contains(const Eigen::Vector3d& p, double t_s, double margin_m) const {
  const Eigen::Vector3d q = rotation.transpose() * (p - center - velocity * t_s);
  const Eigen::Vector3d& h = half_extents;
  switch (shape) {
    case PrimitiveShape::kBox:
      return (q.cwiseAbs() - h).maxCoeff() <= margin_m;
    case PrimitiveShape::kCylinder:
      return std::hypot(q.x(), q.y()) <= h.x() + margin_m && std::abs(q.z()) <= h.z() + margin_m;
    case PrimitiveShape::kEllipsoid: {
      const Eigen::Vector3d g = h + Eigen::Vector3d::Constant(margin_m);
      return q.cwiseQuotient(g).squaredNorm() <= 1.0;
    }
  }
  return false;
}

Primitive makeBox(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw_rad) {
  Primitive p;
  p.shape = PrimitiveShape::kBox;
  p.center = center;
  p.rotation = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.half_extents = 0.5 * size;
  return p;
}

Primitive makeCylinder(const Eigen::Vector3d& center, double radius_m, double height_m) {
  Primitive p;
  p.shape = PrimitiveShape::kCylinder;
  p.center = center;
  p.half_extents = Eigen::Vector3d(radius_m, radius_m, 0.5 * height_m);
  return p;
}

Primitive makeEllipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& semi_axes) {
  Primitive p;
  p.shape = PrimitiveShape::kEllipsoid;
  p.center = center;
  p.half_extents = semi_axes;
  return p;
}

std::uint32_t Scene::addObject(SceneObject object, const std::vector<Primitive>& parts) {
  object.instance_id = static_cast<std::uint32_t>(objects.size() + 1);
  object.first_primitive = static_cast<std::uint32_t>(primitives.size());
  object.num_primitives = static_cast<std::uint32_t>(parts.size());
  for (Primitive p : parts) {
    p.instance_id = object.instance_id;
    p.velocity = object.velocity;
    primitives.push_back(p);
  }
  objects.push_back(object);
  return object.instance_id;
}

void Scene::addBackground(Primitive primitive) {
  primitive.instance_id = 0;
  primitives.push_back(primitive);
}

Eigen::AlignedBox3d Scene::objectBounds(std::uint32_t id, double t_s) const {
  const SceneObject& o = objects.at(id - 1);
  Eigen::AlignedBox3d box;
  for (std::uint32_t i = 0; i < o.num_primitives; ++i) {
    box.extend(primitives[o.first_primitive + i].bounds(t_s));
  }
  return box;
}

// ---------------------------------------------------------------------------------------------

RayCaster::RayCaster(const Scene& scene, const RayCasterParams& params)
    : scene_(scene), params_(params) {
  if (!(params_.cell_m > 0.05) || !std::isfinite(params_.cell_m)) params_.cell_m = 2.0;
  Eigen::AlignedBox3d all;
  for (const Primitive& p : scene_.primitives) all.extend(p.bounds(0.0));
  if (all.isEmpty()) all = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  // Moving objects may leave the static extent; a margin keeps them visible for a while.
  const double margin = 20.0;
  x0_ = all.min().x() - margin;
  y0_ = all.min().y() - margin;
  const double sx = all.sizes().x() + 2 * margin;
  const double sy = all.sizes().y() + 2 * margin;
  // Cap the cell count (a huge scene gets coarser cells rather than a huge table).
  while ((sx / params_.cell_m) * (sy / params_.cell_m) > 4e6) params_.cell_m *= 2.0;
  nx_ = std::max(1, static_cast<int>(std::ceil(sx / params_.cell_m)));
  ny_ = std::max(1, static_cast<int>(std::ceil(sy / params_.cell_m)));
  static_z_max_ = all.max().z();

  // Static primitives are binned as groups: the consecutive primitives of one object (a car's
  // body, cabin, plates and lamps; a tree's trunk and crown lobes), or up to kTerrainGroup
  // consecutive terrain tiles (a stretch of a verge or garden), share one box, so a ray that
  // misses the box skips them all. Other background primitives are groups of their own.
  constexpr std::uint32_t kTerrainGroup = 8;
  std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(nx_) * ny_);
  for (std::uint32_t i = 0; i < scene_.primitives.size(); ++i) {
    const Primitive& p = scene_.primitives[i];
    if (p.moving()) {
      moving_prims_.push_back(i);
      continue;
    }
    const bool terrain = p.instance_id == 0 && p.object_class == ObjectClass::kTerrain;
    if ((p.instance_id != 0 || terrain) && !groups_.empty()) {
      Group& g = groups_.back();
      const Primitive& last = scene_.primitives[g.first + g.count - 1];
      const bool same = p.instance_id != 0
                            ? last.instance_id == p.instance_id
                            : last.instance_id == 0 && last.object_class == ObjectClass::kTerrain &&
                                  g.count < kTerrainGroup;
      if (g.first + g.count == i && same) {
        ++g.count;
        g.box.extend(p.bounds(0.0));
        continue;
      }
    }
    groups_.push_back(Group{i, 1, p.bounds(0.0)});
  }
  for (std::uint32_t g = 0; g < groups_.size(); ++g) binInto(groups_[g].box, g, &cells);
  group_mailbox_.assign(groups_.size(), 0);
  static_start_.assign(cells.size() + 1, 0);
  for (std::size_t c = 0; c < cells.size(); ++c) {
    static_start_[c + 1] = static_start_[c] + static_cast<std::uint32_t>(cells[c].size());
  }
  static_items_.reserve(static_start_.back());
  for (const auto& c : cells) static_items_.insert(static_items_.end(), c.begin(), c.end());
  moving_start_.assign(cells.size() + 1, 0);
  mailbox_.assign(scene_.primitives.size(), 0);
  setTimeWindow(0.0, 0.0);
}

void RayCaster::binInto(const Eigen::AlignedBox3d& box, std::uint32_t prim,
                        std::vector<std::vector<std::uint32_t>>* cells) const {
  const int ix0 = std::max(0, static_cast<int>(std::floor((box.min().x() - x0_) / params_.cell_m)));
  const int iy0 = std::max(0, static_cast<int>(std::floor((box.min().y() - y0_) / params_.cell_m)));
  const int ix1 =
      std::min(nx_ - 1, static_cast<int>(std::floor((box.max().x() - x0_) / params_.cell_m)));
  const int iy1 =
      std::min(ny_ - 1, static_cast<int>(std::floor((box.max().y() - y0_) / params_.cell_m)));
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      (*cells)[static_cast<std::size_t>(iy) * nx_ + ix].push_back(prim);
    }
  }
}

void RayCaster::setTimeWindow(double t0_s, double t1_s) {
  window_t0_ = std::min(t0_s, t1_s);
  window_t1_ = std::max(t0_s, t1_s);
  std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(nx_) * ny_);
  z_max_ = static_z_max_;
  for (std::uint32_t i : moving_prims_) {
    const Primitive& p = scene_.primitives[i];
    Eigen::AlignedBox3d swept = p.bounds(window_t0_);
    swept.extend(p.bounds(window_t1_));
    binInto(swept, i, &cells);
    z_max_ = std::max(z_max_, swept.max().z());
  }
  moving_start_[0] = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    moving_start_[c + 1] = moving_start_[c] + static_cast<std::uint32_t>(cells[c].size());
  }
  moving_items_.clear();
  for (const auto& c : cells) moving_items_.insert(moving_items_.end(), c.begin(), c.end());
}

bool RayCaster::testCell(int cell, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                         double t_s, RayHit* best) {
  bool improved = false;
  auto hit = [&](std::uint32_t prim) {
    const double t = scene_.primitives[prim].intersect(origin, dir, t_s);
    if (t > 0.0 && t < best->distance_m) {
      best->distance_m = t;
      best->primitive = prim;
      improved = true;
    }
  };
  auto test = [&](std::uint32_t prim) {
    if (mailbox_[prim] == ray_id_) return;
    mailbox_[prim] = ray_id_;
    hit(prim);
  };
  for (std::uint32_t k = static_start_[cell]; k < static_start_[cell + 1]; ++k) {
    const std::uint32_t gi = static_items_[k];
    if (group_mailbox_[gi] == ray_id_) continue;
    group_mailbox_[gi] = ray_id_;
    const Group& g = groups_[gi];
    if (g.count > 1) {
      // Skip the group when the ray misses its box or enters it beyond the best hit.
      double t_near = 0.0, t_far = best->distance_m;
      bool in = true;
      for (int a = 0; a < 3 && in; ++a) {
        const double o = origin[a] - g.box.center()[a];
        const double h = 0.5 * (g.box.max()[a] - g.box.min()[a]) + 1e-9;
        in = clipSlab(o, dir[a], h, &t_near, &t_far);
      }
      if (!in) continue;
    }
    for (std::uint32_t q = g.first; q < g.first + g.count; ++q) hit(q);
  }
  for (std::uint32_t k = moving_start_[cell]; k < moving_start_[cell + 1]; ++k) {
    test(moving_items_[k]);
  }
  return improved;
}

RayHit RayCaster::cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                       double max_range_m, double t_s) {
  RayHit miss;
  if (!(max_range_m > 0.0)) return miss;
  if (++ray_id_ == 0) {  // wrapped: forget all marks
    std::fill(mailbox_.begin(), mailbox_.end(), 0);
    std::fill(group_mailbox_.begin(), group_mailbox_.end(), 0);
    ray_id_ = 1;
  }
  // Clip the ray to the grid's xy rectangle.
  double t_enter = 0.0, t_exit = max_range_m;
  const double lo[2] = {x0_, y0_};
  const double hi[2] = {x0_ + nx_ * params_.cell_m, y0_ + ny_ * params_.cell_m};
  for (int a = 0; a < 2; ++a) {
    if (std::abs(dir[a]) < 1e-15) {
      if (origin[a] < lo[a] || origin[a] > hi[a]) return miss;
      continue;
    }
    double t1 = (lo[a] - origin[a]) / dir[a];
    double t2 = (hi[a] - origin[a]) / dir[a];
    if (t1 > t2) std::swap(t1, t2);
    t_enter = std::max(t_enter, t1);
    t_exit = std::min(t_exit, t2);
  }
  if (t_enter > t_exit) return miss;

  const double cell = params_.cell_m;
  const Eigen::Vector3d p = origin + t_enter * dir;
  int ix = std::clamp(static_cast<int>(std::floor((p.x() - x0_) / cell)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((p.y() - y0_) / cell)), 0, ny_ - 1);
  const int step_x = dir.x() > 0 ? 1 : -1;
  const int step_y = dir.y() > 0 ? 1 : -1;
  double t_max_x = kInf, t_max_y = kInf, t_delta_x = kInf, t_delta_y = kInf;
  if (std::abs(dir.x()) >= 1e-15) {
    t_max_x = (x0_ + (ix + (step_x > 0 ? 1 : 0)) * cell - origin.x()) / dir.x();
    t_delta_x = cell / std::abs(dir.x());
  }
  if (std::abs(dir.y()) >= 1e-15) {
    t_max_y = (y0_ + (iy + (step_y > 0 ? 1 : 0)) * cell - origin.y()) / dir.y();
    t_delta_y = cell / std::abs(dir.y());
  }

  RayHit best;
  best.distance_m = max_range_m * (1.0 + 1e-12);
  bool found = false;
  for (;;) {
    const double cell_exit = std::min({t_max_x, t_max_y, t_exit});
    found |= testCell(iy * nx_ + ix, origin, dir, t_s, &best);
    // A hit before this cell's exit cannot be beaten by primitives of later cells.
    if (found && best.distance_m <= cell_exit) break;
    if (cell_exit >= t_exit) break;
    // Above the whole scene and climbing: nothing more to hit.
    if (dir.z() > 0.0 && origin.z() + cell_exit * dir.z() > z_max_) break;
    if (t_max_x < t_max_y) {
      ix += step_x;
      t_max_x += t_delta_x;
      if (ix < 0 || ix >= nx_) break;
    } else {
      iy += step_y;
      t_max_y += t_delta_y;
      if (iy < 0 || iy >= ny_) break;
    }
  }
  if (!found) return miss;
  return best;
}

RayHit RayCaster::castBruteForce(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                 double max_range_m, double t_s) const {
  RayHit best;
  best.distance_m = max_range_m * (1.0 + 1e-12);
  bool found = false;
  for (std::uint32_t i = 0; i < scene_.primitives.size(); ++i) {
    const double t = scene_.primitives[i].intersect(origin, dir, t_s);
    if (t > 0.0 && t < best.distance_m) {
      best.distance_m = t;
      best.primitive = i;
      found = true;
    }
  }
  if (!found) return RayHit();
  return best;
}

}  // namespace core
}  // namespace urban_detection
