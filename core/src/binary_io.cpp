#include "binary_io.hpp"

#include <zlib.h>

#include <algorithm>

namespace chladni::binary_io {

uint32_t crc32_of(const uint8_t* p, std::size_t n) {
  uLong c = crc32(0L, Z_NULL, 0);
  while (n > 0) {  // zlib takes uInt lengths
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    c = crc32(c, p, chunk);
    p += chunk, n -= chunk;
  }
  return static_cast<uint32_t>(c);
}

}  // namespace chladni::binary_io
