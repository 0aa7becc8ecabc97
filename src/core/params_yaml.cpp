#include "urban_detection/core/params_yaml.h"

#include <filesystem>
#include <functional>
#include <map>

#include <yaml-cpp/yaml.h>

namespace urban_detection {
namespace core {

namespace {

// Binds YAML keys of one map to struct fields; apply() rejects unknown keys.
class FieldTable {
 public:
  template <typename T>
  void bind(const std::string& key, T* field) {
    setters_[key] = [field](const YAML::Node& n) { *field = n.as<T>(); };
  }
  void bindMap(const std::string& key, std::function<bool(const YAML::Node&, std::string*)> f) {
    maps_[key] = std::move(f);
  }
  bool apply(const YAML::Node& node, const std::string& where, std::string* error) const {
    if (!node.IsMap()) {
      *error = where + "expected a map of parameters";
      return false;
    }
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      const auto s = setters_.find(key);
      if (s != setters_.end()) {
        try {
          s->second(kv.second);
        } catch (const YAML::Exception& e) {
          *error = where + key + ": wrong type (" + e.what() + ")";
          return false;
        }
        continue;
      }
      const auto m = maps_.find(key);
      if (m != maps_.end()) {
        if (!m->second(kv.second, error)) return false;
        continue;
      }
      *error = where + key + ": unknown parameter";
      return false;
    }
    return true;
  }

