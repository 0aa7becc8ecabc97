// Shared object geometry (hull, minimum-area box), the distance weight and its polynomial fit
// (paper Sec. 4), and the cell fitness value.
#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "detection_test_utils.h"
#include "urban_detection/core/detection/cell_fitness.h"
#include "urban_detection/core/detection/distance_weight.h"
#include "urban_detection/core/detection/object_geometry.h"

namespace urban_detection {
namespace {

TEST(ObjectGeometry, HullOfASquareWithInteriorPoints) {
  std::vector<Eigen::Vector2f> pts = {
      {0, 0}, {2, 0},       {2, 2}, {0, 2},
      {1, 1}, {0.5f, 1.5f}, {1, 0}, {2, 2}};  // an edge point and a duplicate
  std::vector<Eigen::Vector2f> hull;
  core::convexHull2d(&pts, &hull);
  ASSERT_EQ(hull.size(), 4u);
  double area = 0.0;  // shoelace: positive for counter-clockwise
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    area += 0.5 * (a.x() * b.y() - b.x() * a.y());
  }
  EXPECT_NEAR(area, 4.0, 1e-6);
}

TEST(ObjectGeometry, RotatedCarOutlineGivesItsBox) {
  // Points on the outline and inside a 4.5 x 1.8 m rectangle centred at (10, -3), yaw 0.6 rad,
  // z in [-1.5, 0]; the minimum-area box must be that rectangle.
  const float yaw = 0.6f, cx = 10.0f, cy = -3.0f, l = 4.5f, w = 1.8f;
  LabeledCloud cloud;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  for (int i = 0; i < 400; ++i) {
    float a = u(rng) * l, b = u(rng) * w;
    if (i < 4) {  // the four corners, so the box is exact
      a = (i & 1 ? 0.5f : -0.5f) * l;
      b = (i & 2 ? 0.5f : -0.5f) * w;
    }
    const float x = cx + a * std::cos(yaw) - b * std::sin(yaw);
    const float y = cy + a * std::sin(yaw) + b * std::cos(yaw);
    test::addPoint(&cloud, x, y, -1.5f + 1.5f * (i % 7) / 6.0f, 1);
  }
  std::vector<std::uint32_t> pos(cloud.size());
  for (std::size_t i = 0; i < pos.size(); ++i) pos[i] = static_cast<std::uint32_t>(i);
  core::ObjectGeometry g;
  core::DetectedObject o;
  g.compute(cloud, pos, &o);
  EXPECT_NEAR(o.obb_yaw_rad, yaw, 1e-3);
  EXPECT_NEAR(o.obb_size.x(), l, 1e-3);
  EXPECT_NEAR(o.obb_size.y(), w, 1e-3);
  EXPECT_NEAR(o.obb_size.z(), 1.5f, 1e-5);
  EXPECT_NEAR(o.obb_center.x(), cx, 1e-3);
  EXPECT_NEAR(o.obb_center.y(), cy, 1e-3);
  EXPECT_NEAR(o.obb_center.z(), -0.75f, 1e-5);
  // Axis-aligned box of the rotated rectangle, computed by hand.
  const float hx = 0.5f * (l * std::cos(yaw) + w * std::sin(yaw));
  const float hy = 0.5f * (l * std::sin(yaw) + w * std::cos(yaw));
  EXPECT_NEAR(o.min_pt.x(), cx - hx, 1e-4);
  EXPECT_NEAR(o.max_pt.y(), cy + hy, 1e-4);
  // Centroid: mean of the points, by a second route.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.points) mean += Eigen::Vector3d(p.x, p.y, p.z);
  mean /= cloud.size();
  EXPECT_TRUE(o.centroid.cast<double>().isApprox(mean, 1e-5));
}

TEST(ObjectGeometry, YawIsNormalisedAndDegenerateCasesAreSafe) {
  // A box along y has yaw +pi/2 (the range is (-pi/2, pi/2]).
  std::vector<Eigen::Vector2f> hull = {{0, 0}, {1, 0}, {1, 3}, {0, 3}};
  Eigen::Vector2f c, s;
  float yaw;
  core::minAreaRectangle(hull, &c, &s, &yaw);
  EXPECT_NEAR(yaw, M_PI / 2, 1e-6);
  EXPECT_NEAR(s.x(), 3.0f, 1e-6);
  EXPECT_NEAR(s.y(), 1.0f, 1e-6);
  // Collinear points: zero width, length along the line.
  LabeledCloud line;
  for (int i = 0; i < 5; ++i) test::addPoint(&line, i * 1.0f, i * 1.0f, 0.0f, 1);
  core::ObjectGeometry g;
  core::DetectedObject o;
  g.compute(line, {0, 1, 2, 3, 4}, &o);
  EXPECT_NEAR(o.obb_size.x(), 4.0f * std::sqrt(2.0f), 1e-4);
  EXPECT_NEAR(o.obb_size.y(), 0.0f, 1e-6);
  EXPECT_NEAR(o.obb_yaw_rad, M_PI / 4, 1e-5);
  g.compute(line, {}, &o);
  EXPECT_EQ(o.centroid, Eigen::Vector3f::Zero());
}

// Brute force: every hull edge direction, all vertices projected (the O(n^2) definition).
double bruteMinArea(const std::vector<Eigen::Vector2f>& hull) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2f e = hull[(i + 1) % hull.size()] - hull[i];
    if (e.norm() == 0.0f) continue;
    const Eigen::Vector2f u = e.normalized(), v(-u.y(), u.x());
    float a0 = 1e9f, a1 = -1e9f, b0 = 1e9f, b1 = -1e9f;
    for (const auto& q : hull) {
      a0 = std::min(a0, q.dot(u));
      a1 = std::max(a1, q.dot(u));
      b0 = std::min(b0, q.dot(v));
      b1 = std::max(b1, q.dot(v));
    }
    best = std::min(best, static_cast<double>(a1 - a0) * (b1 - b0));
  }
  return best;
}

