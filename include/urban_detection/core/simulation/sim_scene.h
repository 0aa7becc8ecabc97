/// \file sim_scene.h
/// Scene description of the simulated urban drive and an exact ray caster over it (ROS-free).
///
/// A scene is a flat list of solid primitives (oriented boxes, cylinders, ellipsoids), each
/// labelled with an instance id (0 = background: ground, terrain, walls) and an ObjectClass.
/// Objects are groups of primitives sharing an instance id (a car is a body box, a cabin box, a
/// roof, plates and lamps). Moving objects translate linearly: a primitive's centre at time t is
/// `center + velocity * t`. The ray caster finds the first surface along a ray exactly
/// (closed-form intersections), accelerated by a uniform 2-D grid over the primitives' xy bounds.
///
/// Materials: each primitive carries the surface's diffuse reflectivity at the sensor's 905 nm
/// (mean and per-return spread) and, for foliage, a porosity: LidarSimulator lets a ray that
/// enters a porous primitive pass through it with probability `transmission` (it goes on to the
/// surface behind), and otherwise returns it from a random depth inside the volume (exponential
/// with mean `penetration_m`), as a laser footprint among leaves returns from the first leaf it
/// meets. The caster itself treats every primitive as solid.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "urban_detection/core/common/object_class.h"

namespace urban_detection {
namespace core {

/// Shape of a primitive; all are solid and expressed in their local frame.
enum class PrimitiveShape : std::uint8_t {
  kBox,       // |x| <= hx, |y| <= hy, |z| <= hz
  kCylinder,  // x^2 + y^2 <= hx^2 (hy ignored), |z| <= hz: axis along local z
  kEllipsoid  // (x/hx)^2 + (y/hy)^2 + (z/hz)^2 <= 1
};

/// One solid primitive of the scene.
struct Primitive {
  PrimitiveShape shape = PrimitiveShape::kBox;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();        // [m] world position at t = 0
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // local -> world
  Eigen::Vector3d half_extents = Eigen::Vector3d::Ones();  // [m] see PrimitiveShape
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // [m/s] linear motion
  std::uint32_t instance_id = 0;                           // 0 = background
  ObjectClass object_class = ObjectClass::kUnlabeled;
  float reflectivity = 0.2f;         // [0..1] mean diffuse reflectivity at 905 nm
  float reflectivity_spread = 0.0f;  // [0..1] std dev of the reflectivity from return to return
                                     //   (texture, leaf orientation, paint wear)
  float transmission = 0.0f;         // [0..1] chance a ray passes through (porous foliage)
  float penetration_m = 0.0f;        // [m] mean depth inside the volume of a return that does
                                     //   not pass through (0 with transmission 0: opaque)

  bool moving() const { return !velocity.isZero(); }
  /// True for foliage: rays may pass through or return from inside (see the file comment).
  bool porous() const { return transmission > 0.0f || penetration_m > 0.0f; }
  /// World axis-aligned bounds at time `t_s` [s].
  Eigen::AlignedBox3d bounds(double t_s = 0.0) const;
  /// Distance t > t_min [m] along the ray `origin + t * dir` where it enters the solid at time
  /// `t_s`, or a negative value if it misses (a ray starting inside the solid does not hit it).
  /// `dir` need not be normalised; t is in units of |dir|.
  double intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_s,
                   double t_min = 1e-6) const;
  /// The interval [*t_in, *t_out] of the whole line `origin + t * dir` (any sign of t) inside
  /// the solid at time `t_s`; false if the line misses it. Same units as intersect().
  bool span(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_s, double* t_in,
            double* t_out) const;
  /// True if `p` [m] lies inside the solid (grown by `margin_m`) at time `t_s`. For the box
  /// and the cylinder the margin is exact; for the ellipsoid it grows each semi-axis.
  bool contains(const Eigen::Vector3d& p, double t_s, double margin_m = 0.0) const;
};

/// Helpers building primitives.
Primitive makeBox(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw_rad);
Primitive makeCylinder(const Eigen::Vector3d& center, double radius_m, double height_m);
Primitive makeEllipsoid(const Eigen::Vector3d& center, const Eigen::Vector3d& semi_axes);

/// One labelled object of the scene (metadata of a group of primitives).
struct SceneObject {
  std::uint32_t instance_id = 0;                       // >= 1
  ObjectClass object_class = ObjectClass::kUnlabeled;  // class of the whole object
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // [m] footprint centre on the ground, t = 0
  double yaw_rad = 0.0;                                // [rad] heading about z
  Eigen::Vector3d size = Eigen::Vector3d::Zero();      // [m] length, width, height
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // [m/s]
  std::uint32_t first_primitive = 0;                   // index into Scene::primitives
  std::uint32_t num_primitives = 0;
};

/// The whole static + moving scene.
struct Scene {
  std::vector<Primitive> primitives;
  std::vector<SceneObject> objects;  // objects[i].instance_id == i + 1

