// Temporary files of the tests: names unique per process, so that test runs of several
// checkouts on one machine (or a sanitizer run beside a normal one) do not collide.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

namespace ud_test {

/// A path in the test temporary directory: "<TempDir>ud_<pid>_<name>".
inline std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "ud_" + std::to_string(::getpid()) + "_" + name;
}

/// A temporary file with the given text, removed at the end of its scope.
class TempFile {
 public:
  TempFile(const std::string& suffix, const std::string& text) {
    static int counter = 0;
    path_ = tempPath("tmp" + std::to_string(counter++) + suffix);
    std::ofstream(path_) << text;
  }
  ~TempFile() { std::remove(path_.c_str()); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace ud_test
