/// \file param_loading.h
/// Reading ROS parameters into params structs with range checks.
///
/// Every loader reads an optional private parameter (the struct's in-class default stays when it
/// is not set) and throws ParamError with one message naming the fully resolved parameter, the
/// value and the accepted range. Nodelets catch it in onInit(), log it once and stay inactive,
/// so a bad parameter never takes the nodelet manager down.
#pragma once

#include <ros/node_handle.h>

#include "urban_detection/core/common/param_fields.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace urban_detection {
namespace ros_conv {

/// A missing, mistyped or out-of-range parameter. The message is meant for the user as is.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The one wording of an out-of-range value (core/common/param_fields.h).
using core::outOfRangeMessage;

/// Throws ParamError with outOfRangeMessage() unless min <= value <= max (NaN is rejected).
template <typename T>
void checkRange(const std::string& name, T value, T min, T max, const std::string& unit = "") {
  bool ok = value >= min && value <= max;  // false for NaN
  if (ok) return;
  throw ParamError(outOfRangeMessage(name, value, min, max, unit));
}

/// Reads `name` (relative to `nh`, usually the private node handle) into `*value` when set. A
/// parameter of the wrong type is an error, not silently ignored. Ranges are checked from the
/// field tables afterwards (loadFields below), never here.
void loadParam(const ros::NodeHandle& nh, const std::string& name, bool* value);
void loadParam(const ros::NodeHandle& nh, const std::string& name, std::string* value);
void loadParam(const ros::NodeHandle& nh, const std::string& name, double* value);
void loadParam(const ros::NodeHandle& nh, const std::string& name, int* value);

/// A list of numbers (e.g. polynomial coefficients).
void loadParam(const ros::NodeHandle& nh, const std::string& name, std::vector<double>* value);
/// A list of strings (e.g. class names).
void loadParam(const ros::NodeHandle& nh, const std::string& name, std::vector<std::string>* value);

/// A list of exactly N numbers (ranges are checked afterwards, per element).
template <std::size_t N>
void loadParam(const ros::NodeHandle& nh, const std::string& name, std::array<double, N>* value) {
  if (!nh.hasParam(name)) return;
  std::vector<double> list;
  loadParam(nh, name, &list);
  if (list.size() != N) {
    throw ParamError("parameter '" + nh.resolveName(name) + "' must be a list of " +
                     std::to_string(N) + " numbers");
  }
  std::copy(list.begin(), list.end(), value->begin());
}

/// An enum field of a table: one of the names `info` lists.
template <class E, typename = std::enable_if_t<std::is_enum_v<E>>>
void loadParam(const ros::NodeHandle& nh, const core::FieldInfo& info, E* value) {
  std::string name = core::choiceName(info, *value);
  loadParam(nh, info.name, &name);
  if (!core::parseChoice(info, name, value)) {
    throw ParamError(core::badChoiceMessage(nh.resolveName(info.name), name, info.choices));
  }
}

/// "" when `params` is valid, else why not: the field table's ranges (core/common/param_fields.h)
/// with the parameter named as resolved in `nh`, then validate()'s cross-field rules. The
/// start-up loader and every dynamic_reconfigure update check through here.
template <class Params>
std::string checkFields(const ros::NodeHandle& nh, const Params& params) {
  std::string error = core::checkFieldRanges(
      params, [&nh](const std::string& name) { return nh.resolveName(name); });
  if (error.empty()) {
    error = validate(params);  // core::validate, or the ROS layer's for its own structs
    if (!error.empty()) error = "in " + nh.getNamespace() + ": " + error;
  }
  return error;
}

/// Reads every field of `params`' table that is set under `nh` (a value of the wrong type is an
/// error, not ignored), then checkFields(): throws ParamError with the first problem.
template <class Params>
void loadFields(const ros::NodeHandle& nh, Params* params) {
  core::forEachField(*params, [&nh](const core::FieldInfo& info, auto& field) {
    if constexpr (std::is_enum_v<std::decay_t<decltype(field)>>) {
      loadParam(nh, info, &field);
    } else {
      loadParam(nh, info.name, &field);
    }
  });
  const std::string error = checkFields(nh, *params);
  if (!error.empty()) throw ParamError(error);
}

}  // namespace ros_conv
}  // namespace urban_detection
