#include "urban_detection/core/spark/camera_model.h"

namespace urban_detection {
namespace core {

std::string validate(const CameraModelParams& params) {
  return checkFieldRanges(params);
}

std::string validate(const CameraStageParams& params) {
  std::string error = checkFieldRanges(params);
  // The fused rule reads the role of each class by name.
  if (error.empty() && params.fusion.mode == FusionMode::kFused &&
      params.model.class_names_file.empty()) {
    error = "fusion 'fused' needs model/class_names_file (and model/*_classes)";
  }
  return error;
}

std::string inModelDir(const std::string& dir, const std::string& file) {
  if (dir.empty() || file.empty() || file[0] == '/') return file;
  return dir + "/" + file;
}

CameraModelParams withModelDir(CameraModelParams p) {
  p.network.model_path = inModelDir(p.dir, p.network.model_path);
  p.network.config_path = inModelDir(p.dir, p.network.config_path);
  p.class_names_file = inModelDir(p.dir, p.class_names_file);
  return p;
}

bool loadCameraModel(const CameraModelParams& params, bool load_network, CameraModel* model,
                     std::string* error) {
  std::string why = validate(params);
  if (!why.empty()) {
    *error = why;
    return false;
  }
  const CameraModelParams p = withModelDir(params);
  if (load_network && !model->network.load(p.network, &why)) {
    *error = "model/path: " + why +
             " (give a semantic segmentation network cv::dnn::readNet reads: ONNX, Torch7, "
             "Caffe, TensorFlow; e.g. config/spark_enet_cityscapes.yaml)";
    return false;
  }
  model->names.clear();
  if (!p.class_names_file.empty() && !readClassNames(p.class_names_file, &model->names, &why)) {
    *error = "model/class_names_file: " + why;
    return false;
  }
  // Without names, ids up to 65535 may be kept (ids the network never outputs never vote).
  const int bound = model->names.empty() ? 65536 : static_cast<int>(model->names.size());
  if (!resolveKeptClasses(p.keep_classes, model->names, bound, &model->kept_classes, &why)) {
    *error = "model/keep_classes: " + why;
    return false;
  }
  if (p.keep_classes.empty()) model->kept_classes.clear();
  if (!buildCameraClassMap(model->names, p.vehicle_classes, p.pedestrian_classes, p.cyclist_classes,
                           p.other_object_classes, p.background_classes, &model->class_map, &why)) {
    *error = "model/*_classes: " + why;
    return false;
  }
  return true;
}

}  // namespace core
}  // namespace urban_detection