 private:
  std::map<std::string, std::function<void(const YAML::Node&)>> setters_;
  std::map<std::string, std::function<bool(const YAML::Node&, std::string*)>> maps_;
};

bool loadRoot(const std::string& path, const std::string& section, YAML::Node* root,
              std::string* error) {
  try {
    *root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    *error = path + ": " + e.what();
    return false;
  }
  if (!section.empty() && root->IsMap() && (*root)[section]) *root = (*root)[section];
  return true;
}

bool applySegmentation(const YAML::Node& root, const std::string& where,
                       GridSegmenterParams* p, std::string* error) {
  HoughWallRefinerParams& h = p->hough;
  FieldTable hough;
  hough.bind("enabled", &h.enabled);
  hough.bind("max_range_m", &h.max_range_m);
  hough.bind("votes", &h.votes);
  hough.bind("min_line_length_m", &h.min_line_length_m);
  hough.bind("max_line_gap_m", &h.max_line_gap_m);
  hough.bind("theta_resolution_deg", &h.theta_resolution_deg);
  hough.bind("min_tall_fraction", &h.min_tall_fraction);
  hough.bind("min_mixed_wall_length_m", &h.min_mixed_wall_length_m);
  hough.bind("line_half_width_cells", &h.line_half_width_cells);
  hough.bind("extend_lines", &h.extend_lines);
  FieldTable t;
  t.bind("sensor_height_m", &p->sensor_height_m);
  t.bind("cell_size_m", &p->cell_size_m);
  t.bind("max_range_m", &p->max_range_m);
  t.bind("max_abs_height_m", &p->max_abs_height_m);
  t.bind("min_points_per_cell", &p->min_points_per_cell);
  t.bind("ground_in_sparse_cells", &p->ground_in_sparse_cells);
  t.bind("ground_max_range_m", &p->ground_max_range_m);
  t.bind("ground_tolerance_m", &p->ground_tolerance_m);
  t.bind("ground_max_step_m", &p->ground_max_step_m);
  t.bind("curb_cells_ground", &p->curb_cells_ground);
  t.bind("ground_max_gap_m", &p->ground_max_gap_m);
  t.bind("seed_radius_m", &p->seed_radius_m);
  t.bind("seed_max_abs_height_m", &p->seed_max_abs_height_m);
  t.bind("terrain_fill_iterations", &p->terrain_fill_iterations);
  t.bind("terrain_max_offset_m", &p->terrain_max_offset_m);
  t.bind("tall_min_height_m", &p->tall_min_height_m);
  t.bind("tall_min_range_m", &p->tall_min_range_m);
  t.bind("vehicle_max_height_m", &p->vehicle_max_height_m);
  t.bind("vehicle_max_length_m", &p->vehicle_max_length_m);
  t.bind("vehicle_max_width_m", &p->vehicle_max_width_m);
  t.bind("fov_top_elevation_deg", &p->fov_top_elevation_deg);
  t.bindMap("hough", [&hough, where](const YAML::Node& n, std::string* err) {
    return hough.apply(n, where + "hough/", err);
  });
  return t.apply(root, where, error);
}

bool applyHierarchical(const YAML::Node& node, const std::string& where,
                       HierarchicalGridDetectorParams* p, std::string* error) {
  DistanceWeightParams& w = p->weight;
  FieldTable weight;
  weight.bind("enabled", &w.enabled);
  weight.bind("log_fit", &w.log_fit);
  weight.bind("coefficients", &w.coefficients);
  weight.bind("full_density_distance_m", &w.full_density_distance_m);
  weight.bind("max_distance_m", &w.max_distance_m);
  weight.bind("max_weight", &w.max_weight);
  FarObjectMergerParams& fm = p->far_merge;
  FieldTable far_merge;
  far_merge.bind("max_gap_m", &fm.max_gap_m);
  far_merge.bind("max_across_gap_m", &fm.max_across_gap_m);
  far_merge.bind("min_across_overlap", &fm.min_across_overlap);
  far_merge.bind("max_z_gap_m", &fm.max_z_gap_m);
  far_merge.bind("min_range_m", &fm.min_range_m);
  far_merge.bind("max_length_m", &fm.max_length_m);
  far_merge.bind("max_width_m", &fm.max_width_m);
  FieldTable t;
  t.bind("coarse_cell_m", &p->coarse_cell_m);
  t.bind("xi", &p->xi);
  t.bind("grid_half_extent_m", &p->grid_half_extent_m);
  t.bind("max_abs_z_m", &p->max_abs_z_m);
  t.bind("psi_max_m", &p->psi_max_m);
  t.bind("dense_min_weighted_points", &p->dense_min_weighted_points);
  t.bind("radial_bridge_subcells", &p->radial_bridge_subcells);
  t.bind("far_radial_bridge_subcells", &p->far_radial_bridge_subcells);
  t.bind("bridge_range_m", &p->bridge_range_m);
  t.bind("gap_bridge_range_m", &p->gap_bridge_range_m);
  t.bind("roof_bridge_subcells", &p->roof_bridge_subcells);
  t.bind("roof_max_step_m", &p->roof_max_step_m);
  t.bind("roof_bridge_range_m", &p->roof_bridge_range_m);
  t.bind("ring_spacing_deg", &p->ring_spacing_deg);
  t.bind("dense_refinement", &p->dense_refinement);
  t.bind("min_points", &p->min_points);
  t.bind("min_weighted_points", &p->min_weighted_points);
  t.bind("max_extent_m", &p->max_extent_m);
  t.bindMap("weight", [&weight, where](const YAML::Node& n, std::string* err) {
    return weight.apply(n, where + "weight/", err);
  });
  t.bindMap("far_merge", [&far_merge, where](const YAML::Node& n, std::string* err) {
    return far_merge.apply(n, where + "far_merge/", err);
  });
  return t.apply(node, where, error);
}

bool applyKdTree(const YAML::Node& node, const std::string& where, KdTreeDetectorParams* p,
                 std::string* error) {
  FieldTable t;
  t.bind("cluster_tolerance_m", &p->cluster_tolerance_m);
  t.bind("min_cluster_size", &p->min_cluster_size);
  t.bind("max_cluster_size", &p->max_cluster_size);
  t.bind("max_extent_m", &p->max_extent_m);
  t.bind("max_abs_coordinate_m", &p->max_abs_coordinate_m);
  t.bind("sorted_search", &p->sorted_search);
  return t.apply(node, where, error);
}

// A detector file (config/hierarchical_grid.yaml, config/kdtree.yaml): `hierarchical_grid:` and `kdtree:` maps (other top-level keys are left to
// the ROS layer, e.g. marker settings, and ignored here).
bool applyDetection(const YAML::Node& root, const std::string& where,
                    HierarchicalGridDetectorParams* hier, KdTreeDetectorParams* kd,
                    std::string* error) {
  if (!root.IsMap()) {
    *error = where + "expected a map of parameters";
    return false;
  }
  if (hier && root["hierarchical_grid"] &&
      !applyHierarchical(root["hierarchical_grid"], where + "hierarchical_grid/", hier, error)) {
    return false;
  }
  if (kd && root["kdtree"] && !applyKdTree(root["kdtree"], where + "kdtree/", kd, error)) {
    return false;
  }
  return true;
}

bool applyObjectFilter(const YAML::Node& node, const std::string& where, ObjectFilterParams* p,
                       std::string* error) {
  FieldTable t;
  t.bind("enabled", &p->enabled);
  t.bind("min_points", &p->min_points);
  t.bind("max_range_m", &p->max_range_m);
  t.bind("row_gap_deg", &p->row_gap_deg);
  t.bind("max_azimuth_gap_deg", &p->max_azimuth_gap_deg);
  t.bind("jump_m", &p->jump_m);
  t.bind("min_triplets", &p->min_triplets);
  t.bind("max_jump_fraction", &p->max_jump_fraction);
  t.bind("hedge_min_intensity", &p->hedge_min_intensity);
  t.bind("hedge_min_length_m", &p->hedge_min_length_m);
  t.bind("uniform_max_intensity_std", &p->uniform_max_intensity_std);
  t.bind("uniform_min_points", &p->uniform_min_points);
  return t.apply(node, where, error);
}

bool applyClassifier(const YAML::Node& node, const std::string& where,
                     ObjectClassifierParams* p, std::string* error) {
  FieldTable t;
  t.bind("enabled", &p->enabled);
  t.bind("model", &p->model_path);
  t.bind("min_object_probability", &p->min_object_probability);
  t.bind("reject_non_objects", &p->reject_non_objects);
  return t.apply(node, where, error);
}

// The `section:` map of a detection.yaml style file (top level, or under `detection:` in a
// combined file) applied by `apply`; a file without it changes nothing.
template <typename Params, typename Apply>
bool loadDetectionSection(const std::string& path, const std::string& section, Params* params,
                          Apply apply, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  std::string where = path + ": ";
  if (root.IsMap() && root["detection"]) {
    root = root["detection"];
    where += "detection/";
  }
  if (!root.IsMap() || !root[section]) return true;
  return apply(root[section], where + section + "/", params, error);
}

}  // namespace

bool loadObjectFilterParamsYaml(const std::string& path, ObjectFilterParams* params,
                                std::string* error) {
  return loadDetectionSection(path, "object_filter", params, applyObjectFilter, error);
}

bool loadObjectClassifierParamsYaml(const std::string& path, ObjectClassifierParams* params,
                                    std::string* error) {
  if (!loadDetectionSection(path, "classifier", params, applyClassifier, error)) return false;
  // A relative model path is relative to the folder of the file that names it.
  const std::filesystem::path model(params->model_path);
  if (!params->model_path.empty() && model.is_relative()) {
    params->model_path = (std::filesystem::path(path).parent_path() / model).string();
  }
  return true;
}

bool loadGridSegmenterParamsYaml(const std::string& path, const std::string& section,
                                 GridSegmenterParams* p, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, section, &root, error)) return false;
  return applySegmentation(root, path + ": ", p, error);
}

