// Bytes -> load_scene (JSON syntax, duplicate keys, every field's bounds).
#include "chladni/core/scene.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = chladni::fuzz::write_input("scene.json", data, size);
  chladni::fuzz::expect_clean(path, [&] { (void)chladni::load_scene(path); });
  return 0;
}
