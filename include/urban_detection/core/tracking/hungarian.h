/// \file hungarian.h
/// Minimum-cost one-to-one assignment (the Hungarian algorithm, shortest augmenting paths with
/// row and column potentials, O(n^2 m) for n <= m). ROS-free; used by the Tracker for data
/// association and by the CLEAR-MOT scoring.
#pragma once

#include <vector>

namespace urban_detection {
namespace core {

/// Assigns rows to columns of the `rows` x `cols` matrix `cost` (row-major, finite values) so
/// that min(rows, cols) pairs are formed with the smallest total cost. `row_to_col` receives,
/// per row, its column or -1 (rows > cols leaves some rows out). Returns the total cost.
/// Callers that forbid pairs give them a large finite cost and drop such pairs afterwards: the
/// result then has as few forbidden pairs as possible and, among those, the smallest cost.
/// `scratch` (optional) holds the working arrays between calls.
double solveAssignment(const std::vector<double>& cost, int rows, int cols,
                       std::vector<int>* row_to_col, std::vector<double>* scratch = nullptr);

}  // namespace core
}  // namespace urban_detection
