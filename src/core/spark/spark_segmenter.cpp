#include "urban_detection/core/spark/spark_segmenter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace urban_detection {
namespace core {

namespace {
double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

bool SegmentationScores::assign(const cv::Mat& blob, bool softmax) {
  blob_.release();
  confidence_.release();
  data_ = nullptr;
  classes_ = width_ = height_ = 0;
  if (blob.type() != CV_32F || blob.dims != 4 || blob.size[0] != 1 || blob.size[1] < 1 ||
      blob.size[2] < 1 || blob.size[3] < 1 || !blob.isContinuous()) {
    return false;
  }
  blob_ = blob;
  data_ = blob_.ptr<float>();
  classes_ = blob.size[1];
  height_ = blob.size[2];
  width_ = blob.size[3];
  softmax_ = softmax;
  ignore_id_ = -1;
  return true;
}

void SegmentationScores::assignLabels(const cv::Mat& labels, int ignore_id) {
  const int sizes[4] = {1, 1, labels.rows, labels.cols};
  cv::Mat blob(4, sizes, CV_32F);
  cv::Mat plane(labels.rows, labels.cols, CV_32F, blob.ptr<float>());
  labels.convertTo(plane, CV_32F);  // writes into the blob's memory (same size and type)
  assign(blob, false);
  ignore_id_ = ignore_id;
}

void SegmentationScores::reduceTo(SegmentationScores* out) const {
  if (empty()) {
    *out = SegmentationScores();
    return;
  }
  const int sizes[4] = {1, 1, height_, width_};
  cv::Mat labels(4, sizes, CV_32F);
  cv::Mat label_plane(height_, width_, CV_32F, labels.ptr<float>());
  cv::Mat conf(height_, width_, CV_32F);
  if (classes_ == 1) {
    cv::Mat(height_, width_, CV_32F, const_cast<float*>(data_)).copyTo(label_plane);
    if (confidence_.empty())
      conf.setTo(1.0f);
    else
      confidence_.copyTo(conf);
  } else {
    // Whole-plane operations (vectorised by OpenCV) rather than classAt() per pixel: the argmax
    // over C planes, then the softmax denominator sum_c exp(s_c - s_best).
    const std::size_t plane = static_cast<std::size_t>(width_) * height_;
    auto planeAt = [&](int c) {
      return cv::Mat(height_, width_, CV_32F, const_cast<float*>(data_) + c * plane);
    };
    cv::Mat best = planeAt(0).clone(), greater, diff;
    label_plane.setTo(0.0f);
    for (int c = 1; c < classes_; ++c) {
      const cv::Mat s = planeAt(c);
      cv::compare(s, best, greater, cv::CMP_GT);  // strictly greater, as classAt()
      label_plane.setTo(static_cast<float>(c), greater);
      s.copyTo(best, greater);
    }
    if (!softmax_) {
      cv::max(best, 0.0, conf);
      cv::min(conf, 1.0, conf);
    } else {
      cv::Mat sum(height_, width_, CV_32F, cv::Scalar(0.0f));
      for (int c = 0; c < classes_; ++c) {
        cv::subtract(planeAt(c), best, diff);
        cv::exp(diff, diff);
        sum += diff;
      }
      cv::divide(1.0, sum, conf);
    }
    // Non-finite best scores have no class (as in classAt()); OpenCV's vectorised compares do
    // not see NaN reliably, so this pass is per pixel.
    for (int y = 0; y < height_; ++y) {
      const float* b = best.ptr<float>(y);
      float* l = label_plane.ptr<float>(y);
      float* c = conf.ptr<float>(y);
      for (int x = 0; x < width_; ++x) {
        if (!std::isfinite(b[x])) {
          l[x] = -1.0f;
          c[x] = 0.0f;
        }
      }
    }
  }
  out->assign(labels, false);
  out->confidence_ = conf;
  out->ignore_id_ = ignore_id_;
}

int SegmentationScores::classAt(int x, int y, float* confidence) const {
  const std::size_t plane = static_cast<std::size_t>(width_) * height_;
  const float* p = data_ + static_cast<std::size_t>(y) * width_ + x;
  if (classes_ == 1) {
    const float v = *p;
    *confidence = confidence_.empty() ? 1.0f : confidence_.at<float>(y, x);
    if (!(v >= 0.0f && v <= 255.0f)) return -1;  // also NaN
    const int id = static_cast<int>(std::lround(v));
    return id == ignore_id_ ? -1 : id;
  }
  int best = 0;
  float best_score = p[0];
  for (int c = 1; c < classes_; ++c) {
    const float s = p[c * plane];
    if (s > best_score) {
      best_score = s;
      best = c;
    }
  }
  if (!std::isfinite(best_score)) {
    *confidence = 0.0f;
    return -1;
  }
  if (!softmax_) {
    *confidence = std::min(1.0f, std::max(0.0f, best_score));
    return best;
  }
  // Softmax probability of the best class: 1 / sum_c exp(s_c - s_best).
  float sum = 0.0f;
  for (int c = 0; c < classes_; ++c) sum += std::exp(p[c * plane] - best_score);
  *confidence = sum > 0.0f ? 1.0f / sum : 0.0f;
  return best;
}

cv::Mat SegmentationScores::labelImage() const {
  cv::Mat out(height_, width_, CV_8U, cv::Scalar(255));
  if (empty()) return out;
  for (int y = 0; y < height_; ++y) {
    auto* row = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < width_; ++x) {
      float conf = 0.0f;
      const int id = classAt(x, y, &conf);
      row[x] = static_cast<std::uint8_t>(id >= 0 && id < 255 ? id : 255);
    }
  }
  return out;
}

std::string validate(const SegmentationModelParams& params) {
  return checkFieldRanges(params);
}

bool SegmentationModel::load(const SegmentationModelParams& params, std::string* error) {
  loaded_ = false;
  params_ = params;
  if (params.model_path.empty()) {
    *error = "no segmentation model given (model_path is empty)";
    return false;
  }
  *error = validate(params);
  if (!error->empty()) return false;
  for (const std::string* f : {&params.model_path, &params.config_path}) {
    if (f->empty()) continue;
    std::ifstream probe(*f, std::ios::binary);
    if (!probe) {
      *error = "cannot open model file '" + *f + "'";
      return false;
    }
  }
  return readNet(error);
}

bool SegmentationModel::readNet(std::string* error) {
  loaded_ = false;
  net_ = cv::dnn::Net();
  try {
    net_ = cv::dnn::readNet(params_.model_path, params_.config_path);
    net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  } catch (const cv::Exception& e) {
    *error = "OpenCV cannot import '" + params_.model_path + "': " + e.what();
    return false;
  }
  if (net_.empty()) {
    *error = "OpenCV imported an empty network from '" + params_.model_path + "'";
    return false;
  }
  loaded_ = true;
  return true;
}

bool SegmentationModel::setInputSize(int width_px, int height_px, std::string* error) {
  if (width_px == params_.input_width_px && height_px == params_.input_height_px && loaded_)
    return true;
  SegmentationModelParams sized = params_;
  sized.input_width_px = width_px;
  sized.input_height_px = height_px;
  *error = validate(sized);
  if (!error->empty()) return false;
  params_ = sized;
  return readNet(error);
}

bool SegmentationModel::run(const cv::Mat& image, SegmentationScores* scores, std::string* error) {
  if (!loaded_) {
    *error = "no model loaded";
    return false;
  }
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 1)) {
    *error = "image must be a non-empty 8-bit BGR or grey image";
    return false;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const int w = params_.input_width_px, h = params_.input_height_px;
  cv::resize(image, resized_, cv::Size(w, h), 0.0, 0.0, cv::INTER_LINEAR);
  if (resized_.channels() == 1) {
    cv::cvtColor(resized_, colour_, cv::COLOR_GRAY2BGR);
  } else if (params_.input_rgb) {
    cv::cvtColor(resized_, colour_, cv::COLOR_BGR2RGB);
  } else {
    colour_ = resized_;
  }
  const int sizes[4] = {1, 3, h, w};
  blob_.create(4, sizes, CV_32F);
  // Planar NCHW with per-channel (x - mean) * scale; OpenCV 4.6's blobFromImage only takes one
  // scale for all channels, which the usual ImageNet normalisation does not fit. convertTo and
  // split into planes that alias the blob keep it vectorised and copy-free.
  const cv::Scalar scale(params_.scale[0], params_.scale[1], params_.scale[2]);
  const cv::Scalar offset(-params_.mean[0] * params_.scale[0], -params_.mean[1] * params_.scale[1],
                          -params_.mean[2] * params_.scale[2]);
  colour_.convertTo(float_, CV_32FC3);
  cv::multiply(float_, scale, float_);
  cv::add(float_, offset, float_);
  std::vector<cv::Mat> planes(3);
  for (int c = 0; c < 3; ++c)
    planes[c] = cv::Mat(h, w, CV_32F, blob_.ptr<float>() + static_cast<std::size_t>(c) * w * h);
  cv::split(float_, planes);
  stats_.preprocess_ms = msSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  try {
    net_.setInput(blob_);
    output_ = net_.forward();
  } catch (const cv::Exception& e) {
    *error = std::string("inference failed: ") + e.what();
    return false;
  } catch (const std::exception& e) {
    *error = std::string("inference failed: ") + e.what();
    return false;
  }
  stats_.inference_ms = msSince(t1);
  if (output_.dims == 3 && output_.type() == CV_32F && output_.isContinuous()) {
    // [1, h, w] label map (networks ending in an argmax): view it as [1, 1, h, w].
    const int s4[4] = {1, 1, output_.size[1], output_.size[2]};
    output_ = output_.reshape(1, 4, s4);
  }
  if (!scores->assign(output_, params_.output_softmax)) {
    std::ostringstream msg;
    msg << "network output must be float [1, C, h, w], got " << output_.dims << " dims";
    *error = msg.str();
    return false;
  }
  return true;
}

