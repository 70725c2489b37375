#pragma once
// What the batch tests share: a fresh folder, a box mesh, a schema standing in for the precompute
// command's parser, and JSON files read back.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/precompute/batch.hpp"
#include "test_support.hpp"

namespace chladni::test::batch_fixtures {

namespace fs = std::filesystem;
namespace batch = chladni::precompute::batch;

// A fresh folder per test and process.
inline fs::path fresh_dir(const std::string& name) {
  const fs::path d =
      chladni::test::temp_path("chladni_batch_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A closed box a x b x c metres (12 triangles); `open` leaves its top off.
inline void write_box(const fs::path& path, double a, double b, double c, bool open = false) {
  std::ofstream f(path);
  for (int v = 0; v < 8; ++v)
    f << "v " << a * (v & 1) << " " << b * (v >> 1 & 1) << " " << c * (v >> 2 & 1) << "\n";
  f << "f 1 3 4\nf 1 4 2\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\n"
       "f 2 8 6\n";
  if (!open) f << "f 5 6 8\nf 5 8 7\n";
}

// Stands in for the precompute command's parser: a few options of each kind, "--max-modes -1"
// refused, and "--max-memory" an asset's own.
inline batch::OptionSchema fake_schema() {
  batch::OptionSchema s;
  s.kind = [](const std::string& n) {
    if (n == "repair" || n == "no-transfer") return batch::OptionSchema::Flag;
    if (n == "material" || n == "max-modes" || n == "E" || n == "max-memory")
      return batch::OptionSchema::Value;
    if (n == "json") return batch::OptionSchema::Managed;
    return batch::OptionSchema::Unknown;
  };
  s.check = [](const std::string&, const std::string&, const std::vector<std::string>& args) {
    batch::OptionSchema::Own own;
    for (std::size_t i = 0; i + 1 < args.size(); ++i) {
      if (args[i] == "--max-modes" && args[i + 1] == "-1")
        throw InputError("--max-modes: negative");
      own.memory = own.memory || args[i] == "--max-memory";
    }
    return own;
  };
  return s;
}

inline nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace chladni::test::batch_fixtures