bool loadHierarchicalGridParamsYaml(const std::string& path,
                                    HierarchicalGridDetectorParams* params, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  return applyDetection(root, path + ": ", params, nullptr, error);
}

bool loadKdTreeParamsYaml(const std::string& path, KdTreeDetectorParams* params,
                          std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  return applyDetection(root, path + ": ", nullptr, params, error);
}

bool loadPipelineParamsYaml(const std::string& path, GridSegmenterParams* segmentation,
                            HierarchicalGridDetectorParams* hierarchical,
                            KdTreeDetectorParams* kdtree, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  const std::string where = path + ": ";
  if (!root.IsMap()) {
    *error = where + "expected a map of parameters";
    return false;
  }
  if (root["segmentation"] || root["detection"]) {
    if (segmentation && root["segmentation"] &&
        !applySegmentation(root["segmentation"], where + "segmentation/", segmentation, error)) {
      return false;
    }
    return !root["detection"] ||
           applyDetection(root["detection"], where + "detection/", hierarchical, kdtree, error);
  }
  if (root["hierarchical_grid"] || root["kdtree"] || root["object_filter"] ||
      root["classifier"]) {
    return applyDetection(root, where, hierarchical, kdtree, error);
  }
  return !segmentation || applySegmentation(root, where, segmentation, error);
}

}  // namespace core
}  // namespace urban_detection
