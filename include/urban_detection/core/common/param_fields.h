/// \file param_fields.h
/// One field table per parameter struct: every parameter's name, unit, accepted range and
/// meaning, written once beside its struct as a ParamFields<Params> specialisation. Everything
/// else is derived from it:
///   - validate(Params) checks the table's ranges (checkFieldRanges) before its cross-field rules;
///   - the YAML reader (core/params/params_yaml.h) binds exactly the table's keys, rejecting
///     unknown keys and wrong types;
///   - the ROS loader and the dynamic_reconfigure check (ros/param_loading.h) read, type-check
///     and range-check the same fields under the same names;
///   - dynamic_reconfigure Configs are filled from and copied back to the struct by name
///     (ros/param_loading.h), and a test checks that every .cfg entry names a table field;
///   - docs/parameters.md is printed from the tables (urban_detection_params), and a test checks
///     that it is current.
/// A new parameter is therefore one struct member and one line in its table.
///
/// A table is `template <class P, class F> static void visit(P& p, F&& f)` (P is the struct or
/// const struct) calling `f(FieldInfo{...}, p.member)` for every field in order; nested
/// parameter structs are visited with forEachField(p.sub, "sub", f), which names their fields
/// "sub/field". Fields are double, int, bool, std::string, std::vector<double>,
/// std::vector<std::string>, std::array<double, N>, an enum, a list of fixed-size points
/// (std::vector of a fixed-size Eigen vector, e.g. waypoints) or a list of tabled structs
/// (std::vector<S> with a ParamFields<S>; its elements' fields are named "list[i]/field").
/// Ranges apply to the numbers, to each element of a std::array and to each coordinate of a
/// point (inclusive); an enum field is written as one of the names its FieldInfo::choice() lists
/// (the names of its values 0, 1, 2, ... in order); the elements of a list of structs are checked
/// against their own table; the other types take any value of their type.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace urban_detection {
namespace core {

/// What the field table says about one parameter.
struct FieldInfo {
  /// A number with its accepted range [min, max] (inclusive) and unit ("m", "deg", "" ...).
  FieldInfo(std::string name, std::string unit, double min, double max, std::string description)
      : name(std::move(name)),
        unit(std::move(unit)),
        min(min),
        max(max),
        description(std::move(description)) {}
  /// A flag, a text or a list (no range).
  FieldInfo(std::string name, std::string description)
      : name(std::move(name)), description(std::move(description)) {}
  /// An enum field: `choices` are the names of its values 0, 1, 2, ... (what files and the
  /// parameter server hold).
  static FieldInfo choice(std::string name, std::vector<std::string> choices,
                          std::string description) {
    FieldInfo info(std::move(name), std::move(description));
    info.choices = std::move(choices);
    return info;
  }