TEST(ObjectGeometry, CalipersAndColumnHullMatchBruteForceOnRandomClouds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 200; ++trial) {
    // Random anisotropic, rotated blobs of 5..400 points up to ~6 m long.
    const int n = 5 + trial * 2;
    const float sx = 0.2f + 3.0f * std::fabs(u(rng)), sy = 0.1f + 1.0f * std::fabs(u(rng));
    const float r = 3.14159f * u(rng);
    LabeledCloud cloud;
    std::vector<Eigen::Vector2f> all;
    for (int i = 0; i < n; ++i) {
      const float a = sx * u(rng), b = sy * u(rng);
      const float x = 20.0f + a * std::cos(r) - b * std::sin(r);
      const float y = -5.0f + a * std::sin(r) + b * std::cos(r);
      test::addPoint(&cloud, x, y, u(rng), 1);
      all.emplace_back(x, y);
    }
    std::vector<Eigen::Vector2f> exact_hull;
    core::convexHull2d(&all, &exact_hull);
    Eigen::Vector2f c, s;
    float yaw;
    core::minAreaRectangle(exact_hull, &c, &s, &yaw);
    EXPECT_NEAR(static_cast<double>(s.x()) * s.y(), bruteMinArea(exact_hull), 1e-4)
        << "trial " << trial;
    // The detectors' geometry (column hull, 5 cm tolerance) gives nearly the same box.
    std::vector<std::uint32_t> pos(n);
    for (int i = 0; i < n; ++i) pos[i] = i;
    core::ObjectGeometry g;
    core::DetectedObject o;
    g.compute(cloud, pos, &o);
    EXPECT_NEAR(o.obb_size.x(), s.x(), 2 * core::ObjectGeometry::kHullTolerance) << trial;
    EXPECT_NEAR(o.obb_size.y(), s.y(), 2 * core::ObjectGeometry::kHullTolerance) << trial;
    EXPECT_LE(o.obb_size.x() * o.obb_size.y(), s.x() * s.y() + 1e-4) << trial;
  }
  // All points coincident: a zero box at the point.
  LabeledCloud same;
  for (int i = 0; i < 6; ++i) test::addPoint(&same, 3.0f, 4.0f, 1.0f, 1);
  core::ObjectGeometry g;
  core::DetectedObject o;
  g.compute(same, {0, 1, 2, 3, 4, 5}, &o);
  EXPECT_EQ(o.obb_size, Eigen::Vector3f::Zero());
  EXPECT_TRUE(o.obb_center.isApprox(Eigen::Vector3f(3.0f, 4.0f, 1.0f)));
}

