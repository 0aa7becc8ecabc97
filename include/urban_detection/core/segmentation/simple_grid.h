/// \file simple_grid.h
/// The Simple Grid Model of the paper (Sec. 3, "Simple Grid Model"): a regular 2-D grid on
/// the sensor's horizontal plane holding per-cell height statistics. ROS-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "urban_detection/core/common/point_types.h"

namespace urban_detection {
namespace core {

/// Geometry of the simple grid.
struct SimpleGridParams {
  double cell_size_m = 0.5;   // [m] side W_S of a square cell
  double max_range_m = 80.0;  // [m] half side of the square grid centred on the sensor;
                              //     points outside it are not gridded
};

/// A read-only view of a contiguous array (the grid's per-slot tables, which are kept at their
/// full size between frames and only partly valid).
template <typename T>
class ConstArrayView {
 public:
  ConstArrayView(const T* data, std::size_t size) : data_(data), size_(size) {}
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  std::vector<T> toVector() const { return std::vector<T>(begin(), end()); }

 private:
  const T* data_;
  std::size_t size_;
};

/// An allocator whose resize() leaves new elements of trivial types uninitialised: the grid's
/// per-point tables grow with every appended batch of points and are written whole right
/// after, so zero-filling them first would be a wasted pass over a megabyte per revolution.
template <typename T>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// Height statistics of one cell. Heights are referenced to the ground below the sensor
/// (z + sensor height), as in the paper.
struct GridCell {
  std::uint32_t count = 0;                             // points in the cell
  float z_min = std::numeric_limits<float>::max();     // [m] lowest point height
  float z_max = std::numeric_limits<float>::lowest();  // [m] highest point height
  float z_sum = 0.0f;                                  // [m] sum of heights (mean = z_sum/count)

  float zMean() const { return count > 0 ? z_sum / static_cast<float>(count) : 0.0f; }
  float zRange() const { return count > 0 ? z_max - z_min : 0.0f; }
};

/// A bounded square grid of side 2 * max_range_m centred on the sensor. Each finite point
/// within range goes to the cell containing its projection on the z = 0 plane. Buffers are
/// kept between frames; build() only resets the cells the previous frame touched, so its cost
/// is proportional to the number of points, not to the grid area.
///
/// Storage: the statistics of the occupied cells are kept compactly, in first-touch order
/// (a frame occupies a few thousand of the 100k+ cells: 16-byte records spread over the whole
/// grid would mostly miss the caches), and a per-cell slot map gives each occupied cell's
/// position in that order. Every point keeps its slot, so later per-point passes read small
/// per-slot tables instead of grid-sized ones.
class SimpleGrid {
 public:
  /// Marks a point that has no cell (non-finite, beyond max_range_m or absurdly high/low).
  static constexpr std::int32_t kNoCell = -1;

  explicit SimpleGrid(const SimpleGridParams& params = SimpleGridParams());

  /// Per-point tables (one entry per point of the cloud, in order).
  template <typename T>
  using PointTable = std::vector<T, DefaultInitAllocator<T>>;

  /// Assigns every point of `cloud` to its cell. `z_offset_m` [m] is added to each z (the
  /// sensor height, so heights become heights above the ground below the sensor).
  /// Points with |z + z_offset_m| > max_abs_height_m are treated as invalid.
  void build(const CloudXYZIRT& cloud, float z_offset_m, float max_abs_height_m = 100.0f);

  /// The same in pieces, as a revolution arrives: begin() empties the grid, each append()
  /// bins the next `count` points of the cloud (its points begin() + appended() on), and
  /// finish() completes the statistics. begin(); append(...)...; finish() over any split of a
  /// cloud gives exactly build() of the whole cloud (same slots, same floats): a run of
  /// points in one cell may span two appends. `expected_points` only reserves memory.
  void begin(float z_offset_m, float max_abs_height_m = 100.0f, std::size_t expected_points = 0);
  void append(const PointXYZIRT* points, std::size_t count);
  void finish();
  /// finish() that leaves the grid open: the statistics then hold every point appended so
  /// far, and append() may go on (the run left open is taken out of its cell again and
  /// continues), so finish() at the end still gives build()'s floats.
  void settle();
  /// Points binned since begin().
  std::size_t appended() const { return point_slot_.size(); }
  /// Points binned since begin() with a NaN or infinite coordinate (counted while binning,
  /// so a revolution binned as it arrives needs no pass of its own at its end).
  std::size_t nonFinitePoints() const { return non_finite_; }

  const SimpleGridParams& params() const { return params_; }
  int rows() const { return side_; }  ///< cells along y
  int cols() const { return side_; }  ///< cells along x
  std::size_t numCells() const { return slot_.size(); }

