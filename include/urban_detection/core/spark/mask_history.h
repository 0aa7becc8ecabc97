/// \file mask_history.h
/// The hand-over between the camera stage's inference thread and its objects callback:
/// MaskHistory keeps the last few segmented images so an object cloud can take the newest mask
/// whose stamp is close enough to its own. Header-only, ROS-free, thread-safe.
#pragma once

#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>

namespace urban_detection {
namespace core {

/// The last `capacity` values with their stamps [s], newest last.
template <typename T>
class MaskHistory {
 public:
  explicit MaskHistory(std::size_t capacity = 4) : capacity_(capacity < 1 ? 1 : capacity) {}

  void push(double stamp_s, std::shared_ptr<const T> value) {
    std::lock_guard<std::mutex> lock(mutex_);
    entries_.push_back({stamp_s, std::move(value)});
    while (entries_.size() > capacity_) entries_.pop_front();
  }
  /// The newest value whose stamp differs from `stamp_s` by at most `max_gap_s` (null if none);
  /// `gap_s` (optional) receives its signed gap, value stamp - stamp_s.
  std::shared_ptr<const T> newestWithin(double stamp_s, double max_gap_s,
                                        double* gap_s = nullptr) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = entries_.rbegin(); it != entries_.rend(); ++it) {
      if (std::fabs(it->stamp_s - stamp_s) <= max_gap_s) {
        if (gap_s != nullptr) *gap_s = it->stamp_s - stamp_s;
        return it->value;
      }
    }
    return nullptr;
  }
  bool empty() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return entries_.empty();
  }

 private:
  struct Entry {
    double stamp_s;
    std::shared_ptr<const T> value;
  };
  mutable std::mutex mutex_;
  std::size_t capacity_;
  std::deque<Entry> entries_;
};

}  // namespace core
}  // namespace urban_detection
