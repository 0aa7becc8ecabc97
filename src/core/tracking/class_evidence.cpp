#include "urban_detection/core/tracking/class_evidence.h"

#include <algorithm>
#include <cmath>

namespace urban_detection {
namespace core {

void ClassEvidence::add(ObjectCategory category, float confidence) {
  const int c = static_cast<int>(category);
  if (c < 0 || c >= kClasses) return;
  double p = std::isfinite(confidence) ? static_cast<double>(confidence) : 0.0;
  p = std::clamp(p, kMinProbability, 1.0 - kMinProbability);
  const double rest = std::max((1.0 - p) / (kClasses - 1), kMinProbability / (kClasses - 1));
  double best = -1e300;
  for (int k = 0; k < kClasses; ++k) {
    log_p_[k] += std::log(k == c ? p : rest);
    best = std::max(best, log_p_[k]);
  }
  // Relative to the best class (keeps the numbers small over long tracks), spread capped.
  for (int k = 0; k < kClasses; ++k) log_p_[k] = std::max(log_p_[k] - best, -kMaxLogSpread);
  ++count_;
}

ObjectCategory ClassEvidence::category() const {
  if (count_ == 0) return ObjectCategory::kUnknown;
  int best = 0;
  for (int k = 1; k < kClasses; ++k) {
    if (log_p_[k] > log_p_[best]) best = k;
  }
  return static_cast<ObjectCategory>(best);
}

float ClassEvidence::probability() const {
  if (count_ == 0) return 0.0f;
  const int best = static_cast<int>(category());
  double sum = 0.0;
  for (int k = 0; k < kClasses; ++k) sum += std::exp(log_p_[k] - log_p_[best]);
  return static_cast<float>(1.0 / sum);
}

}  // namespace core
}  // namespace urban_detection
