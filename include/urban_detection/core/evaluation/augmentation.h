/// \file augmentation.h
/// Training examples the sensor would have given, made from labelled real scans (ROS-free).
///
/// Two operations on a scan whose points carry their SemanticKITTI labels:
/// - **range resampling**: an object moved farther from the sensor along its line of sight (and
///   turned about the sensor) is re-sampled as the HDL-64E would see it there: only the scan
///   rows whose elevation still meets it, one return per azimuth step of each row, each return
///   snapped onto its row, with range noise and dropouts. So a near pedestrian shows what a far
///   one looks like (a few rows, a few points per row).
/// - **object pasting** (ground-truth sampling, as LiDAR detectors are trained): the re-sampled
///   object is placed into a scan on free ground, its bottom on that ground; the scan's returns
///   it occludes (same row and azimuth step, farther) are removed, and its own returns hidden
///   behind nearer scan points are dropped.
/// The rows of a KITTI scan are recovered from the order of its points (each laser's returns are
/// stored as one sweep of azimuth; assignRingsFromOrder) and their elevations measured per scan
/// (RingModel). Augmented scans are for training only, never scored.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Sets `ring` of a KITTI-ordered scan (laser after laser, each a sweep of azimuth): a new row
/// starts where the azimuth wraps around, after at least `min_row_points` points of the
/// current row. Rows are numbered from 0 in storage order (top laser first in KITTI files) and
/// clamped to 63. Returns the number of rows found.
int assignRingsFromOrder(CloudXYZIRT* cloud, std::size_t min_row_points = 200);

/// Elevation of each scan row as seen from the sensor, and the azimuth step of a row.
struct RingModel {
  static constexpr int kRows = 64;
  std::array<float, kRows>
      elevation_deg{};              ///< median elevation of the row's returns 2.5-60 m away
  std::array<bool, kRows> valid{};  ///< row seen in the scan
  float azimuth_step_deg = 0.17f;   ///< HDL-64E at 10 Hz: about 2,080 returns per row

  /// Measures the rows of a scan whose rings are set (assignRingsFromOrder).
  static RingModel measure(const CloudXYZIRT& cloud);
  /// The row whose elevation is nearest `elevation_deg`, or -1 when none is valid.
  int nearestRow(float elevation_deg) const;
};

/// Parameters of the re-sampling.
struct ResampleParams {
  float range_noise_m = 0.02f;  ///< [m] standard deviation of the range noise added
  float dropout = 0.05f;        ///< [0..1] probability that a return is lost
  /// [0..1] a sensor row takes the object's nearest source row when the elevation gap is at most
  /// this share of the source rows' spacing there (beyond the object's top or bottom: no return)
  float row_tolerance = 0.6f;
};

/// An object's points with the rows they were measured on (ring set).
struct ObjectSample {
  std::vector<PointXYZIRT> points;
  std::uint32_t label = 0;  ///< SemanticKITTI label (class | instance << 16) for every point
};

/// The object seen from the sensor after turning it by `yaw_rad` about the sensor's z axis,
/// moving it along its line of sight to `range_m` (horizontal distance of its centroid; at
/// least its current one: points are only removed, never invented) and lifting it by `dz_m`.
/// Each valid row of `rows` whose elevation lies within the moved object's rows (row_tolerance)
/// takes the points of the nearest moved source row, snapped onto its own elevation; per row,
/// one point per azimuth step (the nearest to the step's centre). Then range noise and
/// dropouts from `rng`. Rings of the output are the sensor rows.
std::vector<PointXYZIRT> resampleObject(const ObjectSample& object, const RingModel& rows,
                                        float yaw_rad, float range_m, float dz_m,
                                        const ResampleParams& params, std::mt19937* rng);

/// Where an object may stand in a scan: `free_ground[i]` tells whether point i is ground
/// (road, parking, sidewalk, other ground, terrain) and belongs to no object. A place is free
/// when every scan point whose horizontal distance to (x, y) is below `radius_m` is free
/// ground and at least `min_ground_points` of them are; `ground_z` is their median height.
bool freeGroundAt(const CloudXYZIRT& cloud, const std::vector<bool>& free_ground, float x, float y,
                  float radius_m, std::size_t min_ground_points, float* ground_z);

/// Pastes re-sampled object points (rings = sensor rows) into a scan with its labels: scan
/// points in the same row and azimuth step as an object point and farther are removed; object
/// points behind a nearer scan point of their cell are dropped. Returns the number of object
/// points added. `labels` stays one per point.
std::size_t pasteObject(const std::vector<PointXYZIRT>& object, std::uint32_t label,
                        const RingModel& rows, CloudXYZIRT* cloud,
                        std::vector<std::uint32_t>* labels);

/// Median height of the free-ground points within `radius_m` of (x, y), whatever else is
/// there; false with fewer than `min_ground_points` of them.
bool groundHeightNear(const CloudXYZIRT& cloud, const std::vector<bool>& free_ground, float x,
                      float y, float radius_m, std::size_t min_ground_points, float* ground_z);

/// True for SemanticKITTI's ground classes (road, parking, sidewalk, other ground, lane
/// marking, terrain).
bool isSemanticKittiGround(std::uint16_t semantic_class);

/// One labelled scan (SemanticKITTI labels, one per point).
struct LabelledScan {
  CloudXYZIRT cloud;
  std::vector<std::uint32_t> labels;
};

/// How many examples to make from one sequence's scans.
struct AugmentParams {
  int person_copies = 8;         ///< [-] copies of each person and cyclist (rider, bicycle)
  int vehicle_copies = 1;        ///< [-] copies of each vehicle
  int max_objects_per_scan = 4;  ///< [-] pasted into one augmented scan
  float max_range_m = 50.0f;     ///< [m] copies are placed between the object's range and this
  std::size_t min_source_points = 10;  ///< [-] smaller labelled objects are not copied
  std::size_t min_points = 5;          ///< [-] copies left with fewer returns are not pasted
  int placement_tries = 30;            ///< [-] random places tried for each copy
  std::uint32_t seed = 1;              ///< the same seed and scans give the same examples
  ResampleParams resample;
};

/// Instance ids of pasted objects start here (SemanticKITTI's own are far below).
constexpr std::uint16_t kPastedInstanceBase = 0xF000;

/// Copies of the sequence's persons, cyclists and vehicles, re-sampled farther away and at other
/// headings, pasted on free ground into the sequence's scans (each augmented scan is one of
/// `scans` with up to max_objects_per_scan objects added, their instances from
/// kPastedInstanceBase). Deterministic for a given seed.
std::vector<LabelledScan> augmentSequence(const std::vector<const LabelledScan*>& scans,
                                          const AugmentParams& params);

}  // namespace core
}  // namespace urban_detection
