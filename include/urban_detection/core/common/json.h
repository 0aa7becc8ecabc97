/// \file json.h
/// The one JSON string escaper of the reports (evaluation, benchmarks, SPARK records). ROS-free.
#pragma once

#include <cstdio>
#include <string>

namespace urban_detection {
namespace core {

/// `s` as the inside of a JSON string literal: quotes and backslashes escaped, control
/// characters written as \u00XX.
inline std::string jsonEscape(const std::string& s) {
  std::string out;
  out.reserve(s.size() + 2);
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out;
}

}  // namespace core
}  // namespace urban_detection