// A detector that accumulates the moments and gathers the xy itself while scattering the points
// of interleaved objects (the hierarchical grid's output pass) gets the very same fields as
// compute() through positions, bit for bit, with one ObjectGeometry reused across objects.
TEST(ObjectGeometry, FinishOnScatteredMomentsEqualsComputeBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  constexpr int kObjects = 7;
  LabeledCloud cloud;
  for (int i = 0; i < 3000; ++i) {
    const int k = static_cast<int>(std::fabs(u(rng)) * kObjects) % kObjects;
    // Object k: a blob of k-dependent size and shape; k = 0 is a line along y (collinear).
    const float x = 10.0f * k + (k == 0 ? 0.0f : 0.3f * k * u(rng));
    const float y = -4.0f + (1.0f + k) * u(rng);
    test::addPoint(&cloud, x, y, 2.0f * u(rng), static_cast<std::uint32_t>(k));
  }
  std::vector<std::vector<std::uint32_t>> positions(kObjects);
  std::vector<core::ObjectMoments> moments(kObjects);
  std::vector<std::vector<Eigen::Vector2f>> xy(kObjects);
  for (std::uint32_t i = 0; i < cloud.size(); ++i) {
    const LabeledPoint& p = cloud[i];
    positions[p.label].push_back(i);
    moments[p.label].add(p.x, p.y, p.z);
    xy[p.label].emplace_back(p.x, p.y);
  }
  core::ObjectGeometry by_positions, by_moments;
  for (int k = kObjects; k-- > 0;) {  // reverse order: the scratch buffers shrink and grow
    ASSERT_GT(positions[k].size(), 10u);
    core::DetectedObject a, b;
    by_positions.compute(cloud, positions[k], &a);
    by_moments.finish(moments[k], xy[k].data(), &b);
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(a.centroid[d], b.centroid[d]) << k;
      EXPECT_EQ(a.min_pt[d], b.min_pt[d]) << k;
      EXPECT_EQ(a.max_pt[d], b.max_pt[d]) << k;
      EXPECT_EQ(a.obb_center[d], b.obb_center[d]) << k;
      EXPECT_EQ(a.obb_size[d], b.obb_size[d]) << k;
    }
    EXPECT_EQ(a.obb_yaw_rad, b.obb_yaw_rad) << k;
    EXPECT_GT(b.obb_size.x(), 1.0f) << k;  // a real box, not the zero of an empty object
  }
  core::DetectedObject empty;
  empty.obb_size.setOnes();
  by_moments.finish(core::ObjectMoments(), nullptr, &empty);
  EXPECT_EQ(empty.obb_size, Eigen::Vector3f::Zero());
}