bool readClassNames(const std::string& path, std::vector<std::string>* names, std::string* error) {
  names->clear();
  std::ifstream in(path);
  if (!in) {
    *error = "cannot open class names file '" + path + "'";
    return false;
  }
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    names->push_back(line);
  }
  while (!names->empty() && names->back().empty()) names->pop_back();
  if (names->empty()) {
    *error = "class names file '" + path + "' is empty";
    return false;
  }
  return true;
}

bool resolveKeptClasses(const std::vector<std::string>& keep, const std::vector<std::string>& names,
                        int bound, std::vector<bool>* kept, std::string* error) {
  kept->assign(static_cast<std::size_t>(std::max(bound, 0)), keep.empty());
  for (const std::string& k : keep) {
    const auto it = std::find(names.begin(), names.end(), k);
    long id = -1;
    if (it != names.end()) {
      id = it - names.begin();
    } else {
      char* end = nullptr;
      const long v = std::strtol(k.c_str(), &end, 10);
      if (!k.empty() && end != nullptr && *end == '\0') id = v;
    }
    if (id < 0 || id >= bound) {
      *error = "kept class '" + k + "' is neither a class name nor an id in [0, " +
               std::to_string(bound - 1) + "]";
      return false;
    }
    (*kept)[static_cast<std::size_t>(id)] = true;
  }
  return true;
}

}  // namespace core
}  // namespace urban_detection
