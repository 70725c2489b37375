// Bytes -> read_paper_frames_binary (the .chpaper frame file), as given and with the trailing
// CRC-32 made to match, so mutations reach the counts and arrays.
#include <zlib.h>

#include <cstring>
#include <vector>

#include "chladni/core/paper_animation.hpp"
#include "fuzz_support.hpp"

namespace {

void parse(const std::vector<uint8_t>& bytes) {
  const std::string path = chladni::fuzz::write_input("frames.chpaper", bytes.data(), bytes.size());
  chladni::fuzz::expect_clean(path, [&] {
    chladni::PaperAnimation anim;
    chladni::read_paper_frames_binary(path, anim);
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  parse(bytes);
  if (bytes.size() >= 4) {
    const uint32_t c = uint32_t(crc32(crc32(0L, Z_NULL, 0), bytes.data(), uInt(bytes.size() - 4)));
    std::memcpy(bytes.data() + bytes.size() - 4, &c, 4);
    parse(bytes);
  }
  return 0;
}