// The column hull of ObjectGeometry written plainly (one scalar pass, the first point wins
// ties), for the bit-for-bit check below of the optimised one (two halves merged, selects by
// masks, vectorised search).
void referenceColumnBox(const std::vector<Eigen::Vector2f>& pts, Eigen::Vector2f* center,
                        Eigen::Vector2f* size, float* yaw) {
  float mnx = pts[0].x(), mxx = mnx, mny = pts[0].y(), mxy = mny;
  for (const Eigen::Vector2f& q : pts) {
    mnx = std::min(mnx, q.x());
    mxx = std::max(mxx, q.x());
    mny = std::min(mny, q.y());
    mxy = std::max(mxy, q.y());
  }
  const bool along_x = (mxx - mnx) >= (mxy - mny);
  auto ab = [along_x](const Eigen::Vector2f& q) {
    return along_x ? q : Eigen::Vector2f(q.y(), q.x());
  };
  const float lo = along_x ? mnx : mny, hi = along_x ? mxx : mxy, len = hi - lo;
  const int cols =
      std::clamp(static_cast<int>(std::ceil(len / core::ObjectGeometry::kHullTolerance)), 1, 512);
  const float scale = len > 0.0f ? cols / len : 0.0f;
  std::vector<int> low(cols, -1), high(cols, -1);
  int first = -1, last = -1;
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
    const Eigen::Vector2f q = ab(pts[i]);
    const int c = std::min(static_cast<int>((q.x() - lo) * scale), cols - 1);
    if (low[c] < 0 || q.y() < ab(pts[low[c]]).y()) low[c] = i;
    if (high[c] < 0 || q.y() > ab(pts[high[c]]).y()) high[c] = i;
    if (first < 0 && q.x() == lo) first = i;
    if (last < 0 && q.x() == hi) last = i;
  }
  std::vector<Eigen::Vector2f> lower = {ab(pts[first])}, upper = {ab(pts[last])};
  for (int c = 0; c < cols; ++c) {
    if (low[c] >= 0) lower.push_back(ab(pts[low[c]]));
  }
  lower.push_back(ab(pts[last]));
  for (int c = cols; c-- > 0;) {
    if (high[c] >= 0) upper.push_back(ab(pts[high[c]]));
  }
  upper.push_back(ab(pts[first]));
  auto cross = [](const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2f> hull;
  for (const Eigen::Vector2f& q : lower) {
    while (hull.size() >= 2 && cross(hull[hull.size() - 2], hull.back(), q) <= 0.0f) {
      hull.pop_back();
    }
    hull.push_back(q);
  }
  const std::size_t t = hull.size() + 1;
  for (std::size_t i = 1; i < upper.size(); ++i) {
    while (hull.size() >= t && cross(hull[hull.size() - 2], hull.back(), upper[i]) <= 0.0f) {
      hull.pop_back();
    }
    hull.push_back(upper[i]);
  }
  hull.pop_back();
  if (!along_x) {
    for (Eigen::Vector2f& q : hull) q = Eigen::Vector2f(q.y(), q.x());
    std::reverse(hull.begin(), hull.end());
  }
  core::minAreaRectangle(hull, center, size, yaw);
}

// ObjectGeometry's box of all points of `cloud` (in order) and referenceColumnBox() of their xy.
void boxAndReference(const LabeledCloud& cloud, const std::vector<Eigen::Vector2f>& pts,
                     core::DetectedObject* object, Eigen::Vector2f* center, Eigen::Vector2f* size,
                     float* yaw) {
  std::vector<std::uint32_t> pos(cloud.size());
  for (std::size_t i = 0; i < pos.size(); ++i) pos[i] = static_cast<std::uint32_t>(i);
  core::ObjectGeometry g;
  g.compute(cloud, pos, object);
  referenceColumnBox(pts, center, size, yaw);
}

// The two boxes of boxAndReference() are equal (centre, size, yaw).
void expectBoxEqualsReference(const LabeledCloud& cloud, const std::vector<Eigen::Vector2f>& pts,
                              int trial) {
  core::DetectedObject o;
  Eigen::Vector2f c, s;
  float yaw;
  boxAndReference(cloud, pts, &o, &c, &s, &yaw);
  EXPECT_EQ(o.obb_center.x(), c.x()) << trial;
  EXPECT_EQ(o.obb_center.y(), c.y()) << trial;
  EXPECT_EQ(o.obb_size.x(), s.x()) << trial;
  EXPECT_EQ(o.obb_size.y(), s.y()) << trial;
  EXPECT_EQ(o.obb_yaw_rad, yaw) << trial;
}

