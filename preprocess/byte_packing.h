// Packing plain values into byte blobs and reading them back with bounds checks: the private
// layouts of the preprocessor's spill files and resume blobs (bricked scenes, brick DAGs).
// Host byte order; the blobs never leave the machine that wrote them.
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/glm.hpp>

#include "format_error.h"

namespace tw {

class ByteWriter {
 public:
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  // u32 length, then the characters.
  void putString(const std::string& s) {
    put(static_cast<uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  // u32 count, then the points.
  void putVec2s(const std::vector<glm::vec2>& v) {
    put(static_cast<uint32_t>(v.size()));
    for (const auto& p : v) put(p);
  }
  // u64 count, then the elements.
  template <typename T>
  void putArray(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<uint64_t>(v.size());
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
  }

  std::vector<uint8_t> bytes;
};

// Every read checks the bytes left; a short or damaged blob throws FormatError naming `source`
// and the offset (`base` + position in the blob).
class ByteReader {
 public:
  ByteReader(std::span<const uint8_t> bytes, std::string source, uint64_t base = 0)
      : bytes_(bytes), source_(std::move(source)), base_(base) {}

  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  std::string getString() {
    uint32_t n = get<uint32_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(bytes_.data() + at_), n);
    at_ += n;
    return s;
  }
  std::vector<glm::vec2> getVec2s() {
    uint32_t n = get<uint32_t>();
    need(uint64_t{n} * sizeof(glm::vec2));
    std::vector<glm::vec2> v(n);
    for (auto& p : v) p = get<glm::vec2>();
    return v;
  }
  template <typename T>
  std::vector<T> getArray() {
    uint64_t n = get<uint64_t>();
    if (n > remaining() / sizeof(T))
      fail("array of " + std::to_string(n) + " elements runs past the end");
    std::vector<T> v(n);
    std::memcpy(v.data(), bytes_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
    return v;
  }

  uint64_t remaining() const { return bytes_.size() - at_; }
  bool atEnd() const { return at_ == bytes_.size(); }
  void need(uint64_t n) const {
    if (n > remaining())
      fail("needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) + " left");
  }
  [[noreturn]] void fail(const std::string& reason) const {
    throw FormatError::atByte(source_, base_ + at_, reason);
  }

 private:
  std::span<const uint8_t> bytes_;
  std::string source_;
  uint64_t base_;
  size_t at_ = 0;
};

}  // namespace tw
