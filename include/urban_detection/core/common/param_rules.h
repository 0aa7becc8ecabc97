/// \file param_rules.h
/// The wording of the cross-field rules of the validate() functions (the field tables check
/// each field's own range; a rule between two fields is checked after them).
#pragma once

#include <sstream>
#include <string>

namespace urban_detection {
namespace core {

/// Two parameters out of order: "parameter '<low>' = <a> must be at most '<high>' = <b>
/// <unit>"; "" when a <= b.
inline std::string orderMessage(const std::string& low, double a, const std::string& high, double b,
                                const std::string& unit = "") {
  if (a <= b) return "";
  std::ostringstream msg;
  msg << "parameter '" << low << "' = " << a << " must be at most '" << high << "' = " << b
      << (unit.empty() ? "" : " ") << unit;
  return msg.str();
}

}  // namespace core
}  // namespace urban_detection
