/// \file spark_segmenter.h
/// A 2-D semantic segmentation network run through OpenCV's DNN module (any file
/// cv::dnn::readNet reads: ONNX, Torch7 `.t7`/`.net`, Caffe, TensorFlow, Darknet; e.g. ENet
/// trained on Cityscapes), and the class scores it returns.
/// This is the "image segmentation" step of the SPARK workflow (second seed paper, Sec. 3.3),
/// used by the live image-to-object label transfer and by the offline SPARK tool. ROS-free; it
/// never prints: failures return false and say why in `error`.
///
/// The scores are not reduced to a full-resolution label image: both consumers only need the
/// class at a few pixels (the pixels the object points project to, every n-th mask pixel), so
/// SegmentationScores::classAt() evaluates the argmax (and the softmax confidence) lazily at the
/// pixels asked for. This keeps the label transfer's cost independent of the image size.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"

namespace urban_detection {
namespace core {

/// Per-pixel class scores of one image: a planar float map [classes][height][width] at the
/// network's output resolution, or a single-channel label map (the class id per pixel, for
/// networks that end in an argmax and for masks painted by other means).
class SegmentationScores {
 public:
  /// Wraps a network output blob of shape [1, C, h, w] (CV_32F) without copying (the blob's
  /// reference count keeps it alive). C == 1 means the blob holds class ids. `softmax`: the
  /// scores are logits, the confidence of a pixel is the softmax probability of its best class;
  /// otherwise the best score itself is the confidence (the scores are probabilities).
  /// Returns false (and leaves the object empty) for any other shape or type.
  bool assign(const cv::Mat& blob, bool softmax);
  /// A label map (CV_8U or CV_32S, class id per pixel, confidence 1). Copied into the blob.
  /// Pixels with id `ignore_id` (if >= 0) have no class.
  void assignLabels(const cv::Mat& labels, int ignore_id = -1);
  /// Reduces these scores to a label map that owns its memory (the argmax per pixel) with the
  /// confidence classAt() would give each pixel, so it outlives the network's next run (the
  /// live transfer hands it to another thread). A label map is copied as is.
  void reduceTo(SegmentationScores* out) const;

  bool empty() const { return data_ == nullptr; }
  int classes() const { return classes_; }  ///< number of score channels (1 for a label map)
  int width() const { return width_; }      ///< [px] of the score map
  int height() const { return height_; }    ///< [px] of the score map
  /// Upper bound of the class ids classAt() can return, plus one (classes(), or 256 for a
  /// label map).
  int classIdBound() const { return classes_ > 1 ? classes_ : 256; }

  /// Class id at score-map pixel (x, y) (callers keep 0 <= x < width(), 0 <= y < height()), or
  /// -1 when the pixel has no class (label map: the ignore id or an id outside [0, 255]).
  /// `confidence` in [0, 1] receives the probability of that class.
  int classAt(int x, int y, float* confidence) const;

  /// The full argmax (CV_8U, 255 = no class or id >= 255), for writing masks to disk.
  cv::Mat labelImage() const;

