#include "urban_detection/core/params/params_yaml.h"

#include <algorithm>
#include <filesystem>

#include <yaml-cpp/yaml.h>

#include "urban_detection/core/params/field_yaml.h"

namespace urban_detection {
namespace core {

namespace {

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

// A detector file (config/hierarchical_grid.yaml, config/kdtree.yaml): `hierarchical_grid:` and
// `kdtree:` maps (other top-level keys are left to the ROS layer, e.g. marker settings, and ignored
// here).
bool applyDetection(const YAML::Node& root, const std::string& where,
                    HierarchicalGridDetectorParams* hier, KdTreeDetectorParams* kd,
                    std::string* error) {
  if (!root.IsMap()) {
    *error = where + "expected a map of parameters";
    return false;
  }
  if (hier && root["hierarchical_grid"] &&
      !applyFieldsYaml(root["hierarchical_grid"], where + "hierarchical_grid/", hier, error)) {
    return false;
  }
  if (kd && root["kdtree"] && !applyFieldsYaml(root["kdtree"], where + "kdtree/", kd, error)) {
    return false;
  }
  return true;
}

// The `section:` map of a detection.yaml style file (top level, or under `detection:` in a
// combined file) applied to `params`; a file without it changes nothing.
template <typename Params>
bool loadDetectionSection(const std::string& path, const std::string& section, Params* params,
                          std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  std::string where = path + ": ";
  if (root.IsMap() && root["detection"]) {
    root = root["detection"];
    where += "detection/";
  }
  if (!root.IsMap() || !root[section]) return true;
  return applyFieldsYaml(root[section], where + section + "/", params, error);
}

}  // namespace

bool loadObjectClassifierParamsYaml(const std::string& path, ObjectClassifierParams* params,
                                    std::string* error) {
  if (!loadDetectionSection(path, "classifier", params, error)) return false;
  // A relative model path is relative to the folder of the file that names it.
  const std::filesystem::path model(params->model_path);
  if (!params->model_path.empty() && model.is_relative()) {
    params->model_path = (std::filesystem::path(path).parent_path() / model).string();
  }
  return true;
}

bool loadBoxFittingParamsYaml(const std::string& path, BoxFittingParams* params,
                              std::string* error) {
  return loadDetectionSection(path, "box_fitting", params, error);
}

bool loadGridSegmenterParamsYaml(const std::string& path, const std::string& section,
                                 GridSegmenterParams* p, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, section, &root, error)) return false;
  return applyFieldsYaml(root, path + ": ", p, error);
}

bool loadCameraStageParamsYaml(const std::string& path, CameraStageParams* params,
                               std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  return applyFieldsYaml(root, path + ": ", params, error);
}

bool loadHierarchicalGridParamsYaml(const std::string& path, HierarchicalGridDetectorParams* params,
                                    std::string* error) {
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
        !applyFieldsYaml(root["segmentation"], where + "segmentation/", segmentation, error)) {
      return false;
    }
    return !root["detection"] ||
           applyDetection(root["detection"], where + "detection/", hierarchical, kdtree, error);
  }
  if (root["hierarchical_grid"] || root["kdtree"] || root["classifier"]) {
    return applyDetection(root, where, hierarchical, kdtree, error);
  }
  return !segmentation || applyFieldsYaml(root, where, segmentation, error);
}

bool loadPipelineConfigYaml(const std::string& path, PipelineParams* params, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  if (root.IsMap() && root["tracker"]) return loadTrackerParamsYaml(path, &params->tracker, error);
  return loadPipelineParamsYaml(path, &params->segmentation, &params->hierarchical_grid,
                                &params->kdtree, error) &&
         loadObjectClassifierParamsYaml(path, &params->classifier, error) &&
         loadBoxFittingParamsYaml(path, &params->box_fitting, error);
}

bool loadPipelineConfigsYaml(const std::vector<std::string>& paths, PipelineParams* params,
                             std::string* error) {
  for (const std::string& path : paths) {
    if (!loadPipelineConfigYaml(path, params, error)) return false;
  }
  return true;
}

bool loadTrackerParamsYaml(const std::string& path, TrackerParams* params, std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  const bool section = root.IsMap() && root["tracker"];
  return applyFieldsYaml(section ? root["tracker"] : root,
                         path + ": " + (section ? "tracker/" : ""), params, error);
}

}  // namespace core
}  // namespace urban_detection
