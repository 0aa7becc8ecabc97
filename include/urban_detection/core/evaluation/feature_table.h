/// \file feature_table.h
/// The object classifier's feature table as a CSV file (urban_detection_eval --features,
/// urban_detection_train_classifier --csv): the tool's leading columns, then one column per
/// feature (featureName()). ROS-free.
#pragma once

#include <cstdio>
#include <string>

#include "urban_detection/core/classification/object_features.h"

namespace urban_detection {
namespace core {

class FeatureCsvWriter {
 public:
  /// Opens `path` and writes the header `leading_columns` ("dataset,frame,...") then the
  /// feature names; an empty path writes nothing (enabled() false).
  FeatureCsvWriter(const std::string& path, const std::string& leading_columns);
  ~FeatureCsvWriter();
  FeatureCsvWriter(const FeatureCsvWriter&) = delete;
  FeatureCsvWriter& operator=(const FeatureCsvWriter&) = delete;

  bool enabled() const { return !path_.empty(); }
  /// False when the file could not be opened.
  bool ok() const { return path_.empty() || file_ != nullptr; }
  /// One row: `leading_values` (comma-separated, as many as the leading columns), then the
  /// features (%.6g).
  void row(const std::string& leading_values, const ObjectFeatureVector& features);

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

}  // namespace core
}  // namespace urban_detection
