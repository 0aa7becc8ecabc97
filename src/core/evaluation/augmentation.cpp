#include "urban_detection/core/evaluation/augmentation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

namespace urban_detection {
namespace core {

namespace {

constexpr float kRadToDeg = 57.29577951308232f;
constexpr float kDegToRad = 0.017453292519943295f;

float azimuthDeg(float x, float y) {
  return std::atan2(y, x) * kRadToDeg;
}

float elevationDeg(float x, float y, float z) {
  return std::atan2(z, std::hypot(x, y)) * kRadToDeg;
}

// Cell of a return: its row and its azimuth step.
std::int64_t cellOf(int ring, float azimuth_deg, float step_deg) {
  const auto bin = static_cast<std::int64_t>(std::floor((azimuth_deg + 180.0f) / step_deg));
  return static_cast<std::int64_t>(ring) * 100000 + bin;
}

bool finitePoint(const PointXYZIRT& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

}  // namespace

int assignRingsFromOrder(CloudXYZIRT* cloud, std::size_t min_row_points) {
  int ring = 0;
  std::size_t in_row = 0;
  bool have_prev = false;
  float prev = 0.0f;
  for (auto& p : cloud->points) {
    if (!finitePoint(p)) {
      p.ring = static_cast<std::uint16_t>(ring);
      continue;
    }
    const float a = azimuthDeg(p.x, p.y);
    if (have_prev && std::fabs(a - prev) > 180.0f && in_row >= min_row_points) {
      ring = std::min(ring + 1, RingModel::kRows - 1);
      in_row = 0;
    }
    p.ring = static_cast<std::uint16_t>(ring);
    prev = a;
    have_prev = true;
    ++in_row;
  }
  return cloud->empty() ? 0 : ring + 1;
}

RingModel RingModel::measure(const CloudXYZIRT& cloud) {
  RingModel m;
  std::array<std::vector<float>, kRows> elevations;
  std::array<std::size_t, kRows> count{};
  for (const auto& p : cloud) {
    if (!finitePoint(p) || p.ring >= kRows) continue;
    ++count[p.ring];
    const float rho = std::hypot(p.x, p.y);
    if (rho < 2.5f || rho > 60.0f) continue;
    elevations[p.ring].push_back(elevationDeg(p.x, p.y, p.z));
  }
  std::vector<std::size_t> counts;
  for (int r = 0; r < kRows; ++r) {
    auto& e = elevations[r];
    if (e.size() < 20) continue;
    std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
    m.elevation_deg[r] = e[e.size() / 2];
    m.valid[r] = true;
    counts.push_back(count[r]);
  }
  if (!counts.empty()) {
    // The fullest rows miss the fewest returns: their count gives the azimuth step.
    std::sort(counts.begin(), counts.end());
    const std::size_t full = counts[(counts.size() * 9) / 10];
    if (full >= 500) m.azimuth_step_deg = 360.0f / static_cast<float>(full);
  }
  return m;
}

int RingModel::nearestRow(float elevation) const {
  int best = -1;
  float best_d = 1e9f;
  for (int r = 0; r < kRows; ++r) {
    if (!valid[r]) continue;
    const float d = std::fabs(elevation_deg[r] - elevation);
    if (d < best_d) {
      best_d = d;
      best = r;
    }
  }
  return best;
}

std::vector<PointXYZIRT> resampleObject(const ObjectSample& object, const RingModel& rows,
                                        float yaw_rad, float range_m, float dz_m,
                                        const ResampleParams& params, std::mt19937* rng) {
  std::vector<PointXYZIRT> out;
  if (object.points.empty()) return out;
  // Turn about the sensor, then move along the line of sight (never nearer: no point is made up).
  const float c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  std::vector<PointXYZIRT> moved;
  double cx = 0.0, cy = 0.0;
  for (const auto& p : object.points) {
    if (!finitePoint(p)) continue;
    PointXYZIRT q = p;
    q.x = c * p.x - s * p.y;
    q.y = s * p.x + c * p.y;
    q.z = p.z + dz_m;
    cx += q.x;
    cy += q.y;
    moved.push_back(q);
  }
  if (moved.empty()) return out;
  cx /= static_cast<double>(moved.size());
  cy /= static_cast<double>(moved.size());
  const double r0 = std::hypot(cx, cy);
  if (r0 < 1e-3) return out;
  const double shift = std::max(0.0, static_cast<double>(range_m) - r0);
  const float ux = static_cast<float>(cx / r0), uy = static_cast<float>(cy / r0);
  for (auto& q : moved) {
    q.x += static_cast<float>(shift) * ux;
    q.y += static_cast<float>(shift) * uy;
  }
  // The source rows after the move: their mean elevation, in elevation order.
  std::map<int, std::vector<const PointXYZIRT*>> by_ring;
  for (const auto& q : moved) by_ring[q.ring].push_back(&q);
  struct SourceRow {
    float elevation;
    const std::vector<const PointXYZIRT*>* points;
  };
  std::vector<SourceRow> src;
  for (const auto& kv : by_ring) {
    double e = 0.0;
    for (const PointXYZIRT* q : kv.second) e += elevationDeg(q->x, q->y, q->z);
    src.push_back({static_cast<float>(e / kv.second.size()), &kv.second});
  }
  std::sort(src.begin(), src.end(),
            [](const SourceRow& a, const SourceRow& b) { return a.elevation < b.elevation; });
  // Spacing of the source rows around each one; one row alone: the sensor's typical 0.4 deg
  // row spacing, shrunk by the move.
  const float lone = 0.4f * static_cast<float>(r0 / (r0 + shift));
  std::normal_distribution<float> noise(0.0f, params.range_noise_m);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float step = rows.azimuth_step_deg;
  for (int m = 0; m < RingModel::kRows; ++m) {
    if (!rows.valid[m]) continue;
    const float e = rows.elevation_deg[m];
    std::size_t best = 0;
    float best_d = 1e9f;
    for (std::size_t k = 0; k < src.size(); ++k) {
      const float d = std::fabs(src[k].elevation - e);
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    float spacing = lone;
    if (src.size() > 1) {
      const float below = best > 0 ? src[best].elevation - src[best - 1].elevation : 1e9f;
      const float above =
          best + 1 < src.size() ? src[best + 1].elevation - src[best].elevation : 1e9f;
      spacing = std::min(below, above);
    }
    if (best_d > params.row_tolerance * spacing) continue;
    // One return per azimuth step: the source point nearest the step's centre.
    std::unordered_map<std::int64_t, std::pair<float, const PointXYZIRT*>> cell;
    for (const PointXYZIRT* q : *src[best].points) {
      const float a = azimuthDeg(q->x, q->y);
      const auto bin = static_cast<std::int64_t>(std::floor((a + 180.0f) / step));
      const float centre = (static_cast<float>(bin) + 0.5f) * step - 180.0f;
      const float d = std::fabs(a - centre);
      auto it = cell.find(bin);
      if (it == cell.end() || d < it->second.first) cell[bin] = {d, q};
    }
    std::vector<std::int64_t> bins;
    for (const auto& kv : cell) bins.push_back(kv.first);
    std::sort(bins.begin(), bins.end());  // deterministic order of the random draws
    for (const std::int64_t bin : bins) {
      const PointXYZIRT* q = cell[bin].second;
      const float drop = unit(*rng);
      const float dr = params.range_noise_m > 0.0f ? noise(*rng) : 0.0f;
      if (drop < params.dropout) continue;
      const float a = ((static_cast<float>(bin) + 0.5f) * step - 180.0f) * kDegToRad;
      const float rho = std::hypot(q->x, q->y);
      const float range = std::max(0.5f, std::hypot(rho, q->z) + dr);
      PointXYZIRT p = *q;
      const float el = e * kDegToRad;
      p.x = range * std::cos(el) * std::cos(a);
      p.y = range * std::cos(el) * std::sin(a);
      p.z = range * std::sin(el);
      p.ring = static_cast<std::uint16_t>(m);
      p.time = 0.0f;
      out.push_back(p);
    }
  }
  return out;
}

namespace {

// Median height of the free-ground points within `radius_m` of (x, y); with `require_free`,
// false as soon as a point within it is not free ground.
bool medianGroundZ(const CloudXYZIRT& cloud, const std::vector<bool>& free_ground, float x, float y,
                   float radius_m, std::size_t min_ground_points, bool require_free,
                   float* ground_z) {
  std::vector<float> z;
  const float r2 = radius_m * radius_m;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!finitePoint(p)) continue;
    const float dx = p.x - x, dy = p.y - y;
    if (dx * dx + dy * dy >= r2) continue;
    const bool free = i < free_ground.size() && free_ground[i];
    if (!free) {
      if (require_free) return false;
      continue;
    }
    z.push_back(p.z);
  }
  if (z.size() < std::max<std::size_t>(1, min_ground_points)) return false;
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  *ground_z = z[z.size() / 2];
  return true;
}

}  // namespace

bool freeGroundAt(const CloudXYZIRT& cloud, const std::vector<bool>& free_ground, float x, float y,
                  float radius_m, std::size_t min_ground_points, float* ground_z) {
  return medianGroundZ(cloud, free_ground, x, y, radius_m, min_ground_points, true, ground_z);
}

std::size_t pasteObject(const std::vector<PointXYZIRT>& object, std::uint32_t label,
                        const RingModel& rows, CloudXYZIRT* cloud,
                        std::vector<std::uint32_t>* labels) {
  const float step = rows.azimuth_step_deg;
  std::unordered_map<std::int64_t, float> object_range;  // nearest object return per cell
  for (const auto& p : object) {
    const std::int64_t k = cellOf(p.ring, azimuthDeg(p.x, p.y), step);
    const float r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    auto it = object_range.find(k);
    if (it == object_range.end() || r < it->second) object_range[k] = r;
  }
  std::unordered_map<std::int64_t, float> scene_range;  // nearest scene return per object cell
  CloudXYZIRT kept;
  kept.reserve(cloud->size() + object.size());
  std::vector<std::uint32_t> kept_labels;
  kept_labels.reserve(cloud->size() + object.size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const auto& p = (*cloud)[i];
    if (finitePoint(p)) {
      const std::int64_t k = cellOf(p.ring, azimuthDeg(p.x, p.y), step);
      const auto it = object_range.find(k);
      if (it != object_range.end()) {
        const float r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
        if (r > it->second) continue;  // hidden behind the pasted object
        auto s = scene_range.find(k);
        if (s == scene_range.end() || r < s->second) scene_range[k] = r;
      }
    }
    kept.push_back(p);
    kept_labels.push_back(i < labels->size() ? (*labels)[i] : 0u);
  }
  std::size_t added = 0;
  for (const auto& p : object) {
    const std::int64_t k = cellOf(p.ring, azimuthDeg(p.x, p.y), step);
    const auto s = scene_range.find(k);
    const float r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    if (s != scene_range.end() && s->second < r) continue;  // behind a nearer scene return
    kept.push_back(p);
    kept_labels.push_back(label);
    ++added;
  }
  kept.width = static_cast<std::uint32_t>(kept.size());
  kept.height = 1;
  kept.is_dense = cloud->is_dense;
  kept.header = cloud->header;
  cloud->swap(kept);
  labels->swap(kept_labels);
  return added;
}

bool groundHeightNear(const CloudXYZIRT& cloud, const std::vector<bool>& free_ground, float x,
                      float y, float radius_m, std::size_t min_ground_points, float* ground_z) {
  return medianGroundZ(cloud, free_ground, x, y, radius_m, min_ground_points, false, ground_z);
}

bool isSemanticKittiGround(std::uint16_t c) {
  return c == 40 || c == 44 || c == 48 || c == 49 || c == 60 || c == 72;
}

namespace {

enum class CopyKind { kNone, kPerson, kVehicle };

CopyKind copyKind(std::uint16_t c) {
  switch (c) {
    case 30:
    case 31:
    case 32:
    case 11:
    case 15:
    case 253:
    case 254:
    case 255:
      return CopyKind::kPerson;  // persons, riders, two-wheelers
    case 10:
    case 13:
    case 18:
    case 20:
    case 252:
    case 256:
    case 257:
    case 258:
    case 259:
      return CopyKind::kVehicle;
    default:
      return CopyKind::kNone;
  }
}

std::vector<bool> freeGround(const std::vector<std::uint32_t>& labels) {
  std::vector<bool> f(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    f[i] = (labels[i] >> 16) == 0 && isSemanticKittiGround(labels[i] & 0xFFFFu);
  }
  return f;
}

struct SourceObject {
  ObjectSample sample;
  float ground_z = 0.0f;
  float radius_m = 0.0f;  // horizontal extent about the centroid
  float range_m = 0.0f;
  float azimuth_rad = 0.0f;
  int copies = 0;
};

}  // namespace

std::vector<LabelledScan> augmentSequence(const std::vector<const LabelledScan*>& scans,
                                          const AugmentParams& params) {
  std::vector<LabelledScan> out;
  if (scans.empty()) return out;
  std::mt19937 rng(params.seed);
  // Every scan with its rows; the objects to copy.
  std::vector<LabelledScan> base(scans.size());
  std::vector<RingModel> rows(scans.size());
  std::vector<SourceObject> objects;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    base[s] = *scans[s];
    assignRingsFromOrder(&base[s].cloud);
    rows[s] = RingModel::measure(base[s].cloud);
    const std::vector<bool> free = freeGround(base[s].labels);
    std::map<std::uint32_t, std::vector<std::size_t>> members;
    for (std::size_t i = 0; i < base[s].labels.size() && i < base[s].cloud.size(); ++i) {
      const std::uint32_t l = base[s].labels[i];
      if ((l >> 16) != 0 && copyKind(l & 0xFFFFu) != CopyKind::kNone &&
          finitePoint(base[s].cloud[i])) {
        members[l].push_back(i);
      }
    }
    for (const auto& kv : members) {
      if (kv.second.size() < params.min_source_points) continue;
      SourceObject o;
      o.sample.label = kv.first;
      double cx = 0.0, cy = 0.0;
      float min_z = 1e9f;
      for (const std::size_t i : kv.second) {
        o.sample.points.push_back(base[s].cloud[i]);
        cx += base[s].cloud[i].x;
        cy += base[s].cloud[i].y;
        min_z = std::min(min_z, base[s].cloud[i].z);
      }
      cx /= static_cast<double>(kv.second.size());
      cy /= static_cast<double>(kv.second.size());
      for (const auto& p : o.sample.points) {
        o.radius_m = std::max(o.radius_m, static_cast<float>(std::hypot(p.x - cx, p.y - cy)));
      }
      o.range_m = static_cast<float>(std::hypot(cx, cy));
      o.azimuth_rad = static_cast<float>(std::atan2(cy, cx));
      if (!groundHeightNear(base[s].cloud, free, static_cast<float>(cx), static_cast<float>(cy),
                            o.radius_m + 1.5f, 5, &o.ground_z)) {
        o.ground_z = min_z;
      }
      o.copies = copyKind(kv.first & 0xFFFFu) == CopyKind::kPerson ? params.person_copies
                                                                   : params.vehicle_copies;
      if (o.copies > 0 && o.range_m < params.max_range_m) objects.push_back(std::move(o));
    }
  }
  // Augmented scans under construction, one per base scan.
  std::vector<LabelledScan> open(scans.size());
  std::vector<int> pasted(scans.size(), 0);
  std::vector<std::uint16_t> next_instance(scans.size(), kPastedInstanceBase);
  std::uniform_int_distribution<std::size_t> pick_scan(0, scans.size() - 1);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const SourceObject& o : objects) {
    for (int copy = 0; copy < o.copies; ++copy) {
      const std::size_t t = pick_scan(rng);
      if (pasted[t] == 0) open[t] = base[t];
      const std::vector<bool> free = freeGround(open[t].labels);
      for (int attempt = 0; attempt < params.placement_tries; ++attempt) {
        const float range = o.range_m + unit(rng) * (params.max_range_m - o.range_m);
        const float azimuth = (unit(rng) * 2.0f - 1.0f) * 3.14159265f;
        const float x = range * std::cos(azimuth), y = range * std::sin(azimuth);
        float ground_z = 0.0f;
        if (!freeGroundAt(open[t].cloud, free, x, y, o.radius_m + 0.3f, 3, &ground_z)) continue;
        const std::vector<PointXYZIRT> points =
            resampleObject(o.sample, rows[t], azimuth - o.azimuth_rad, range, ground_z - o.ground_z,
                           params.resample, &rng);
        if (points.size() < params.min_points) break;  // too far for this object: next copy
        const std::uint32_t label =
            (o.sample.label & 0xFFFFu) | (static_cast<std::uint32_t>(next_instance[t]++) << 16);
        if (pasteObject(points, label, rows[t], &open[t].cloud, &open[t].labels) <
            params.min_points) {
          break;
        }
        if (++pasted[t] >= params.max_objects_per_scan) {
          out.push_back(std::move(open[t]));
          pasted[t] = 0;
          next_instance[t] = kPastedInstanceBase;
        }
        break;
      }
    }
  }
  for (std::size_t t = 0; t < scans.size(); ++t) {
    if (pasted[t] > 0) out.push_back(std::move(open[t]));
  }
  return out;
}

}  // namespace core
}  // namespace urban_detection
