/// \file tunable_fields.h
/// Which parameters each dynamic_reconfigure Config (cfg/*.cfg) mirrors, listed once per
/// Config. A list is a functor `fields(config, params, f)` calling f(config field, params field)
/// for every tunable field (either side may be const); toConfig() and fromConfig() copy through
/// it in either direction, so a new tunable parameter is one line here plus its .cfg entry.
/// Header-only and free of the generated Config headers (they exist only for the nodelet
/// library, built after gencfg): the lists are templates on the Config type.
#pragma once

#include <type_traits>

namespace urban_detection {
namespace ros_conv {

/// A Config holding the tunable fields of `params`.
template <class Config, class Params, class Fields>
Config toConfig(const Params& params, Fields fields) {
  Config config;
  fields(config, params,
         [](auto& c, const auto& p) { c = static_cast<std::decay_t<decltype(c)>>(p); });
  return config;
}

/// `base` with its tunable fields replaced by those of `config` (the others are not in the cfg).
template <class Config, class Params, class Fields>
Params fromConfig(const Config& config, Params base, Fields fields) {
  fields(config, base,
         [](const auto& c, auto& p) { p = static_cast<std::decay_t<decltype(p)>>(c); });
  return base;
}

/// core::GridSegmenterParams <-> GridSegmentationConfig.
struct GridSegmenterTunables {
  template <class C, class P, class F>
  void operator()(C& c, P& p, F f) const {
    f(c.sensor_height_m, p.sensor_height_m);
    f(c.min_points_per_cell, p.min_points_per_cell);
    f(c.ground_max_range_m, p.ground_max_range_m);
    f(c.ground_tolerance_m, p.ground_tolerance_m);
    f(c.ground_max_step_m, p.ground_max_step_m);
    f(c.tall_min_height_m, p.tall_min_height_m);
    f(c.tall_min_range_m, p.tall_min_range_m);
    f(c.vehicle_max_height_m, p.vehicle_max_height_m);
    f(c.hough_enabled, p.hough.enabled);
    f(c.hough_votes, p.hough.votes);
    f(c.hough_min_line_length_m, p.hough.min_line_length_m);
    f(c.hough_max_line_gap_m, p.hough.max_line_gap_m);
    f(c.hough_min_tall_fraction, p.hough.min_tall_fraction);
    f(c.hough_min_mixed_wall_length_m, p.hough.min_mixed_wall_length_m);
  }
};

/// core::HierarchicalGridDetectorParams <-> HierarchicalGridDetectorConfig.
struct HierarchicalGridTunables {
  template <class C, class P, class F>
  void operator()(C& c, P& p, F f) const {
    f(c.coarse_cell_m, p.coarse_cell_m);
    f(c.xi, p.xi);
    f(c.psi_max_m, p.psi_max_m);
    f(c.dense_refinement, p.dense_refinement);
    f(c.dense_min_weighted_points, p.dense_min_weighted_points);
    f(c.weight_enabled, p.weight.enabled);
    f(c.radial_bridge_subcells, p.radial_bridge_subcells);
    f(c.far_radial_bridge_subcells, p.far_radial_bridge_subcells);
    f(c.bridge_range_m, p.bridge_range_m);
    f(c.gap_bridge_range_m, p.gap_bridge_range_m);
    f(c.roof_bridge_subcells, p.roof_bridge_subcells);
    f(c.roof_max_step_m, p.roof_max_step_m);
    f(c.roof_bridge_range_m, p.roof_bridge_range_m);
    f(c.ring_spacing_deg, p.ring_spacing_deg);
    f(c.min_points, p.min_points);
    f(c.min_weighted_points, p.min_weighted_points);
    f(c.max_extent_m, p.max_extent_m);
    f(c.far_merge_max_gap_m, p.far_merge.max_gap_m);
    f(c.far_merge_min_range_m, p.far_merge.min_range_m);
  }
};

/// core::KdTreeDetectorParams <-> KdTreeDetectorConfig.
struct KdTreeTunables {
  template <class C, class P, class F>
  void operator()(C& c, P& p, F f) const {
    f(c.cluster_tolerance_m, p.cluster_tolerance_m);
    f(c.min_cluster_size, p.min_cluster_size);
    f(c.max_cluster_size, p.max_cluster_size);
    f(c.max_extent_m, p.max_extent_m);
  }
};

/// ros_conv::ObjectMarkerParams <-> ObjectMarkersConfig.
struct ObjectMarkerTunables {
  template <class C, class P, class F>
  void operator()(C& c, P& p, F f) const {
    f(c.show_ids, p.show_ids);
    f(c.box_alpha, p.box_alpha);
    f(c.text_size_m, p.text_size_m);
    f(c.min_box_size_m, p.min_box_size_m);
  }
};

}  // namespace ros_conv
}  // namespace urban_detection