  std::string name;  // relative name; nested structs as "sub/field"
  std::string unit;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  std::string description;
  std::vector<std::string> choices;  // enum fields: the name of each value
};

/// Specialised beside every parameter struct (see the file comment).
template <class Params>
struct ParamFields;

/// Calls `f(const FieldInfo&, field&)` for every field of `params` (const or not), in table order.
template <class Params, class F>
void forEachField(Params& params, F&& f) {
  ParamFields<std::remove_const_t<Params>>::visit(params, f);
}

/// The fields of a nested struct, named "<prefix>/<field>".
template <class Sub, class F>
void forEachField(Sub& sub, const std::string& prefix, F&& f) {
  forEachField(sub, [&](const FieldInfo& info, auto& field) {
    FieldInfo nested = info;
    nested.name = prefix + "/" + info.name;
    f(nested, field);
  });
}

/// True for the field types a range applies to.
template <class T>
constexpr bool kRangedField = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;

/// True for fixed-size lists of numbers (std::array<double, N>): the range applies to each.
template <class T>
struct IsRangedArray : std::false_type {};
template <std::size_t N>
struct IsRangedArray<std::array<double, N>> : std::true_type {};
template <class T>
constexpr bool kRangedArray = IsRangedArray<T>::value;

/// True for types with a field table (a ParamFields specialisation declared before the use).
template <class T, class = void>
struct HasFieldTable : std::false_type {};
template <class T>
struct HasFieldTable<T, std::void_t<decltype(sizeof(ParamFields<T>))>> : std::true_type {};

/// True for lists of tabled structs (std::vector<S>, S with a field table).
template <class T>
struct IsTabledList : std::false_type {};
template <class S, class A>
struct IsTabledList<std::vector<S, A>> : HasFieldTable<S> {};
template <class T>
constexpr bool kTabledList = IsTabledList<T>::value;

/// True for lists of fixed-size points (std::vector of a fixed-size Eigen vector): the range
/// applies to each coordinate.
template <class T, class = void>
struct IsPointList : std::false_type {};
template <class V, class A>
struct IsPointList<std::vector<V, A>, std::void_t<decltype(V::SizeAtCompileTime)>>
    : std::bool_constant<(V::SizeAtCompileTime > 0)> {};
template <class T>
constexpr bool kPointList = IsPointList<T>::value;

/// The name of enum `value` in `info.choices` ("" when it has none).
template <class E>
std::string choiceName(const FieldInfo& info, E value) {
  const auto i = static_cast<std::size_t>(value);
  return i < info.choices.size() ? info.choices[i] : std::string();
}

/// Sets enum `*value` from its name; false (value unchanged) for a name `info` does not list.
template <class E>
bool parseChoice(const FieldInfo& info, const std::string& name, E* value) {
  for (std::size_t i = 0; i < info.choices.size(); ++i) {
    if (info.choices[i] == name) {
      *value = static_cast<E>(i);
      return true;
    }
  }
  return false;
}

/// "parameter '<name>' = '<value>' is not one of: a, b, c" (the one wording of a bad name).
inline std::string badChoiceMessage(const std::string& name, const std::string& value,
                                    const std::vector<std::string>& choices) {
  std::string msg = "parameter '" + name + "' = '" + value + "' is not one of:";
  for (std::size_t i = 0; i < choices.size(); ++i) msg += (i ? ", " : " ") + choices[i];
  return msg;
}

/// The one wording of an out-of-range value, at start-up, in YAML files, in a refused
/// dynamic_reconfigure update and in validate(): "parameter '<name>' = <value> is out of range:
/// accepted [<min>, <max>] <unit>".
template <typename T>
std::string outOfRangeMessage(const std::string& name, T value, T min, T max,
                              const std::string& unit = "") {
  std::ostringstream msg;
  msg << "parameter '" << name << "' = " << value << " is out of range: accepted [" << min << ", "
      << max << "]" << (unit.empty() ? "" : " ") << unit;
  return msg.str();
}

/// "" when every number of `params` lies in its table range, else outOfRangeMessage() of the
/// first one that does not (NaN never does). `shown` maps a field name to the name shown to the
/// user (e.g. resolved in a ROS namespace).
template <class Params, class Shown>
std::string checkFieldRanges(const Params& params, Shown shown) {
  std::string error;
  forEachField(params, [&](const FieldInfo& info, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (kRangedField<T>) {
      if (error.empty() && !(value >= info.min && value <= info.max)) {
        error = outOfRangeMessage(shown(info.name), value, static_cast<T>(info.min),
                                  static_cast<T>(info.max), info.unit);
      }
    } else if constexpr (kRangedArray<T>) {
      for (std::size_t i = 0; i < value.size() && error.empty(); ++i) {
        if (!(value[i] >= info.min && value[i] <= info.max)) {
          error = outOfRangeMessage(shown(info.name) + "[" + std::to_string(i) + "]", value[i],
                                    info.min, info.max, info.unit);
        }
      }
    } else if constexpr (kPointList<T>) {
      for (std::size_t i = 0; i < value.size() && error.empty(); ++i) {
        for (int k = 0; k < value[i].size() && error.empty(); ++k) {
          if (!(value[i][k] >= info.min && value[i][k] <= info.max)) {
            error = outOfRangeMessage(
                shown(info.name) + "[" + std::to_string(i) + "][" + std::to_string(k) + "]",
                static_cast<double>(value[i][k]), info.min, info.max, info.unit);
          }
        }
      }
    } else if constexpr (kTabledList<T>) {
      for (std::size_t i = 0; i < value.size() && error.empty(); ++i) {
        const std::string element = shown(info.name) + "[" + std::to_string(i) + "]/";
        error = checkFieldRanges(value[i],
                                 [&element](const std::string& name) { return element + name; });
      }
    } else if constexpr (std::is_enum_v<T>) {
      if (error.empty() && choiceName(info, value).empty()) {
        error = badChoiceMessage(shown(info.name), std::to_string(static_cast<long long>(value)),
                                 info.choices);
      }
    }
  });
  return error;
}

template <class Params>
std::string checkFieldRanges(const Params& params) {
  return checkFieldRanges(params, [](const std::string& name) { return name; });
}

/// The rows of fieldTableMarkdown() for `params`, names prefixed by `prefix`.
template <class Params>
void fieldTableRows(const Params& params, const std::string& prefix, std::ostringstream& md) {
  forEachField(params, [&md, &prefix](const FieldInfo& info, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    md << "| `" << prefix << info.name << "` | ";
    if constexpr (std::is_same_v<T, bool>) {
      md << (value ? "true" : "false") << " | | | ";
    } else if constexpr (std::is_same_v<T, std::string>) {
      md << "\"" << value << "\" | | | ";
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      md << value.size() << " numbers | | | ";
    } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      md << "[";
      for (std::size_t i = 0; i < value.size(); ++i) md << (i ? ", " : "") << value[i];
      md << "] | | | ";
    } else if constexpr (kRangedArray<T>) {
      md << "[";
      for (std::size_t i = 0; i < value.size(); ++i) md << (i ? ", " : "") << value[i];
      md << "] | [" << info.min << ", " << info.max << "] each | " << info.unit << " | ";
    } else if constexpr (kPointList<T>) {
      md << value.size() << " points | [" << info.min << ", " << info.max << "] each | "
         << info.unit << " | ";
    } else if constexpr (kTabledList<T>) {
      md << value.size() << " entries | | | ";
    } else if constexpr (std::is_enum_v<T>) {
      md << choiceName(info, value) << " | ";
      for (std::size_t i = 0; i < info.choices.size(); ++i)
        md << (i ? ", " : "") << info.choices[i];
      md << " | | ";
    } else {
      md << value << " | [" << static_cast<T>(info.min) << ", " << static_cast<T>(info.max)
         << "] | " << info.unit << " | ";
    }
    md << info.description << " |\n";
    if constexpr (kTabledList<T>) {
      fieldTableRows(typename T::value_type(), prefix + info.name + "[]/", md);
    }
  });
}

/// The Markdown table of `params`' fields (name, default = the value in `params`, range, unit,
/// description): docs/parameters.md is made of these (urban_detection_params). A list of
/// structs is one row (its length) followed by the rows of its element's table, named
/// "list[]/field", with the defaults of a default-constructed element.
template <class Params>
std::string fieldTableMarkdown(const Params& params) {
  std::ostringstream md;
  md << "| parameter | default | range | unit | description |\n|---|---|---|---|---|\n";
  fieldTableRows(params, "", md);
  return md.str();
}

}  // namespace core
}  // namespace urban_detection
