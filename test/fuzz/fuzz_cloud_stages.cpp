// libFuzzer target: the cloud stages on hostile clouds: GridSegmenter (simple grid, ground
// growing, terrain fill, Hough wall refinement), extractForeground, and both detectors
// (HierarchicalGridDetector, KdTreeDetector), each fed the segmented foreground and also the
// raw fuzz cloud directly (a detector must survive any LabeledCloud it is given).
//
// Input: byte 0 picks one of four parameter sets, byte 1 holds flags (bit 0: append copies of
// the cloud shifted by a few millimetres, so thousands of points share one grid cell). Then
// 7 bytes per point: a mode byte and three 16-bit coordinates. Each axis takes 2 mode bits:
// 0: centimetres (+-327 m), 1: millimetres (+-32 m), 2: a special value (NaN, +-inf, +-1e30,
// FLT_MAX, a denormal, the grid border), 3: the previous point's value (same cell).
// The stages run twice per input on the same objects (scratch buffers reused across frames, as
// in the nodelets), the second time on the cloud in reverse order.
//
// Checked: labels cover the cloud; non-finite points are unknown; label counts match the stats;
// the foreground is exactly the finite short points with their indices; objects have ids 1..n,
// at least min_points distinct indices that exist in the input and point at finite points,
// finite boxes containing their centroid, and an xy extent within max_extent_m; no point
// belongs to two objects.
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <unordered_map>
#include <vector>

#include "urban_detection/core/common/point_types.h"  // first: PCL_NO_PRECOMPILE

#include "fuzz_common.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"

namespace ud = urban_detection;
namespace core = urban_detection::core;
using urban_detection::fuzz::ByteReader;

