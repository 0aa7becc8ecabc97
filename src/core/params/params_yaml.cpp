#include "urban_detection/core/params/params_yaml.h"

#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <type_traits>

#include <yaml-cpp/yaml.h>

namespace urban_detection {
namespace core {

namespace {

// The YAML map `node` applied to `params` through its field table (core/common/param_fields.h):
// nested maps for nested structs ("hough: {votes: 8}" is the field "hough/votes"); an unknown key
// or a value of the wrong type is an error naming it; then the complete struct is validated
// (its table's ranges and cross-field rules).
template <class Params>
bool applyFields(const YAML::Node& node, const std::string& where, Params* params,
                 std::string* error) {
  // A setter returns "" or why the value was refused (a YAML::Exception: the wrong type).
  std::map<std::string, std::function<std::string(const YAML::Node&)>> setters;
  std::set<std::string> groups;  // "hough", "weight", ...: names of nested maps
  forEachField(*params, [&](const FieldInfo& info, auto& field) {
    using T = std::decay_t<decltype(field)>;
    setters[info.name] = [&field, info, where](const YAML::Node& n) -> std::string {
      if constexpr (std::is_enum_v<T>) {
        const std::string name = n.as<std::string>();
        if (!parseChoice(info, name, &field)) {
          return where + badChoiceMessage(info.name, name, info.choices);
        }
      } else if constexpr (kRangedArray<T>) {
        const auto list = n.as<std::vector<double>>();
        if (list.size() != field.size()) {
          return where + "parameter '" + info.name + "' needs " + std::to_string(field.size()) +
                 " numbers, has " + std::to_string(list.size());
        }
        std::copy(list.begin(), list.end(), field.begin());
      } else {
        field = n.as<T>();
      }
      return "";
    };
    for (std::size_t slash = info.name.find('/'); slash != std::string::npos;
         slash = info.name.find('/', slash + 1)) {
      groups.insert(info.name.substr(0, slash));
    }
  });
  std::function<bool(const YAML::Node&, const std::string&)> walk = [&](const YAML::Node& map,
                                                                        const std::string& prefix) {
    if (!map.IsMap()) {
      *error = where + prefix + "expected a map of parameters";
      return false;
    }
    for (const auto& kv : map) {
      const std::string name = prefix + kv.first.as<std::string>();
      const auto setter = setters.find(name);
      if (setter != setters.end()) {
        try {
          *error = setter->second(kv.second);
        } catch (const YAML::Exception& e) {
          *error = where + name + ": wrong type (" + e.what() + ")";
        }
        if (!error->empty()) return false;
      } else if (groups.count(name)) {
        if (!walk(kv.second, name + "/")) return false;
      } else {
        *error = where + name + ": unknown parameter";
        return false;
      }
    }
    return true;
  };
  if (!walk(node, "")) return false;
  const std::string invalid = validate(*params);
  if (!invalid.empty()) *error = where + invalid;
  return invalid.empty();
}

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
      !applyFields(root["hierarchical_grid"], where + "hierarchical_grid/", hier, error)) {
    return false;
  }
  if (kd && root["kdtree"] && !applyFields(root["kdtree"], where + "kdtree/", kd, error)) {
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
  return applyFields(root[section], where + section + "/", params, error);
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
  return applyFields(root, path + ": ", p, error);
}

bool loadCameraStageParamsYaml(const std::string& path, CameraStageParams* params,
                               std::string* error) {
  YAML::Node root;
  if (!loadRoot(path, "", &root, error)) return false;
  return applyFields(root, path + ": ", params, error);
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
        !applyFields(root["segmentation"], where + "segmentation/", segmentation, error)) {
      return false;
    }
    return !root["detection"] ||
           applyDetection(root["detection"], where + "detection/", hierarchical, kdtree, error);
  }
  if (root["hierarchical_grid"] || root["kdtree"] || root["classifier"]) {
    return applyDetection(root, where, hierarchical, kdtree, error);
  }
  return !segmentation || applyFields(root, where, segmentation, error);
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
  return applyFields(section ? root["tracker"] : root, path + ": " + (section ? "tracker/" : ""),
                     params, error);
}

}  // namespace core
}  // namespace urban_detection