// Coordinates on a 1 cm lattice: many points tie for a column's extreme, in both halves of the
// point list, and for the box's minimum and maximum; odd and even point counts, both axes.
TEST(ObjectGeometry, ColumnHullEqualsAPlainSinglePassBitForBit) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> cm(-150, 150);
  std::uniform_int_distribution<int> small(0, 30);
  for (int trial = 0; trial < 1300; ++trial) {
    // 1..300 points over up to 9 x 1 m, then 1000 small objects (30 x 5 cm) where most column
    // extremes are hull vertices.
    const bool tiny = trial >= 300;
    const int n = tiny ? 2 + trial % 13 : 1 + trial;
    const float stretch = trial % 2 ? 3.0f : 0.3f;  // long along x or along y
    LabeledCloud cloud;
    std::vector<Eigen::Vector2f> pts;
    for (int i = 0; i < n; ++i) {
      const float a = 0.01f * (tiny ? small(rng) : cm(rng)), b = 0.01f * (small(rng) % 6);
      const float x = 12.0f + (tiny ? (trial % 2 ? a : b) : 0.01f * cm(rng) * stretch);
      const float y = -3.0f + (tiny ? (trial % 2 ? b : a) : 0.01f * cm(rng) / stretch);
      test::addPoint(&cloud, x, y, 0.01f * cm(rng), 1);
      pts.emplace_back(x, y);
    }
    expectBoxEqualsReference(cloud, pts, trial);
  }
}

// Chains with long runs of pops (the hull chains pop up to two points per candidate without a
// branch and take a loop beyond): arcs of a parabola, whose every candidate pops its
// predecessor, ended by an outlier that pops the whole run, and zig-zags; along x and along y,
// with and without the outliers; the box equals the plain reference bit for bit.
TEST(ObjectGeometry, ColumnHullWithDeepPopsEqualsAPlainSinglePassBitForBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
  for (int trial = 0; trial < 64; ++trial) {
    const bool swap = trial % 2, outliers = (trial / 2) % 2, zigzag = (trial / 4) % 2;
    const int n = 20 + 7 * trial;
    LabeledCloud cloud;
    std::vector<Eigen::Vector2f> pts;
    auto add = [&](float a, float b) {
      const float x = 5.0f + (swap ? b : a), y = 2.0f + (swap ? a : b);
      test::addPoint(&cloud, x, y, 0.0f, 1);
      pts.emplace_back(x, y);
    };
    if (outliers) add(-0.01f, 3.0f);  // before the first column: pops the upper chain's run
    for (int i = 0; i < n; ++i) {
      const float a = 0.05f * i + (trial > 32 ? jitter(rng) : 0.0f);
      const float arc = 0.2f * (a - 1.0f) * (a - 1.0f);
      add(a, zigzag ? (i % 2 ? arc : -arc) : -arc);  // lower run, popping one by one
      add(a, zigzag ? (i % 3 ? -arc : arc) : arc);   // upper run
    }
    if (outliers) add(0.05f * n, -3.0f);  // past the last column: pops the lower chain's run
    expectBoxEqualsReference(cloud, pts, trial);
  }
}

// Rotating calipers written plainly (every projection recomputed, branches), the reference for
// the bit-for-bit check of the optimised minAreaRectangle (projections carried over, steps as
// selects, the best edge's box recomputed at the end).
void referenceCalipers(const std::vector<Eigen::Vector2f>& h, Eigen::Vector2f* center,
                       Eigen::Vector2f* size, float* yaw_rad) {
  *center = Eigen::Vector2f::Zero();
  *size = Eigen::Vector2f::Zero();
  *yaw_rad = 0.0f;
  const std::size_t n = h.size();
  if (n == 0) return;
  *center = h[0];
  auto next = [n](std::size_t k) { return (k + 1) % n; };
  std::size_t a = 0, b = 0, c = 0;
  bool init = false, found = false;
  double best_area = std::numeric_limits<double>::infinity();
  Eigen::Vector2f best_u(0.0f, 0.0f);
  float best_lu = 0.0f, best_lv = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f e = h[next(i)] - h[i];
    const float len = e.norm();
    if (len <= 0.0f) continue;
    const Eigen::Vector2f u = e / len, v(-u.y(), u.x());
    if (!init) {
      for (std::size_t k = 0; k < n; ++k) {
        if (h[k].dot(u) > h[a].dot(u)) a = k;
        if (h[k].dot(v) > h[b].dot(v)) b = k;
        if (h[k].dot(u) < h[c].dot(u)) c = k;
      }
      init = true;
    } else {
      for (std::size_t s = 0; s < n && h[next(a)].dot(u) >= h[a].dot(u); ++s) a = next(a);
      for (std::size_t s = 0; s < n && h[next(b)].dot(v) >= h[b].dot(v); ++s) b = next(b);
      for (std::size_t s = 0; s < n && h[next(c)].dot(u) <= h[c].dot(u); ++s) c = next(c);
    }
    const float umin = h[c].dot(u), umax = h[a].dot(u), vmin = h[i].dot(v), vmax = h[b].dot(v);
    const double area = static_cast<double>(umax - umin) * static_cast<double>(vmax - vmin);
    if (area < best_area - 1e-12) {
      best_area = area;
      *center = u * (0.5f * (umin + umax)) + v * (0.5f * (vmin + vmax));
      best_u = u;
      best_lu = umax - umin;
      best_lv = vmax - vmin;
      found = true;
    }
  }
  if (!found) return;
  float lu = best_lu, lv = best_lv, yaw = std::atan2(best_u.y(), best_u.x());
  if (lv > lu) {
    std::swap(lu, lv);
    yaw += static_cast<float>(M_PI / 2);
  }
  while (yaw > static_cast<float>(M_PI / 2)) yaw -= static_cast<float>(M_PI);
  while (yaw <= -static_cast<float>(M_PI / 2)) yaw += static_cast<float>(M_PI);
  *size = Eigen::Vector2f(lu, lv);
  *yaw_rad = yaw;
}

