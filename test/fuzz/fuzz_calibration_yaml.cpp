// libFuzzer target: velodyne_pointcloud YAML calibration reader (core::loadCalibrationYaml).
// The input is the file content; see calibration_check.h for what is checked.
#include "calibration_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static urban_detection::fuzz::ScratchFile file(".yaml");
  urban_detection::fuzz::checkCalibration(urban_detection::core::loadCalibration,
                                          file.write(data, size));
  return 0;
}