namespace {

constexpr std::size_t kMaxPoints = 4096;
// The kd-tree baseline (PCL's Euclidean clustering) is quadratic in the size of a dense blob:
// every point's radius search returns, and FLANN sorts, the whole blob (4096 points in one
// spot: ~17 M neighbour visits per run, seconds under the sanitizers). It gets the first
// kKdTreeMaxPoints points of its input so one input stays well under a second; the grid
// stages get the whole cloud. (2 M points through both detectors: test_large_hostile_cloud.)
constexpr std::size_t kKdTreeMaxPoints = 256;
constexpr int kVariants = 4;

struct Stages {
  core::GridSegmenter segmenter;
  core::HierarchicalGridDetector grid_detector;
  core::KdTreeDetector kdtree_detector;
  Stages(const core::GridSegmenterParams& s, const core::HierarchicalGridDetectorParams& h,
         const core::KdTreeDetectorParams& k)
      : segmenter(s), grid_detector(h), kdtree_detector(k) {}
};

Stages& stages(int variant) {
  static std::unique_ptr<Stages> all[kVariants];
  if (!all[variant]) {
    core::GridSegmenterParams s;
    core::HierarchicalGridDetectorParams h;
    core::KdTreeDetectorParams k;
    switch (variant) {
      case 0:  // defaults
        break;
      case 1:  // small cells, no Hough, one-point cells count
        s.cell_size_m = 0.2;
        s.max_range_m = 30.0;
        s.min_points_per_cell = 1;
        s.hough.enabled = false;
        h.xi = 8;
        h.coarse_cell_m = 0.4;
        h.grid_half_extent_m = 30.0;
        h.min_points = 1;
        k.min_cluster_size = 1;
        break;
      case 2:  // coarse grid only, Hough with short lines
        s.cell_size_m = 1.0;
        s.hough.min_line_length_m = 2.0;
        s.hough.votes = 2;
        s.hough.line_half_width_cells = 3;
        h.dense_refinement = false;
        h.xi = 1;
        h.max_extent_m = 1000.0;
        k.cluster_tolerance_m = 2.0;
        k.max_extent_m = 1000.0;
        break;
      default:  // extreme but valid
        s.cell_size_m = 0.05;
        s.max_range_m = 10.0;
        s.ground_max_gap_m = 0.0;
        s.terrain_fill_iterations = 0;
        s.hough.theta_resolution_deg = 45.0;
        h.grid_half_extent_m = 1.0;
        h.psi_max_m = 0.0;
        h.radial_bridge_subcells = 8;
        h.far_radial_bridge_subcells = 0;
        h.bridge_range_m = 0.0;
        h.gap_bridge_range_m = 0.0;
        h.dense_min_weighted_points = 0.0;
        k.cluster_tolerance_m = 0.01;
        k.max_abs_coordinate_m = 1e5;
        break;
    }
    all[variant] = std::make_unique<Stages>(s, h, k);
  }
  return *all[variant];
}

float special(std::uint16_t v) {
  static const float kTable[] = {std::numeric_limits<float>::quiet_NaN(),
                                 std::numeric_limits<float>::infinity(),
                                 -std::numeric_limits<float>::infinity(),
                                 1e30f,
                                 -1e30f,
                                 FLT_MAX,
                                 -FLT_MAX,
                                 std::numeric_limits<float>::denorm_min(),
                                 -0.0f,
                                 80.0f,
                                 -80.0f,
                                 79.99999f,
                                 -1.73f,
                                 1e5f,
                                 -std::numeric_limits<float>::quiet_NaN(),
                                 20.0f};
  return kTable[v % 16];
}

bool finite(const ud::LabeledPoint& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// Checks one detector's output against its input cloud.
void checkObjects(const ud::LabeledCloud& input, const std::vector<core::DetectedObject>& objects,
                  std::size_t min_points, double max_extent_m) {
  std::unordered_map<std::uint32_t, std::size_t> position_of;  // index field -> position
  for (std::size_t i = 0; i < input.size(); ++i) position_of[input[i].index] = i;
  std::vector<std::uint8_t> used(input.size(), 0);
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const core::DetectedObject& o = objects[k];
    UD_FUZZ_CHECK(o.id == k + 1);
    UD_FUZZ_CHECK(o.indices.size() >= min_points);
    for (const std::uint32_t idx : o.indices) {
      const auto it = position_of.find(idx);
      UD_FUZZ_CHECK(it != position_of.end());
      UD_FUZZ_CHECK(!used[it->second]);  // in no other object, not twice in this one
      used[it->second] = 1;
      const ud::LabeledPoint& p = input[it->second];
      UD_FUZZ_CHECK(finite(p));
      const float eps = 1e-3f * (1.0f + std::fabs(p.x) + std::fabs(p.y) + std::fabs(p.z));
      UD_FUZZ_CHECK(p.x >= o.min_pt.x() - eps && p.x <= o.max_pt.x() + eps);
      UD_FUZZ_CHECK(p.y >= o.min_pt.y() - eps && p.y <= o.max_pt.y() + eps);
      UD_FUZZ_CHECK(p.z >= o.min_pt.z() - eps && p.z <= o.max_pt.z() + eps);
    }
    UD_FUZZ_CHECK(o.centroid.allFinite() && o.min_pt.allFinite() && o.max_pt.allFinite());
    UD_FUZZ_CHECK(o.obb_center.allFinite() && o.obb_size.allFinite() &&
                  std::isfinite(o.obb_yaw_rad));
    for (int a = 0; a < 3; ++a) {
      const float eps = 1e-3f * (1.0f + std::fabs(o.centroid[a]));
      UD_FUZZ_CHECK(o.min_pt[a] <= o.centroid[a] + eps && o.centroid[a] <= o.max_pt[a] + eps);
    }
    UD_FUZZ_CHECK(o.max_pt.x() - o.min_pt.x() <= max_extent_m * (1 + 1e-6) + 1e-4);
    UD_FUZZ_CHECK(o.max_pt.y() - o.min_pt.y() <= max_extent_m * (1 + 1e-6) + 1e-4);
  }
}

void runFrame(Stages& st, const ud::CloudXYZIRT& cloud) {
  std::vector<core::SegmentClass> labels;
  st.segmenter.segment(cloud, &labels);
  UD_FUZZ_CHECK(labels.size() == cloud.size());
  std::size_t counts[5] = {0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int l = static_cast<int>(labels[i]);
    UD_FUZZ_CHECK(l >= 0 && l < 5);
    ++counts[l];
    const ud::PointXYZIRT& p = cloud[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
      UD_FUZZ_CHECK(labels[i] == core::SegmentClass::kUnknown);
    }
  }
  const core::SegmentationStats& s = st.segmenter.stats();
  UD_FUZZ_CHECK(s.points_unknown == counts[0] && s.points_clutter == counts[1] &&
                s.points_ground == counts[2] && s.points_tall == counts[3] &&
                s.points_short == counts[4]);

  ud::LabeledCloud foreground;
  core::extractForeground(cloud, labels, &foreground);
  UD_FUZZ_CHECK(foreground.size() == counts[4]);
  for (const ud::LabeledPoint& q : foreground.points) {
    UD_FUZZ_CHECK(q.index < cloud.size() && labels[q.index] == core::SegmentClass::kShort);
    UD_FUZZ_CHECK(q.x == cloud[q.index].x && q.y == cloud[q.index].y && q.z == cloud[q.index].z);
  }

  // The raw cloud as a detector input: index field scrambled so the mapping is checked.
  ud::LabeledCloud raw;
  raw.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    raw[i].x = cloud[i].x;
    raw[i].y = cloud[i].y;
    raw[i].z = cloud[i].z;
    raw[i].intensity = cloud[i].intensity;
    raw[i].label = static_cast<std::uint32_t>(core::SegmentClass::kShort);
    raw[i].index = static_cast<std::uint32_t>(3 * i + 7);
  }

