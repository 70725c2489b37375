#pragma once
// Little-endian binary encoding with bounds-checked reads and CRC-32 (zlib), shared by the
// soundbank and the paper-frame file. Reads name the file and what was truncated.
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "chladni/core/error.hpp"

namespace chladni::binary_io {

/// CRC-32 (zlib's polynomial) of n bytes.
uint32_t crc32_of(const uint8_t* p, std::size_t n);

// Explicit little-endian encoding, independent of the host's byte order.
class Writer {
 public:
  std::vector<uint8_t> bytes;
  void u8s(const void* p, std::size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
  template <class T>
  void le(T v) {
    using U = std::conditional_t<sizeof(T) == 8, uint64_t,
                                 std::conditional_t<sizeof(T) == 4, uint32_t, uint16_t>>;
    const U u = std::bit_cast<U>(v);
    for (std::size_t k = 0; k < sizeof(T); ++k) bytes.push_back(uint8_t(u >> (8 * k)));
  }
  void str(const std::string& s) {
    le<uint32_t>(static_cast<uint32_t>(s.size()));
    u8s(s.data(), s.size());
  }
};

class Reader {
 public:
  Reader(const uint8_t* p, std::size_t n, std::string where)
      : p_(p), n_(n), where_(std::move(where)) {}
  template <class T>
  T le() {
    need(sizeof(T));
    using U = std::conditional_t<sizeof(T) == 8, uint64_t,
                                 std::conditional_t<sizeof(T) == 4, uint32_t, uint16_t>>;
    U u = 0;
    for (std::size_t k = 0; k < sizeof(T); ++k) u |= U(p_[pos_ + k]) << (8 * k);
    pos_ += sizeof(T);
    return std::bit_cast<T>(u);
  }
  /// n values in a row; fails naming `what` if they do not fit.
  template <class T>
  void le_array(T* out, std::size_t n, const char* what) {
    need_items(n, sizeof(T), what);
    if (n == 0) return;  // out may be null (an empty vector's data())
    if constexpr (std::endian::native == std::endian::little) {
      std::memcpy(out, p_ + pos_, n * sizeof(T));
      pos_ += n * sizeof(T);
    } else {
      for (std::size_t i = 0; i < n; ++i) out[i] = le<T>();
    }
  }
  std::size_t position() const { return pos_; }
  std::string str(std::size_t max_len) {
    const uint32_t len = le<uint32_t>();
    if (len > max_len) fail("string length " + std::to_string(len) + " is implausible");
    need(len);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), len);
    pos_ += len;
    return s;
  }
  // Count of items of `item_bytes` each that must still fit in the section.
  void need_items(uint64_t count, std::size_t item_bytes, const char* what) {
    if (count > (n_ - pos_) / item_bytes) {
      fail(std::string(what) + ": " + std::to_string(count) + " items of " +
           std::to_string(item_bytes) + " bytes do not fit in the " + std::to_string(n_ - pos_) +
           " bytes left (truncated or corrupted)");
    }
  }
  void expect_end() {
    if (pos_ != n_) fail(std::to_string(n_ - pos_) + " unexpected trailing bytes");
  }
  [[noreturn]] void fail(const std::string& what) const { throw InputError(where_ + ": " + what); }

 private:
  void need(std::size_t k) {
    if (n_ - pos_ < k) fail("truncated (needs " + std::to_string(k) + " more bytes)");
  }
  const uint8_t* p_;
  std::size_t n_, pos_ = 0;
  std::string where_;
};

}  // namespace chladni::binary_io
