/// \file tunable_fields.h
/// dynamic_reconfigure Configs <-> parameter structs, by name through the struct's field table
/// (core/common/param_fields.h): the .cfg entry of the field "hough/votes" is `hough_votes`.
/// A .cfg lists the fields worth tuning live; it declares no ranges (the table's apply, see
/// validated_reconfigure.h). unmatchedConfigEntries() lists the entries naming no field, and a
/// test requires it to be empty for every Config, so a .cfg entry cannot silently do nothing.
/// Header-only and free of the generated Config headers: the functions are templates on the
/// Config type.
#pragma once

#include <algorithm>
#include <string>
#include <type_traits>
#include <vector>

#include <dynamic_reconfigure/Config.h>

#include "urban_detection/core/common/param_fields.h"

namespace urban_detection {
namespace ros_conv {

/// The .cfg name of a field: its table name with '/' replaced by '_'.
inline std::string configName(std::string field_name) {
  std::replace(field_name.begin(), field_name.end(), '/', '_');
  return field_name;
}

namespace detail {

template <class T>
auto& entriesOf(dynamic_reconfigure::Config& msg) {
  if constexpr (std::is_same_v<T, bool>) {
    return msg.bools;
  } else if constexpr (std::is_same_v<T, int>) {
    return msg.ints;
  } else if constexpr (std::is_same_v<T, double>) {
    return msg.doubles;
  } else {
    return msg.strs;
  }
}

template <class T>
constexpr bool kConfigurable = std::is_same_v<T, bool> || std::is_same_v<T, int> ||
                               std::is_same_v<T, double> || std::is_same_v<T, std::string>;

// Calls f(entry, field) for every field of `params` with an entry of its name and type.
template <class Params, class F>
void forEachConfigured(dynamic_reconfigure::Config& msg, Params& params, F f) {
  core::forEachField(params, [&](const core::FieldInfo& info, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (kConfigurable<T>) {
      const std::string name = configName(info.name);
      for (auto& entry : entriesOf<T>(msg)) {
        if (entry.name == name) f(entry, field);
      }
    }
  });
}

}  // namespace detail

/// A Config holding `params`' values of the fields it lists (the others at the .cfg default).
template <class Config, class Params>
Config toConfig(const Params& params) {
  Config config = Config::__getDefault__();
  dynamic_reconfigure::Config msg;
  config.__toMessage__(msg);
  detail::forEachConfigured(msg, params,
                            [](auto& entry, const auto& field) { entry.value = field; });
  config.__fromMessage__(msg);
  return config;
}

/// `base` with the fields `config` lists replaced by its values.
template <class Config, class Params>
Params fromConfig(const Config& config, Params base) {
  dynamic_reconfigure::Config msg;
  config.__toMessage__(msg);
  detail::forEachConfigured(msg, base, [](const auto& entry, auto& field) {
    field = static_cast<std::decay_t<decltype(field)>>(entry.value);
  });
  return base;
}

/// The Config's entries that name no field of Params of their type (empty when the .cfg and the
/// table agree).
template <class Config, class Params>
std::vector<std::string> unmatchedConfigEntries() {
  dynamic_reconfigure::Config msg;
  Config::__getDefault__().__toMessage__(msg);
  Params params;
  std::vector<std::string> matched;
  detail::forEachConfigured(msg, params,
                            [&](const auto& entry, auto&) { matched.push_back(entry.name); });
  std::vector<std::string> unmatched;
  auto collect = [&](const auto& entries) {
    for (const auto& e : entries) {
      if (std::find(matched.begin(), matched.end(), e.name) == matched.end()) {
        unmatched.push_back(e.name);
      }
    }
  };
  collect(msg.bools);
  collect(msg.ints);
  collect(msg.doubles);
  collect(msg.strs);
  return unmatched;
}

}  // namespace ros_conv
}  // namespace urban_detection
