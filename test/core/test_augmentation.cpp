// Training-example augmentation (augmentation.h): rows recovered from the point order, range
// re-sampling that keeps only the rows the sensor would hit, pasting that removes what the
// pasted object hides, and deterministic augmented scans. The scenes are scanned by a small
// ray caster with an HDL-64E-like row layout, so the expected rows are known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "urban_detection/core/evaluation/augmentation.h"

namespace urban_detection {
namespace core {
namespace {

constexpr float kPi = 3.14159265f;
constexpr float kStepDeg = 0.2f;  // azimuth step of the test sensor
constexpr float kSensorHeight = 1.73f;

float rowElevationDeg(int m) {
  return 2.0f - m * (26.8f / 63.0f);  // +2 .. -24.8 deg, top laser first (KITTI's order)
}

struct Cylinder {
  float x, y, radius, height;  // standing on the ground (z = -kSensorHeight)
  std::uint32_t label;
};

// Scans a flat ground inside a round building with vertical cylinders, row after row, each row a
// sweep of azimuth from -180 deg (the order of KITTI files); returns the cloud and its
// SemanticKITTI labels (ground: road 40).
LabelledScan scan(const std::vector<Cylinder>& cylinders, float max_range = 70.0f) {
  LabelledScan s;
  const int steps = static_cast<int>(std::lround(360.0f / kStepDeg));
  for (int m = 0; m < 64; ++m) {
    const float el = rowElevationDeg(m) * kPi / 180.0f;
    for (int b = 0; b < steps; ++b) {
      const float az = ((b + 0.5f) * kStepDeg - 180.0f) * kPi / 180.0f;
      const float dx = std::cos(el) * std::cos(az), dy = std::cos(el) * std::sin(az),
                  dz = std::sin(el);
      float best_t = dz < 0.0f ? -kSensorHeight / dz : 1e9f;
      std::uint32_t label = 40;
      for (const Cylinder& c : cylinders) {
        // Horizontal ray-circle intersection, then the height test.
        const float a = dx * dx + dy * dy;
        const float bq = -2.0f * (dx * c.x + dy * c.y);
        const float cq = c.x * c.x + c.y * c.y - c.radius * c.radius;
        const float disc = bq * bq - 4.0f * a * cq;
        if (disc < 0.0f) continue;
        const float t = (-bq - std::sqrt(disc)) / (2.0f * a);
        const float z = t * dz;
        if (t > 0.0f && t < best_t && z >= -kSensorHeight && z <= -kSensorHeight + c.height) {
          best_t = t;
          label = c.label;
        }
      }
      // A building all around at 50 m, so that every row has returns (as on a street).
      const float t_wall = 50.0f / std::hypot(dx, dy);
      if (t_wall < best_t) {
        best_t = t_wall;
        label = 50;
      }
      if (best_t > max_range) continue;
      PointXYZIRT p;
      p.x = best_t * dx;
      p.y = best_t * dy;
      p.z = best_t * dz;
      p.intensity = 10.0f;
      p.ring = 0;
      p.time = 0.0f;
      s.cloud.push_back(p);
      s.labels.push_back(label);
    }
  }
  return s;
}

ObjectSample objectOf(const LabelledScan& s, std::uint32_t label) {
  ObjectSample o;
  o.label = label;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    if (s.labels[i] == label) o.points.push_back(s.cloud[i]);
  }
  return o;
}

constexpr std::uint32_t kPerson = 30u | (7u << 16);

TEST(Augmentation, RowsFromPointOrder) {
  LabelledScan s = scan({});
  EXPECT_EQ(assignRingsFromOrder(&s.cloud), 64);
  const RingModel rows = RingModel::measure(s.cloud);
  int valid = 0;
  for (int m = 0; m < 64; ++m) {
    if (!rows.valid[m]) continue;
    ++valid;
    EXPECT_NEAR(rows.elevation_deg[m], rowElevationDeg(m), 0.01) << "row " << m;
  }
  EXPECT_EQ(valid, 64);
  EXPECT_NEAR(rows.azimuth_step_deg, kStepDeg, 0.01);
}

TEST(Augmentation, ResamplingKeepsOnlyTheRowsTheSensorWouldHit) {
  // A person (0.25 m radius, 1.8 m tall) at 8 m, moved to 24 m.
  LabelledScan near = scan({{8.0f, 0.0f, 0.25f, 1.8f, kPerson}});
  assignRingsFromOrder(&near.cloud);
  const RingModel rows = RingModel::measure(near.cloud);
  ObjectSample person = objectOf(near, kPerson);
  ASSERT_GT(person.points.size(), 100u);
  ResampleParams p;
  p.range_noise_m = 0.0f;
  p.dropout = 0.0f;
  std::mt19937 rng(3);
  const float yaw = 0.7f;
  const std::vector<PointXYZIRT> far = resampleObject(person, rows, yaw, 24.0f, 0.0f, p, &rng);
  // The rows the sensor has on the person at 24 m (front face at about 23.75 m).
  std::set<int> expected;
  for (int m = 0; m < 64; ++m) {
    const float z = 23.75f * std::tan(rowElevationDeg(m) * kPi / 180.0f);
    if (z >= -kSensorHeight && z <= -kSensorHeight + 1.8f) expected.insert(m);
  }
  std::set<int> got;
  for (const auto& q : far) got.insert(q.ring);
  ASSERT_FALSE(got.empty());
  // Every row used is one the sensor would hit; at most the edge row either side differs.
  for (const int m : got) {
    EXPECT_TRUE(expected.count(m) || expected.count(m - 1) || expected.count(m + 1)) << m;
  }
  EXPECT_GE(got.size() + 1, expected.size());
  EXPECT_LE(got.size(), expected.size() + 1);
  // Far fewer rows than near, each return on its row's elevation and azimuth step.
  std::set<int> near_rows;
  for (const auto& q : person.points) near_rows.insert(q.ring);
  EXPECT_LT(got.size() * 2, near_rows.size());
  for (const auto& q : far) {
    const float el = std::atan2(q.z, std::hypot(q.x, q.y)) * 180.0f / kPi;
    EXPECT_NEAR(el, rows.elevation_deg[q.ring], 1e-3);
    const float az = std::atan2(q.y, q.x) * 180.0f / kPi + 180.0f;
    const float frac = az / rows.azimuth_step_deg - std::floor(az / rows.azimuth_step_deg);
    EXPECT_NEAR(frac, 0.5f, 0.02f);
    EXPECT_NEAR(std::hypot(q.x, q.y), 24.0f, 0.6f);
  }
  // Per row, the person's 0.5 m width at 24 m: about 0.5 / (24 * 0.2 deg) = 6 returns.
  std::map<int, int> per_row;
  for (const auto& q : far) ++per_row[q.ring];
  for (const auto& kv : per_row) EXPECT_LE(kv.second, 8) << "row " << kv.first;
  // The heading about the sensor moved with the yaw.
  double cx = 0, cy = 0;
  for (const auto& q : far) {
    cx += q.x;
    cy += q.y;
  }
  EXPECT_NEAR(std::atan2(cy, cx), yaw, 0.02);
}

TEST(Augmentation, PastingRemovesWhatTheObjectHides) {
  // A scene with a pole at 6 m straight ahead; the person pasted at 12 m behind it and to the
  // side: ground returns behind the person go, the person's returns behind the pole go.
  LabelledScan scene = scan({{6.0f, 0.0f, 0.05f, 3.0f, 80u}});
  assignRingsFromOrder(&scene.cloud);
  const RingModel rows = RingModel::measure(scene.cloud);
  LabelledScan near = scan({{8.0f, 0.0f, 0.3f, 1.8f, kPerson}});
  assignRingsFromOrder(&near.cloud);
  ResampleParams p;
  p.range_noise_m = 0.0f;
  p.dropout = 0.0f;
  std::mt19937 rng(1);
  const std::vector<PointXYZIRT> person =
      resampleObject(objectOf(near, kPerson), rows, 0.0f, 12.0f, 0.0f, p, &rng);
  ASSERT_GT(person.size(), 20u);
  const std::size_t before = scene.cloud.size();
  const std::uint32_t label = 30u | (static_cast<std::uint32_t>(kPastedInstanceBase) << 16);
  const std::size_t added = pasteObject(person, label, rows, &scene.cloud, &scene.labels);
  ASSERT_EQ(scene.cloud.size(), scene.labels.size());
  EXPECT_GT(added, 0u);
  EXPECT_LT(added, person.size());  // the pole hides some of it
  std::size_t pasted = 0, ground_behind = 0, pole = 0;
  for (std::size_t i = 0; i < scene.cloud.size(); ++i) {
    const auto& q = scene.cloud[i];
    if (scene.labels[i] == label) {
      ++pasted;
      // No pasted return in the pole's azimuth steps (it is behind the pole).
      EXPECT_GT(std::fabs(std::atan2(q.y, q.x)), 0.05f / 6.0f - 0.004f);
    }
    if (scene.labels[i] == 80u) ++pole;
    // No ground return left behind the person (same row and azimuth step, farther).
    if (scene.labels[i] == 40u && std::hypot(q.x, q.y) > 12.3f &&
        std::fabs(std::atan2(q.y, q.x)) < 0.3f / 12.0f - 0.005f) {
      ++ground_behind;
    }
  }
  EXPECT_EQ(pasted, added);
  EXPECT_GT(pole, 0u);
  EXPECT_EQ(ground_behind, 0u);
  EXPECT_LT(scene.cloud.size(), before + added);  // ground hidden by the person removed
}

TEST(Augmentation, SequenceIsDeterministicAndPlacesOnFreeGround) {
  std::vector<LabelledScan> scans;
  scans.push_back(
      scan({{7.0f, 2.0f, 0.3f, 1.8f, kPerson}, {-9.0f, 4.0f, 1.0f, 1.5f, 10u | (3u << 16)}}));
  scans.push_back(scan({{10.0f, -3.0f, 0.3f, 1.7f, 30u | (9u << 16)}}));
  std::vector<const LabelledScan*> in = {&scans[0], &scans[1]};
  AugmentParams p;
  p.person_copies = 6;
  p.vehicle_copies = 2;
  p.max_range_m = 35.0f;
  const std::vector<LabelledScan> a = augmentSequence(in, p);
  const std::vector<LabelledScan> b = augmentSequence(in, p);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].cloud.size(), b[k].cloud.size());
    EXPECT_EQ(0, std::memcmp(a[k].cloud.points.data(), b[k].cloud.points.data(),
                             a[k].cloud.size() * sizeof(PointXYZIRT)));
    EXPECT_EQ(a[k].labels, b[k].labels);
  }
  p.seed = 2;
  const std::vector<LabelledScan> c = augmentSequence(in, p);
  bool differs = c.size() != a.size();
  for (std::size_t k = 0; !differs && k < a.size(); ++k) differs = a[k].labels != c[k].labels;
  EXPECT_TRUE(differs);
  // Every pasted object stands on the ground, at least as far as its source.
  std::size_t pasted_objects = 0;
  for (const LabelledScan& s : a) {
    std::map<std::uint32_t, std::pair<float, float>> z_and_range;  // min z, min range
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      if ((s.labels[i] >> 16) < kPastedInstanceBase) continue;
      auto& e = z_and_range.emplace(s.labels[i], std::make_pair(1e9f, 1e9f)).first->second;
      e.first = std::min(e.first, s.cloud[i].z);
      e.second = std::min(e.second, static_cast<float>(std::hypot(s.cloud[i].x, s.cloud[i].y)));
    }
    for (const auto& kv : z_and_range) {
      ++pasted_objects;
      EXPECT_LT(kv.second.first, -kSensorHeight + 0.8f);
      EXPECT_GT(kv.second.first, -kSensorHeight - 0.2f);
      EXPECT_GT(kv.second.second, 6.0f);
      EXPECT_LT(kv.second.second, 36.0f);
    }
  }
  EXPECT_GE(pasted_objects, 8u);
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