  std::vector<core::DetectedObject> objects;
  const core::HierarchicalGridDetectorParams& hp = st.grid_detector.params();
  const core::KdTreeDetectorParams& kp = st.kdtree_detector.params();
  for (const ud::LabeledCloud* in : {&foreground, &raw}) {
    st.grid_detector.detect(*in, &objects);
    checkObjects(*in, objects, static_cast<std::size_t>(hp.min_points), hp.max_extent_m);
    UD_FUZZ_CHECK(st.grid_detector.stats().objects == objects.size());
    ud::LabeledCloud head;
    const ud::LabeledCloud* kd_in = in;
    if (in->size() > kKdTreeMaxPoints) {
      head.points.assign(in->points.begin(), in->points.begin() + kKdTreeMaxPoints);
      head.width = static_cast<std::uint32_t>(head.size());
      head.height = 1;
      kd_in = &head;
    }
    st.kdtree_detector.detect(*kd_in, &objects);
    checkObjects(*kd_in, objects, static_cast<std::size_t>(kp.min_cluster_size), kp.max_extent_m);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  Stages& st = stages(in.u8() % kVariants);
  const std::uint8_t flags = in.u8();

  ud::CloudXYZIRT cloud;
  float prev[3] = {0.0f, 0.0f, 0.0f};
  while (in.remaining() >= 7 && cloud.size() < kMaxPoints) {
    const std::uint8_t mode = in.u8();
    ud::PointXYZIRT p;
    float* xyz[3] = {&p.x, &p.y, &p.z};
    for (int a = 0; a < 3; ++a) {
      const std::int16_t v = in.i16();
      switch ((mode >> (2 * a)) & 3) {
        case 0:
          *xyz[a] = v * 0.01f;
          break;
        case 1:
          *xyz[a] = v * 0.001f;
          break;
        case 2:
          *xyz[a] = special(static_cast<std::uint16_t>(v));
          break;
        default:
          *xyz[a] = prev[a];
          break;
      }
      prev[a] = *xyz[a];
    }
    p.intensity = static_cast<float>(mode);
    p.ring = static_cast<std::uint16_t>(mode >> 2);
    p.time = 0.0f;
    cloud.push_back(p);
  }
  if ((flags & 1) && !cloud.empty()) {
    // Copies shifted by 1 mm steps: a dense blob in the cells of the original points.
    const std::size_t n = cloud.size();
    for (std::size_t k = 1; cloud.size() < kMaxPoints; ++k) {
      for (std::size_t i = 0; i < n && cloud.size() < kMaxPoints; ++i) {
        ud::PointXYZIRT p = cloud[i];
        p.x += 0.001f * static_cast<float>(k % 7);
        p.z += 0.001f * static_cast<float>(k % 5);
        cloud.push_back(p);
      }
    }
  }
  runFrame(st, cloud);
  ud::CloudXYZIRT reversed;
  reversed.points.assign(cloud.points.rbegin(), cloud.points.rend());
  reversed.width = static_cast<std::uint32_t>(reversed.size());
  reversed.height = 1;
  runFrame(st, reversed);
  return 0;
}