  /// Linear cell index (row * cols + col) of point i of the last cloud, or kNoCell.
  std::int32_t pointCell(std::size_t i) const {
    const std::int32_t s = point_slot_[i];
    return s == 0 ? kNoCell : occupied_[s - 1];
  }
  /// Per point of the last cloud: 1 + the slot (position in occupiedCells()) of its cell, or 0
  /// for a point without a cell.
  const PointTable<std::int32_t>& pointSlots() const { return point_slot_; }
  /// Height of point i above the ground below the sensor [m] (valid when pointCell != kNoCell).
  float pointHeight(std::size_t i) const { return point_z_[i]; }
  const PointTable<float>& pointHeights() const { return point_z_; }

  /// Statistics of a cell (all-default for an empty cell).
  const GridCell& cell(std::int32_t index) const {
    const std::int32_t s = slot_[index];
    return s < 0 ? kEmptyCell : occupied_cells_[s];
  }
  const GridCell& cell(int row, int col) const { return cell(row * side_ + col); }
  /// Linear indices of the cells holding at least one point, in first-touch order; a cell's
  /// position in this list is its slot.
  ConstArrayView<std::int32_t> occupiedCells() const {
    return ConstArrayView<std::int32_t>(occupied_.data(), num_occupied_);
  }
  /// Statistics of the occupied cells, by slot (same order as occupiedCells()).
  ConstArrayView<GridCell> occupiedStats() const {
    return ConstArrayView<GridCell>(occupied_cells_.data(), num_occupied_);
  }
  /// Slot of a cell, or -1 when it holds no point.
  std::int32_t slotOf(std::int32_t index) const { return slot_[index]; }

  /// Row and column of a linear cell index. A division by a runtime divisor costs tens of
  /// cycles and the terrain growing does it per visited cell: the quotient is taken from a
  /// double multiply by 1 / cols and corrected by one where rounding made it off (exact for
  /// every index of the grid).
  int rowOf(std::int32_t index) const {
    int q = static_cast<int>(static_cast<double>(index) * inv_side_);
    q -= q * side_ > index;
    q += (q + 1) * side_ <= index;
    return q;
  }
  int colOf(std::int32_t index) const { return index - rowOf(index) * side_; }
  /// build() computes the cells of eight points at a time with AVX2 when the CPU has it
  /// (checked at run time; same results as the SSE2 path). false forces the SSE2 path
  /// (tests compare the two).
  void setAllowAvx2(bool allow) { allow_avx2_ = allow; }
  /// Whether build() uses the AVX2 path (allowed and supported by this CPU).
  bool avx2Active() const;

  /// Cell of a metric position, or kNoCell when outside the grid or non-finite.
  std::int32_t cellAt(float x_m, float y_m) const;
  /// Centre of a cell in the sensor frame [m].
  void cellCenter(std::int32_t index, float* x_m, float* y_m) const {
    const int row = rowOf(index);
    *x_m = origin_m_ + (static_cast<float>(index - row * side_) + 0.5f) * cell_m_;
    *y_m = origin_m_ + (static_cast<float>(row) + 0.5f) * cell_m_;
  }

 private:
  static const GridCell kEmptyCell;
  SimpleGridParams params_;
  int side_ = 0;
  float inv_cell_ = 1.0f;
  double inv_side_ = 1.0;           // [1/cells] 1 / side_, for rowOf
  float origin_m_ = 0.0f;           // [m] coordinate of the grid's lower-left corner (both axes)
  float cell_m_ = 1.0f;             // [m] cell side as a float (cellCenter)
  std::vector<std::int32_t> slot_;  // per cell: slot, or -1 (reset on occupied_ only)
  // Per slot, numCells() + 1 entries (the first num_occupied_ valid): build() writes the entry
  // of the next slot for every run, new cell or not, so that it needs no branch on newness.
  std::vector<std::int32_t> occupied_;    // per slot: cell index
  std::vector<GridCell> occupied_cells_;  // per slot: statistics
  std::size_t num_occupied_ = 0;
  std::size_t non_finite_ = 0;           // see nonFinitePoints()
  PointTable<std::int32_t> point_slot_;  // per point: 1 + slot, 0 = no cell
  PointTable<float> point_z_;
  // Between begin() and finish(): the height offset and bound, and the run of points in one
  // cell still open at the end of the last append() (its sums not yet in the cell's).
  float z_offset_m_ = 0.0f, max_abs_height_m_ = 100.0f;
  struct Run {
    std::int32_t cell = kNoCell, slot = -1;
    std::uint32_t count = 0;
    float min = 0.0f, max = 0.0f, sum = 0.0f;
  };
  Run run_;
  // After settle(): the open run's cell as it was before the run was added to it.
  bool settled_ = false;
  GridCell settled_cell_;
  void unsettle();
  std::vector<std::int32_t> chunk_cell_;  // scratch: cell indices of one chunk of points
  bool allow_avx2_ = true;
};

}  // namespace core
}  // namespace urban_detection
