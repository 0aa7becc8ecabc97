/// \file field_yaml.h
/// The one YAML reader of the parameter structs: a YAML map applied to a struct through its field
/// table (core/common/param_fields.h). Nested maps for nested structs ("hough: {votes: 8}" is the
/// field "hough/votes"), a list of maps for a list of tabled structs, a list of [x, y] for a list
/// of points; an unknown key or a value of the wrong type is an error naming it. ROS-free; used by
/// params_yaml.h and by the simulation config.
#pragma once

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "urban_detection/core/common/param_fields.h"

namespace urban_detection {
namespace core {

/// Sets the fields of `params` named in the YAML map `node`, without validating. Field names are
/// prefixed by `prefix` ("" or e.g. "scene/sections[2]"), the keys of `node` being relative to
/// it; error messages start with `where` (e.g. "file.yaml: "). Returns "" or the error; `params`
/// may then be partly updated.
template <class Params>
std::string bindFieldsYaml(const YAML::Node& node, const std::string& where,
                           const std::string& prefix, Params* params) {
  // A setter returns "" or why the value was refused (a YAML::Exception: the wrong type).
  std::map<std::string, std::function<std::string(const YAML::Node&)>> setters;
  std::set<std::string> groups;  // "hough", "weight", ...: names of nested maps
  auto bind = [&](const FieldInfo& info, auto& field) {
    using T = std::decay_t<decltype(field)>;
    setters[info.name] = [&field, info, where](const YAML::Node& n) -> std::string {
      if constexpr (std::is_enum_v<T>) {
        const std::string name = n.as<std::string>();
        if (!parseChoice(info, name, &field)) {
          return where + badChoiceMessage(info.name, name, info.choices);
        }
      } else if constexpr (kRangedArray<T>) {
        const auto list = n.as<std::vector<double>>();
        if (list.size() != field.size()) {
          return where + "parameter '" + info.name + "' needs " + std::to_string(field.size()) +
                 " numbers, has " + std::to_string(list.size());
        }
        std::copy(list.begin(), list.end(), field.begin());
      } else if constexpr (kTabledList<T>) {
        if (!n.IsSequence()) return where + info.name + ": expected a list of maps";
        T list;
        for (std::size_t i = 0; i < n.size(); ++i) {
          typename T::value_type element{};
          const std::string error =
              bindFieldsYaml(n[i], where, info.name + "[" + std::to_string(i) + "]", &element);
          if (!error.empty()) return error;
          list.push_back(element);
        }
        field = std::move(list);
      } else if constexpr (kPointList<T>) {
        using V = typename T::value_type;
        if (!n.IsSequence()) return where + info.name + ": expected a list of points";
        T list;
        for (std::size_t i = 0; i < n.size(); ++i) {
          const auto xs = n[i].as<std::vector<double>>();
          if (xs.size() != static_cast<std::size_t>(V::SizeAtCompileTime)) {
            return where + "parameter '" + info.name + "[" + std::to_string(i) + "]' needs " +
                   std::to_string(V::SizeAtCompileTime) + " numbers, has " +
                   std::to_string(xs.size());
          }
          V point;
          for (int k = 0; k < V::SizeAtCompileTime; ++k) point[k] = xs[k];
          list.push_back(point);
        }
        field = std::move(list);
      } else {
        field = n.as<T>();
      }
      return "";
    };
    for (std::size_t slash = info.name.find('/'); slash != std::string::npos;
         slash = info.name.find('/', slash + 1)) {
      groups.insert(info.name.substr(0, slash));
    }
  };
  if (prefix.empty()) {
    forEachField(*params, bind);
  } else {
    forEachField(*params, prefix, bind);
  }
  std::string error;
  std::function<bool(const YAML::Node&, const std::string&)> walk = [&](const YAML::Node& map,
                                                                        const std::string& at) {
    if (!map.IsMap()) {
      error = where + at + "expected a map of parameters";
      return false;
    }
    for (const auto& kv : map) {
      const std::string name = at + kv.first.as<std::string>();
      const auto setter = setters.find(name);
      if (setter != setters.end()) {
        try {
          error = setter->second(kv.second);
        } catch (const YAML::Exception& e) {
          error = where + name + ": wrong type (" + e.what() + ")";
        }
        if (!error.empty()) return false;
      } else if (groups.count(name)) {
        if (!walk(kv.second, name + "/")) return false;
      } else {
        error = where + name + ": unknown parameter";
        return false;
      }
    }
    return true;
  };
  walk(node, prefix.empty() ? "" : prefix + "/");
  return error;
}

/// bindFieldsYaml() of the whole of `node`, then the complete struct is validated (its table's
/// ranges and cross-field rules: `std::string validate(const Params&)`). False with `error` set.
template <class Params>
bool applyFieldsYaml(const YAML::Node& node, const std::string& where, Params* params,
                     std::string* error) {
  *error = bindFieldsYaml(node, where, "", params);
  if (!error->empty()) return false;
  const std::string invalid = validate(*params);
  if (!invalid.empty()) *error = where + invalid;
  return invalid.empty();
}

}  // namespace core
}  // namespace urban_detection
