/// \file param_loading.h
/// Reading ROS parameters into params structs with range checks.
///
/// Every loader reads an optional private parameter (the struct's in-class default stays when it
/// is not set) and throws ParamError with one message naming the fully resolved parameter, the
/// value and the accepted range. Nodelets catch it in onInit(), log it once and stay inactive,
/// so a bad parameter never takes the nodelet manager down.
#pragma once

#include <ros/node_handle.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace urban_detection {

/// A missing, mistyped or out-of-range parameter. The message is meant for the user as is.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The one wording of an out-of-range value, at start-up and in a refused dynamic_reconfigure
/// update of every stage: "parameter '<name>' = <value> is out of range: accepted [<min>,
/// <max>] <unit>". `name` is the name shown to the user (resolved where a node handle is at
/// hand), `unit` is appended to the range ("m", "s", "deg"; may be empty).
template <typename T>
std::string outOfRangeMessage(const std::string& name, T value, T min, T max,
                              const std::string& unit = "") {
  std::ostringstream msg;
  msg << "parameter '" << name << "' = " << value << " is out of range: accepted [" << min
      << ", " << max << "]" << (unit.empty() ? "" : " ") << unit;
  return msg.str();
}

/// Throws ParamError with outOfRangeMessage() unless min <= value <= max (NaN is rejected).
template <typename T>
void checkRange(const std::string& name, T value, T min, T max, const std::string& unit = "") {
  bool ok = value >= min && value <= max;  // false for NaN
  if (ok) return;
  throw ParamError(outOfRangeMessage(name, value, min, max, unit));
}

/// Reads `name` (relative to `nh`, usually the private node handle) into `*value` when set, then
/// checks the range. A parameter of the wrong type is an error, not silently ignored.
void loadParam(const ros::NodeHandle& nh, const std::string& name, double* value, double min,
               double max, const std::string& unit = "");
void loadParam(const ros::NodeHandle& nh, const std::string& name, int* value, int min,
               int max, const std::string& unit = "");
void loadParam(const ros::NodeHandle& nh, const std::string& name, bool* value);
void loadParam(const ros::NodeHandle& nh, const std::string& name, std::string* value);
/// Type-checked only (for structs whose ranges are checked as a whole afterwards).
void loadParam(const ros::NodeHandle& nh, const std::string& name, double* value);
void loadParam(const ros::NodeHandle& nh, const std::string& name, int* value);

/// The numeric fields of one params struct with their accepted ranges: the one list that both
/// the start-up loader (load()) and dynamic_reconfigure (check()) use, so a value is accepted
/// through one path exactly when it is accepted through the other. Holds pointers to the fields
/// of one struct instance; build it for the instance to load or check.
class ParamTable {
 public:
  /// `name` relative to the node handle given to load() / check() ("weight/max_weight" is fine).
  ParamTable& add(const std::string& name, double* field, double min, double max,
                  const std::string& unit = "");
  ParamTable& add(const std::string& name, int* field, int min, int max,
                  const std::string& unit = "");
  /// loadParam() of every field in order: throws ParamError on the first bad one.
  void load(const ros::NodeHandle& nh) const;
  /// "" when every field is within its range, else the ParamError message of the first one
  /// that is not (naming the parameter resolved in `nh`, its value and the accepted range).
  std::string check(const ros::NodeHandle& nh) const;

 private:
  struct Entry {
    std::string name, unit;
    double* d;  // exactly one of d, i is set
    int* i;
    double dmin, dmax;
    int imin, imax;
  };
  std::vector<Entry> entries_;
};

}  // namespace urban_detection
