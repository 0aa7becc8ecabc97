/// \file params_yaml.h
/// Loading of the core parameter structs from the config/*.yaml files without a ROS master
/// (offline tools: evaluation, benchmark). The files are the ones the launch files load into
/// the parameter server, so a tuned file works unchanged in both places. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/classification/object_classifier.h"
#include "urban_detection/core/detection/box_fitting.h"
#include "urban_detection/core/detection/hierarchical_grid_detector.h"
#include "urban_detection/core/detection/kdtree_detector.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/spark/camera_model.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {

/// Overrides the fields of `params` present in the YAML file `path` (segmentation.yaml layout:
/// GridSegmenterParams field names, the Hough fields under `hough:`). When `section` is not
/// empty and the file has a top-level map of that name, that map is read instead of the root.
/// Unknown keys and values of the wrong type are errors (a typo must not be silently ignored).
/// Returns false with `error` set; `params` may then be partly updated.
bool loadGridSegmenterParamsYaml(const std::string& path, const std::string& section,
                                 GridSegmenterParams* params, std::string* error);

/// Overrides the fields of `params` from the `hierarchical_grid:` map of a detection.yaml
/// style file (the distance weight under `weight:`). A file without that map changes nothing.
bool loadHierarchicalGridParamsYaml(const std::string& path, HierarchicalGridDetectorParams* params,
                                    std::string* error);

/// Overrides the fields of `params` from the `kdtree:` map of a detection.yaml style file.
bool loadKdTreeParamsYaml(const std::string& path, KdTreeDetectorParams* params,
                          std::string* error);

/// Loads any of the pipeline's config files, recognised by their top-level keys: a combined
/// file (`segmentation:` and/or `detection:` maps), a detection.yaml (`hierarchical_grid:`,
/// `kdtree:` and/or `classifier:` maps; the latter is read by loadObjectClassifierParamsYaml)
/// or otherwise a segmentation.yaml. Null pointers skip that part.
bool loadPipelineParamsYaml(const std::string& path, GridSegmenterParams* segmentation,
                            HierarchicalGridDetectorParams* hierarchical,
                            KdTreeDetectorParams* kdtree, std::string* error);

/// Overrides the fields of `params` from the `classifier:` map of a detection.yaml style file
/// (top level, or under `detection:`). A relative `model` path is taken relative to the
/// folder of that file. A file without the map changes nothing.
bool loadObjectClassifierParamsYaml(const std::string& path, ObjectClassifierParams* params,
                                    std::string* error);

/// Overrides the fields of `params` from the `box_fitting:` map of a detection.yaml style file
/// (config/classification.yaml; top level, or under `detection:`). A file without it changes
/// nothing.
bool loadBoxFittingParamsYaml(const std::string& path, BoxFittingParams* params,
                              std::string* error);

/// Applies one of the pipeline's config files to `params`, recognised by its top-level keys:
/// a tracker file (`tracker:` map, config/object_tracker.yaml) sets params->tracker; any other
/// file is read as by loadPipelineParamsYaml() plus its `classifier:` and `box_fitting:` maps
/// (config/segmentation.yaml, hierarchical_grid.yaml, kdtree.yaml, classification.yaml).
bool loadPipelineConfigYaml(const std::string& path, PipelineParams* params, std::string* error);

/// loadPipelineConfigYaml() for each file in order over the values already in `params`; stops
/// at the first error.
bool loadPipelineConfigsYaml(const std::vector<std::string>& paths, PipelineParams* params,
                             std::string* error);

/// Overrides the fields of `params` from the `tracker:` map of a file (config/object_tracker.yaml),
/// or from its root when it has no such map.
bool loadTrackerParamsYaml(const std::string& path, TrackerParams* params, std::string* error);

/// Overrides the fields of `params` present in a camera stage file
/// (config/image_label_transfer.yaml, or a preset such as config/spark_enet_cityscapes.yaml
/// loaded over it): `fusion`, `fusion_rule:`, `model:`, `transfer:`. Unknown keys, values of the
/// wrong type and out-of-range values are errors naming the key.
bool loadCameraStageParamsYaml(const std::string& path, CameraStageParams* params,
                               std::string* error);

}  // namespace core
}  // namespace urban_detection
