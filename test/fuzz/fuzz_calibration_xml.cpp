// libFuzzer target: Velodyne db.xml calibration reader (core::loadCalibrationDbXml).
// The input is the file content; see calibration_check.h for what is checked.
#include "calibration_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static urban_detection::fuzz::ScratchFile file(".xml");
  urban_detection::fuzz::checkCalibration(urban_detection::core::loadCalibration,
                                          file.write(data, size));
  return 0;
}
