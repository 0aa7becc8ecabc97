#include "urban_detection/core/evaluation/feature_table.h"

namespace urban_detection {
namespace core {

FeatureCsvWriter::FeatureCsvWriter(const std::string& path, const std::string& leading_columns)
    : path_(path) {
  if (path_.empty()) return;
  file_ = std::fopen(path_.c_str(), "w");
  if (!file_) return;
  std::fputs(leading_columns.c_str(), file_);
  for (int k = 0; k < kNumObjectFeatures; ++k) std::fprintf(file_, ",%s", featureName(k));
  std::fprintf(file_, "\n");
}

FeatureCsvWriter::~FeatureCsvWriter() {
  if (file_) std::fclose(file_);
}

void FeatureCsvWriter::row(const std::string& leading_values, const ObjectFeatureVector& features) {
  if (!file_) return;
  std::fputs(leading_values.c_str(), file_);
  for (const float v : features) std::fprintf(file_, ",%.6g", v);
  std::fprintf(file_, "\n");
}

}  // namespace core
}  // namespace urban_detection