std::uint32_t bitsOf(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof(u));
  return u;
}

// Polygons with many ties (lattice hulls: rectangles, equal projections of several vertices),
// long thin ones, and hulls of random float points; 3..200 vertices, plus degenerate ones
// (a repeated point, two points).
TEST(ObjectGeometry, CalipersEqualAPlainImplementationBitForBit) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> lattice(-6, 6);
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<Eigen::Vector2f> pts, hull;
    const int n = 2 + trial % 300;
    const int kind = trial % 3;
    const float r = 3.14159f * u(rng), sx = 0.1f + 4.0f * std::fabs(u(rng));
    for (int i = 0; i < n; ++i) {
      if (kind == 0) {  // lattice: ties everywhere
        pts.emplace_back(0.25f * lattice(rng), 0.5f * (lattice(rng) % 3));
      } else {  // rotated anisotropic blobs, near and far from the origin
        const float a = sx * u(rng), b = 0.2f * u(rng), off = kind == 1 ? 0.0f : 60.0f;
        pts.emplace_back(off + a * std::cos(r) - b * std::sin(r),
                         -off + a * std::sin(r) + b * std::cos(r));
      }
    }
    core::convexHull2d(&pts, &hull);
    Eigen::Vector2f c, s, rc, rs;
    float yaw = 0.0f, ryaw = 0.0f;
    core::minAreaRectangle(hull, &c, &s, &yaw);
    referenceCalipers(hull, &rc, &rs, &ryaw);
    for (int d = 0; d < 2; ++d) {
      EXPECT_EQ(bitsOf(c[d]), bitsOf(rc[d])) << trial;
      EXPECT_EQ(bitsOf(s[d]), bitsOf(rs[d])) << trial;
    }
    EXPECT_EQ(bitsOf(yaw), bitsOf(ryaw)) << trial;
  }
  for (const std::vector<Eigen::Vector2f>& degenerate :
       {std::vector<Eigen::Vector2f>{{1, 2}}, std::vector<Eigen::Vector2f>{{1, 2}, {1, 2}},
        std::vector<Eigen::Vector2f>{{1, 2}, {3, 2}}}) {
    Eigen::Vector2f c, s, rc, rs;
    float yaw = 0.0f, ryaw = 0.0f;
    core::minAreaRectangle(degenerate, &c, &s, &yaw);
    referenceCalipers(degenerate, &rc, &rs, &ryaw);
    EXPECT_EQ(c, rc);
    EXPECT_EQ(s, rs);
    EXPECT_EQ(yaw, ryaw);
  }
}

