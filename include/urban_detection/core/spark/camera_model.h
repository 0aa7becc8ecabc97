/// \file camera_model.h
/// The camera stage's configuration, config/image_label_transfer.yaml, as one field-tabled struct
/// (CameraStageParams: the fusion mode and rule, the `model:` map, the `transfer:` map), and
/// the one path from it to a usable camera model (loadCameraModel: the network, its class names,
/// which classes vote and what each class means). The ImageLabelTransfer nodelet and
/// urban_detection_spark both go through here, so one tuned file serves both and is refused by
/// both for the same reasons. ROS-free; never prints.
#pragma once

#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/spark/camera_fusion.h"
#include "urban_detection/core/spark/image_label_transfer.h"
#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace core {

/// The `model:` map: the network, where its files are, its class names and the role of each
/// class (docs/spark.md).
struct CameraModelParams {
  SegmentationModelParams network;  ///< path, config_file, input size, normalisation
  std::string dir;                  ///< relative path / config_file / class_names_file start here
  std::string class_names_file;     ///< one name per line (line n = output channel n)
  /// Names (or ids) of the classes that vote in camera mode; empty: all.
  std::vector<std::string> keep_classes;
  /// The camera classes of each object category (fused rule and veto); background = road,
  /// building, vegetation, ... Classes in none of the lists are ignored.
  std::vector<std::string> vehicle_classes, pedestrian_classes, cyclist_classes,
      other_object_classes, background_classes;
  int inference_threads = 1;  ///< [-] OpenCV threads (process-wide); 0 = OpenCV's default
  int inference_nice = 19;    ///< [0..19] nice of the thread that runs the network
};

/// "" when every field is in its table range.
std::string validate(const CameraModelParams& params);

template <>
struct ParamFields<CameraModelParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    ParamFields<SegmentationModelParams>::visit(p.network, f);  // flat: model/path, ...
    f({"dir", "folder of the relative path, config_file and class_names_file"}, p.dir);
    f({"class_names_file", "one class name per line (line n = output channel n); empty: class_<n>"},
      p.class_names_file);
    f({"keep_classes", "camera mode: names (or ids) of the classes that vote; []: all"},
      p.keep_classes);
    f({"vehicle_classes", "camera classes that are vehicles"}, p.vehicle_classes);
    f({"pedestrian_classes", "camera classes that are pedestrians"}, p.pedestrian_classes);
    f({"cyclist_classes", "camera classes that are cyclists"}, p.cyclist_classes);
    f({"other_object_classes", "camera classes that are other objects (poles, signs, ...)"},
      p.other_object_classes);
    f({"background_classes", "camera classes that are background (road, building, ...): veto"},
      p.background_classes);
    f({"inference_threads", "", 0, 64,
       "OpenCV threads of the network (process-wide); 0: OpenCV's default"},
      p.inference_threads);
    f({"inference_nice", "", 0, 19, "nice of the thread that runs the network"}, p.inference_nice);
  }
};

/// Everything config/image_label_transfer.yaml holds.
struct CameraStageParams {
  CameraFusionParams fusion;          ///< `fusion` (the mode) and `fusion_rule/*`
  CameraModelParams model;            ///< `model/*`
  ImageLabelTransferParams transfer;  ///< `transfer/*` (kept_classes from model/keep_classes)
  /// [s] objects take the newest mask whose image stamp is within this of their cloud's.
  double max_mask_gap_s = 0.15;
  int queue_size = 5;                 ///< [messages] per input and for the synchroniser
  double max_sync_interval_s = 0.06;  ///< [s] objects vs. objects/points stamps
  /// Non-empty: the camera <- LiDAR transform goes from the cloud stamp to the image stamp
  /// through this frame (moving platform); empty: at the image stamp.
  std::string fixed_frame;
  double tf_timeout_s = 0.0;  ///< [s] wait for the camera <- LiDAR transform (0: what tf has)
};

/// "" when every field is in its table range.
std::string validate(const CameraStageParams& params);

template <>
struct ParamFields<CameraStageParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f(FieldInfo::choice("fusion", {"lidar", "camera", "fused"},
                        "lidar: LiDAR classes passed on; camera: the network's class where the "
                        "camera sees the object; fused: the rule of camera_fusion.h"),
      p.fusion.mode);
    forEachField(p.fusion, "fusion_rule", f);
    forEachField(p.model, "model", f);
    forEachField(p.transfer, "transfer", f);
    f({"transfer/max_mask_gap_s", "s", 0, 10,
       "objects take the newest mask within this of their stamp (else LiDAR classes stay)"},
      p.max_mask_gap_s);
    f({"transfer/queue_size", "messages", 1, 100, "per input and for the synchroniser"},
      p.queue_size);
    f({"transfer/max_sync_interval_s", "s", 0, 1, "objects and objects/points stamps may differ"},
      p.max_sync_interval_s);
    f({"transfer/fixed_frame",
       "e.g. odom: tf from the cloud stamp to the image stamp through it; empty: at the image "
       "stamp"},
      p.fixed_frame);
    f({"transfer/tf_timeout_s", "s", 0, 1, "wait for the camera <- LiDAR transform"},
      p.tf_timeout_s);
  }
};

/// `params` with its relative path, config_file and class_names_file taken from `dir`.
CameraModelParams withModelDir(CameraModelParams params);
/// `file` relative to `dir` when it is relative and `dir` set (for other files of the model).
std::string inModelDir(const std::string& dir, const std::string& file);

/// A camera model ready to use.
struct CameraModel {
  SegmentationModel network;       ///< loaded when loadCameraModel() was asked to
  std::vector<std::string> names;  ///< class names; empty without class_names_file
  CameraClassMap class_map;        ///< the object category of each class
  std::vector<bool> kept_classes;  ///< classes that vote (empty: all), for the transfer
};

/// The one path from the `model:` map to a camera model: files relative to `dir`, the network
/// (when `load_network`), the class names, keep_classes (without names any id below 65536 may
/// be kept: the network's class count is only known after its first run) and the class map.
/// Returns false with `error` naming the parameter at fault ("model/path: ...").
bool loadCameraModel(const CameraModelParams& params, bool load_network, CameraModel* model,
                     std::string* error);

}  // namespace core
}  // namespace urban_detection
