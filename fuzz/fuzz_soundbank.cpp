// Bytes -> read_soundbank, and a bank that parses must also become a playable model. Each input
// is tried as given and with its size field and CRCs made consistent, so mutations reach the
// section parsers instead of stopping at a checksum.
#include <zlib.h>

#include <cstring>
#include <vector>

#include "chladni/core/soundbank.hpp"
#include "fuzz_support.hpp"

namespace {

// docs/soundbank-format.md: a 32-byte header (CRC of its first 28 bytes last, the table's CRC
// before it, the file size at 16) and 32-byte table entries (offset at 8, size at 16, CRC at 24).
constexpr std::size_t kHeader = 32, kEntry = 32;

uint32_t crc(const uint8_t* p, std::size_t n) {
  return uint32_t(crc32(crc32(0L, Z_NULL, 0), p, uInt(n)));
}
template <class T>
T get(const std::vector<uint8_t>& b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <class T>
void put(std::vector<uint8_t>& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

void make_consistent(std::vector<uint8_t>& b) {
  if (b.size() < kHeader) return;
  put<uint64_t>(b, 16, b.size());
  const uint32_t count = get<uint32_t>(b, 12);
  if (count > 64 || kHeader + kEntry * std::size_t(count) > b.size()) return;
  for (uint32_t s = 0; s < count; ++s) {
    const std::size_t e = kHeader + kEntry * s;
    const uint64_t off = get<uint64_t>(b, e + 8), size = get<uint64_t>(b, e + 16);
    if (off <= b.size() && size <= b.size() - off)
      put<uint32_t>(b, e + 24, crc(b.data() + off, size));
  }
  put<uint32_t>(b, 24, crc(b.data() + kHeader, kEntry * std::size_t(count)));
  put<uint32_t>(b, 28, crc(b.data(), 28));
}

void parse(const std::vector<uint8_t>& bytes) {
  const std::string path = chladni::fuzz::write_input("input.chbank", bytes.data(), bytes.size());
  chladni::fuzz::expect_clean(path, [&] {
    const chladni::Soundbank b = chladni::read_soundbank(path);
    (void)chladni::to_modal_model(b, "fuzzed");
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  parse(bytes);
  make_consistent(bytes);
  parse(bytes);
  return 0;
}
