// One harness per mesh format (CHLADNI_FUZZ_EXT names it): bytes -> read_mesh.
#include "chladni/precompute/surface_mesh.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = chladni::fuzz::write_input("input" CHLADNI_FUZZ_EXT, data, size);
  chladni::fuzz::expect_clean(path, [&] {
    const chladni::precompute::SurfaceMesh m = chladni::precompute::read_mesh(path);
    for (const auto& t : m.triangles)
      for (uint32_t v : t)
        if (v >= m.vertices.size()) std::abort();  // the reader promised valid indices
  });
  return 0;
}
