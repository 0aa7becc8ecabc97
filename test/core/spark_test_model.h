// Builds the tiny colour-segmentation ONNX network of test/spark_colour_model.py at test time
// (no downloaded weights). Tests skip visibly when Debian's python3-onnx is not installed.
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "urban_detection/core/spark/spark_segmenter.h"

namespace urban_detection {
namespace test {

/// Class ids of the colour model: background (grey/black/white), car (red), vegetation
/// (green), pole (blue).
enum ColourClass { kBackground = 0, kCar = 1, kVegetation = 2, kPole = 3 };

/// A fresh scratch directory under the system temp dir, unique to this process.
inline std::string scratchDir(const std::string& name) {
  // Every scratch directory is removed when the test binary exits.
  struct Registry {
    std::vector<std::filesystem::path> dirs;
    ~Registry() {
      for (const auto& d : dirs) {
        std::error_code ec;
        std::filesystem::remove_all(d, ec);
      }
    }
  };
  static Registry registry;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("ud_spark_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  registry.dirs.push_back(dir);
  return dir.string();
}

/// Writes the model (input `width` x `height`) and its class names into `dir`; fills the
/// model parameters (RGB in [0, 1], logits). Returns false with `why` when python3-onnx is
/// missing or the script fails.
inline bool makeColourModel(const std::string& dir, int width, int height,
                            core::SegmentationModelParams* params, std::string* names_path,
                            std::string* why) {
  if (std::system("/usr/bin/python3 -c 'import onnx' >/dev/null 2>&1") != 0) {
    *why = "python3-onnx is not installed (apt-get install python3-onnx)";
    return false;
  }
  const std::string model = dir + "/colour_model.onnx";
  *names_path = dir + "/colour_classes.txt";
  const std::string cmd = "/usr/bin/python3 " UD_SOURCE_DIR "/test/spark_colour_model.py " + model +
                          " " + std::to_string(width) + " " + std::to_string(height) + " " +
                          *names_path;
  if (std::system(cmd.c_str()) != 0) {
    *why = "spark_colour_model.py failed: " + cmd;
    return false;
  }
  params->model_path = model;
  params->input_width_px = width;
  params->input_height_px = height;
  params->input_rgb = true;
  params->mean = {0.0, 0.0, 0.0};
  params->scale = {1.0 / 255.0, 1.0 / 255.0, 1.0 / 255.0};
  params->output_softmax = true;
  return true;
}

}  // namespace test
}  // namespace urban_detection