// A column's extremes tie between -0 and +0 (equal as floats): the first point wins, as in a
// plain pass, down to the sign bit of the box fields. Coordinates differing by a subnormal
// amount (a column width that overflows to an infinite scale) give a finite box, not a column
// outside the array.
TEST(ObjectGeometry, SignedZeroTiesAndSubnormalExtentsAreSafe) {
  for (int order = 0; order < 4; ++order) {
    LabeledCloud cloud;
    std::vector<Eigen::Vector2f> pts;
    const float z1 = order & 1 ? -0.0f : 0.0f, z2 = order & 2 ? -0.0f : 0.0f;
    // The lowest two points of the column of x = 1.01 and 1.03 m tie at y = 0; the one taken is
    // a hull vertex and a corner of the box, which moves by 2 cm with it.
    for (const Eigen::Vector2f& q :
         {Eigen::Vector2f(0.5f, 0.6f), Eigen::Vector2f(1.01f, z1), Eigen::Vector2f(1.03f, z2),
          Eigen::Vector2f(3.0f, 1.0f), Eigen::Vector2f(2.5f, 0.8f), Eigen::Vector2f(2.0f, 0.6f)}) {
      test::addPoint(&cloud, q.x(), q.y(), 0.0f, 1);
      pts.push_back(q);
    }
    core::DetectedObject o;
    Eigen::Vector2f c, s;
    float yaw;
    boxAndReference(cloud, pts, &o, &c, &s, &yaw);
    for (int d = 0; d < 2; ++d) {
      EXPECT_EQ(bitsOf(o.obb_center[d]), bitsOf(c[d])) << order;
      EXPECT_EQ(bitsOf(o.obb_size[d]), bitsOf(s[d])) << order;
    }
    EXPECT_EQ(bitsOf(o.obb_yaw_rad), bitsOf(yaw)) << order;
  }
  LabeledCloud tiny;
  test::addPoint(&tiny, 0.0f, 0.0f, 0.0f, 1);
  test::addPoint(&tiny, 1e-40f, 0.0f, 0.0f, 1);
  test::addPoint(&tiny, 0.0f, 1e-41f, 0.0f, 1);
  core::ObjectGeometry g;
  core::DetectedObject o;
  g.compute(tiny, {0, 1, 2}, &o);
  EXPECT_TRUE(o.obb_center.allFinite());
  EXPECT_TRUE(o.obb_size.allFinite());
  EXPECT_LE(o.obb_size.x(), 1e-39f);
}

TEST(DistanceWeight, FitRecoversAKnownSixthDegreePolynomial) {
  // Synthetic "densities" on the ring centres 1.5..79.5 m from a known polynomial.
  const std::vector<double> truth = {0.9, -0.05, 1.2e-3, -1.5e-5, 1.0e-7, -3.5e-10, 5.0e-13};
  std::vector<double> x, y;
  for (double d = 1.5; d < 80.0; d += 1.0) {
    x.push_back(d);
    double v = 0.0, p = 1.0;
    for (const double c : truth) {
      v += c * p;
      p *= d;
    }
    y.push_back(v);
  }
  const std::vector<double> c = core::fitPolynomial(x, y, 6);
  ASSERT_EQ(c.size(), 7u);
  for (std::size_t k = 0; k < 7; ++k) {
    EXPECT_NEAR(c[k], truth[k], 1e-6 * std::fabs(truth[k]) + 1e-14) << "coefficient " << k;
  }
  EXPECT_TRUE(core::fitPolynomial(x, y, 90).empty());  // more unknowns than samples
}

TEST(DistanceWeight, RingDensityOfAKnownRadialDistribution) {
  // n_i points in ring i = area_i * 1000 / (1 + 0.1 d_i^2): the density must come out as
  // 1000 / (1 + 0.1 d^2) per sweep, normalised to 1 in the first ring.
  core::RingDensity rings(1.0, 80.0, 1.0);
  std::vector<double> expect;
  for (std::size_t i = 0; i < rings.rings(); ++i) {
    const double r0 = 1.0 + i, r1 = r0 + 1.0, d = rings.ringCenter(i);
    const double per_m2 = 1000.0 / (1.0 + 0.1 * d * d);
    const long n = std::lround(M_PI * (r1 * r1 - r0 * r0) * per_m2);
    for (long k = 0; k < n; ++k) rings.addDistance(r0 + (k + 0.5) / n);
    expect.push_back(n / (M_PI * (r1 * r1 - r0 * r0)));
  }
  const auto dens = rings.density();
  const auto norm = rings.normalisedDensity();
  for (std::size_t i = 0; i < rings.rings(); ++i) {
    EXPECT_NEAR(dens[i], expect[i], 1e-9);
    EXPECT_NEAR(norm[i], expect[i] / expect[0], 1e-9);
  }
  // And a whole cloud: NaN and out-of-range points are not counted.
  CloudXYZIRT cloud;
  PointXYZIRT p{};
  p.x = 3.0f;
  cloud.push_back(p);
  p.x = std::nanf("");
  cloud.push_back(p);
  p.x = 90.0f;
  cloud.push_back(p);
  core::RingDensity r2;
  EXPECT_EQ(r2.add(cloud), 1u);
}

