/// \file latest_slot.h
/// The hand-over between the camera stage's callbacks and its inference thread:
/// LatestSlot keeps only the newest input (an older one not yet taken is dropped, so the
/// network always works on the newest image and never builds a queue), and MaskHistory keeps
/// the last few segmented images so an object cloud can take the newest mask whose stamp is
/// close enough to its own. Header-only, ROS-free, thread-safe.
#pragma once

#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>

namespace urban_detection {
namespace core {

/// A one-element mailbox: put() replaces what is there, take() waits for a value.
template <typename T>
class LatestSlot {
 public:
  /// Stores `value`; a value not taken yet is dropped (counted in dropped()).
  void put(std::shared_ptr<const T> value) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (value_) ++dropped_;
      value_ = std::move(value);
    }
    cv_.notify_one();
  }
  /// Waits until a value is there or close() was called; returns it (null after close()).
  std::shared_ptr<const T> take() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return value_ != nullptr || closed_; });
    if (closed_) return nullptr;
    return std::move(value_);
  }
  /// Wakes take() for good (shutdown).
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }
  std::uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::shared_ptr<const T> value_;
  std::uint64_t dropped_ = 0;
  bool closed_ = false;
};

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
