// Bytes -> read_number_rows (radiate's --velocity and --points files).
#include "chladni/core/number_table.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = chladni::fuzz::write_input("table.txt", data, size);
  chladni::fuzz::expect_clean(path, [&] {
    for (const auto& row : chladni::read_number_rows(path, 1, 3, "points file"))
      if (row.empty() || row.size() > 3) std::abort();
  });
  return 0;
}