 private:
  cv::Mat blob_;
  cv::Mat confidence_;  // CV_32F [h][w] of a reduced label map; empty: confidence 1
  const float* data_ = nullptr;
  int classes_ = 0, width_ = 0, height_ = 0;
  int ignore_id_ = -1;
  bool softmax_ = true;
};

/// Network input geometry and normalisation, mirrored in config/image_label_transfer.yaml.
struct SegmentationModelParams {
  std::string model_path;     ///< any file cv::dnn::readNet reads (format from the extension)
  std::string config_path;    ///< second file of some formats (Caffe .prototxt, TF .pbtxt)
  int input_width_px = 1024;  ///< [px] the image is resized to this before inference
  int input_height_px = 512;  ///< [px]
  bool input_rgb = true;      ///< network expects RGB channel order (images come BGR)
  /// Per-channel mean subtracted from the 0..255 pixel values, in the network's channel order.
  std::array<double, 3> mean = {123.675, 116.28, 103.53};
  /// Per-channel factor applied after the mean (1 / standard deviation; 1/255 for [0, 1]).
  std::array<double, 3> scale = {1.0 / 58.395, 1.0 / 57.12, 1.0 / 57.375};
  bool output_softmax = true;  ///< outputs are logits (true) or probabilities (false)
};

/// "" when every field is in its table range (ParamFields<SegmentationModelParams> below).
std::string validate(const SegmentationModelParams& params);

/// SegmentationModelParams' field table (core/common/param_fields.h): the network's keys of the
/// `model:` map of config/image_label_transfer.yaml (CameraModelParams, camera_model.h).
template <>
struct ParamFields<SegmentationModelParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"path", "network file cv::dnn::readNet reads (.onnx, .t7/.net Torch7, .caffemodel, .pb)"},
      p.model_path);
    f({"config_file", "second file of some formats (Caffe .prototxt, TF .pbtxt)"}, p.config_path);
    f({"input_width_px", "px", 8, 8192, "the image is resized to this for the network"},
      p.input_width_px);
    f({"input_height_px", "px", 8, 8192, "the image is resized to this for the network"},
      p.input_height_px);
    f({"input_rgb", "the network expects RGB channel order (images come BGR)"}, p.input_rgb);
    f({"mean", "", 0, 255, "per-channel mean subtracted from the 0..255 pixel values"}, p.mean);
    f({"scale", "", 1e-6, 1000, "per-channel factor applied after the mean (1 / std dev)"},
      p.scale);
    f({"output_softmax", "outputs are logits (false: probabilities)"}, p.output_softmax);
  }
};

/// Timings of one SegmentationModel::run() [ms].
struct SegmentationModelStats {
  double preprocess_ms = 0.0;  ///< resize, channel order, normalisation into the input blob
  double inference_ms = 0.0;   ///< cv::dnn::Net::forward
};

/// Loads a segmentation network and runs it on BGR images. One cv::dnn::Net per input size:
/// changing the size reads the file again, because reshaping an imported network (Torch7 ENet
/// in OpenCV 4.6 at least) silently corrupts its output.
class SegmentationModel {
 public:
  /// Checks the parameters and reads the network (CPU backend). Returns false with `error`
  /// naming the problem (missing file, unsupported operator, bad input size).
  bool load(const SegmentationModelParams& params, std::string* error);
  /// Another network input size: a fresh network is read from the same file (no-op when the
  /// size is unchanged). Returns false with `error` (and stays unloaded) on failure.
  bool setInputSize(int width_px, int height_px, std::string* error);
  bool loaded() const { return loaded_; }
  const SegmentationModelParams& params() const { return params_; }

  /// Runs the network on `image` (CV_8UC3 BGR or CV_8UC1 grey, any size). `scores` wraps the
  /// output (valid until the next run). Returns false with `error` on an OpenCV failure or an
  /// output that is not [1, C, h, w].
  bool run(const cv::Mat& image, SegmentationScores* scores, std::string* error);
  const SegmentationModelStats& stats() const { return stats_; }

 private:
  SegmentationModelParams params_;
  bool readNet(std::string* error);

  cv::dnn::Net net_;
  bool loaded_ = false;
  cv::Mat resized_, colour_, float_, blob_, output_;  // scratch reused between images
  SegmentationModelStats stats_;
};

/// Reads a class-names file: one name per line (line n = class id n), blank lines are kept as
/// empty names, a trailing newline is ignored, '\r' stripped. Returns false if unreadable or
/// empty.
bool readClassNames(const std::string& path, std::vector<std::string>* names, std::string* error);

/// Resolves `keep` (class names or decimal ids) against `names` into a membership table of size
/// `bound` (true = the class votes). Empty `keep` keeps every class. Returns false with `error`
/// naming the first entry that is neither a known name nor an id below `bound`.
bool resolveKeptClasses(const std::vector<std::string>& keep, const std::vector<std::string>& names,
                        int bound, std::vector<bool>* kept, std::string* error);

}  // namespace core
}  // namespace urban_detection