  /// Appends an object made of `parts` (their instance ids are overwritten), returns its id.
  std::uint32_t addObject(SceneObject object, const std::vector<Primitive>& parts);
  /// Appends a background primitive (instance id 0).
  void addBackground(Primitive primitive);
  /// World bounds of an object's primitives at time `t_s`. `id` must be a valid instance id.
  Eigen::AlignedBox3d objectBounds(std::uint32_t id, double t_s) const;
};

/// Result of one cast.
struct RayHit {
  double distance_m = -1.0;     // along the unit direction; < 0: no hit
  std::uint32_t primitive = 0;  // index into Scene::primitives
};

/// Parameters of the ray caster.
struct RayCasterParams {
  double cell_m = 2.0;  // [m] side of a cell of the 2-D acceleration grid
};

/// Casts rays against a scene with a uniform 2-D grid of primitive xy bounds. Static primitives
/// are binned once, grouped by object (one box test skips an object's parts); moving primitives
/// are binned with their bounds swept over the time window given to setTimeWindow(). Not
/// thread-safe (per-ray mailbox).
class RayCaster {
 public:
  /// Keeps a reference to `scene`, which must outlive the caster and not change.
  RayCaster(const Scene& scene, const RayCasterParams& params = RayCasterParams());

  /// Rebins the moving primitives for casts with times in [t0_s, t1_s].
  void setTimeWindow(double t0_s, double t1_s);

  /// First surface hit by the ray `origin + d * dir` (dir must be a unit vector) with
  /// d in (0, max_range_m], the moving primitives being placed at time `t_s`
  /// (which must lie in the current time window).
  RayHit cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range_m,
              double t_s);

  /// Reference implementation: tests every primitive (for tests).
  RayHit castBruteForce(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        double max_range_m, double t_s) const;

  const Scene& scene() const { return scene_; }

 private:
  void binInto(const Eigen::AlignedBox3d& box, std::uint32_t prim,
               std::vector<std::vector<std::uint32_t>>* cells) const;
  bool testCell(int cell, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_s,
                RayHit* best);

  const Scene& scene_;
  RayCasterParams params_;
  double x0_ = 0.0, y0_ = 0.0;  // [m] grid origin
  int nx_ = 1, ny_ = 1;
  double z_max_ = 0.0;         // [m] highest point of the scene (rays above it going up stop)
  double static_z_max_ = 0.0;  // [m] same, static primitives only
  struct Group {  // consecutive static primitives of one object (or one background primitive)
    std::uint32_t first = 0, count = 0;
    Eigen::AlignedBox3d box;
  };
  std::vector<Group> groups_;
  std::vector<std::uint32_t> group_mailbox_;
  std::vector<std::uint32_t> static_start_, static_items_;  // CSR per cell (group indices)
  std::vector<std::uint32_t> moving_start_, moving_items_;  // CSR per cell (time window)
  std::vector<std::uint32_t> moving_prims_;
  std::vector<std::uint32_t> mailbox_;
  std::uint32_t ray_id_ = 0;
  double window_t0_ = 0.0, window_t1_ = 0.0;
};

}  // namespace core
}  // namespace urban_detection