TEST(DistanceWeight, WeightIsOneNearClampedFarAndInverseOfTheFittedDensity) {
  core::DistanceWeightParams p;
  p.log_fit = false;
  p.coefficients = {1.0, -0.01};  // f(d) = 1 - 0.01 d
  p.full_density_distance_m = 0.0;
  p.max_distance_m = 80.0;
  p.max_weight = 4.0;
  const core::DistanceWeight w(p);
  EXPECT_DOUBLE_EQ(w.exact(0.0), 1.0);
  EXPECT_NEAR(w.exact(50.0), 1.0 / 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(w.exact(79.0), 4.0);         // 1 / 0.21 clamped
  EXPECT_NEAR(w(50.0f), 2.0f, 2.0f * 0.0006f);  // table: half a 5 cm step of distance
  p.log_fit = true;
  p.coefficients = {0.0, -0.05};  // f(d) = exp(-0.05 d), normalised at d0 = 10 m
  p.full_density_distance_m = 10.0;
  p.max_weight = 100.0;
  const core::DistanceWeight wl(p);
  EXPECT_DOUBLE_EQ(wl.exact(5.0), 1.0);
  EXPECT_NEAR(wl.exact(30.0), std::exp(0.05 * 20.0), 1e-9);
  p.enabled = false;
  EXPECT_DOUBLE_EQ(core::DistanceWeight(p).exact(60.0), 1.0);
  // The shipped fit: 1 up to d0, growing, clamped at max_weight far away.
  const core::DistanceWeight def;
  EXPECT_DOUBLE_EQ(def.exact(3.0), 1.0);
  EXPECT_GT(def.exact(15.0), def.exact(10.0));
  EXPECT_DOUBLE_EQ(def.exact(70.0), def.params().max_weight);
}

TEST(CellFitness, CountsAndFormulaByHand) {
  LabeledCloud cloud;
  // 25 points in the 1 m cell [0,1)^2 (dense, t_min 20) and 3 points in [5,6)x[0,1) (sparse).
  for (int i = 0; i < 25; ++i) test::addPoint(&cloud, 0.5f, 0.5f, 0.0f, 1);
  for (int i = 0; i < 3; ++i) test::addPoint(&cloud, 5.5f, 0.5f, 0.0f, 2);
  test::addPoint(&cloud, std::nanf(""), 0.5f, 0.0f, 3);
  core::CellCounts c;
  core::countCells(cloud, 1.0, 40.0, 20, &c);
  EXPECT_EQ(c.dense, 1u);
  EXPECT_EQ(c.sparse, 1u);
  EXPECT_EQ(c.empty, 16u);  // two separate 3x3 rims
  EXPECT_DOUBLE_EQ(c.fitness(), 1.0 / 18.0);
  // Adjacent cells share their rim: [0,1) and [1,2) dense -> 10 empty around a 2x1 block.
  for (int i = 0; i < 25; ++i) test::addPoint(&cloud, 1.5f, 0.5f, 0.0f, 1);
  core::CellCounts c2;
  core::countCells(cloud, 1.0, 40.0, 20, &c2);
  EXPECT_EQ(c2.dense, 2u);
  EXPECT_EQ(c2.empty, 10u + 8u);
  EXPECT_DOUBLE_EQ(core::CellCounts().fitness(), 0.0);
}

}  // namespace
}  // namespace urban_detection
