/// \file fuzz_common.h
/// Helpers shared by the libFuzzer targets: a byte reader that never fails (missing bytes read
/// as zero) and a per-process scratch file for the parsers that only take a path.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace urban_detection {
namespace fuzz {

/// Consumes a fuzz input front to back; reads past the end yield zeros.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t remaining() const { return size_ - pos_; }
  bool empty() const { return pos_ >= size_; }

  std::uint8_t u8() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() {
    return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16);
  }
  std::int16_t i16() {
    const std::uint16_t v = u16();
    std::int16_t s;
    std::memcpy(&s, &v, sizeof s);
    return s;
  }
  /// Raw IEEE bits: any float including NaN, inf and denormals.
  float rawFloat() {
    const std::uint32_t v = u32();
    float f;
    std::memcpy(&f, &v, sizeof f);
    return f;
  }
  /// The rest of the input.
  const std::uint8_t* rest(std::size_t* n) {
    *n = remaining();
    const std::uint8_t* p = data_ + pos_;
    pos_ = size_;
    return p;
  }
  /// Up to `n` bytes.
  const std::uint8_t* take(std::size_t n, std::size_t* got) {
    *got = n < remaining() ? n : remaining();
    const std::uint8_t* p = data_ + pos_;
    pos_ += *got;
    return p;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// A file in $TMPDIR (or /tmp) owned by this process, rewritten with each input: the
/// calibration and pcap readers take a path, as they do in the nodelets.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& suffix) {
    const char* dir = std::getenv("TMPDIR");
    path_ = std::string(dir != nullptr && *dir != '\0' ? dir : "/tmp") + "/ud_fuzz_" +
            std::to_string(::getpid()) + "_" + std::to_string(counter()++) + suffix;
  }
  ~ScratchFile() { std::remove(path_.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  /// Replaces the file's content; aborts if the file cannot be written (a harness fault, not
  /// a finding).
  const std::string& write(const std::uint8_t* data, std::size_t size) {
    std::FILE* f = std::fopen(path_.c_str(), "wb");
    if (f == nullptr) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    return path_;
  }
  const std::string& path() const { return path_; }

 private:
  static int& counter() {
    static int n = 0;
    return n;
  }
  std::string path_;
};

/// Aborts with a message: an invariant the code under test promises was broken. libFuzzer
/// reports the abort as a crash and saves the input.
[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fuzz invariant violated: %s\n", what);
  std::abort();
}
#define UD_FUZZ_CHECK(cond)                            \
  do {                                                 \
    if (!(cond)) ::urban_detection::fuzz::fail(#cond); \
  } while (0)

}  // namespace fuzz
}  // namespace urban_detection
