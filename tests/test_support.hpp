#pragma once
// Shared helpers: GPU availability (tests skip without a Vulkan device unless
// CHLADNI_REQUIRE_GPU=1, which the CI sets so that the GPU path is really tested).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <span>
#include <string>

#include "chladni/gpu/context.hpp"

namespace chladni::test {

#ifdef CHLADNI_SHARED_MESHES
/// The bundled meshes' folder.
inline const std::string kMeshes = CHLADNI_SHARED_MESHES;
#endif

inline std::shared_ptr<gpu::Context> gpu_context() {
  static std::shared_ptr<gpu::Context> ctx = []() -> std::shared_ptr<gpu::Context> {
    try {
      return std::make_shared<gpu::Context>();
    } catch (const gpu::NoDeviceError& e) {
      if (const char* req = std::getenv("CHLADNI_REQUIRE_GPU"); req && std::string(req) == "1") {
        ADD_FAILURE() << "CHLADNI_REQUIRE_GPU=1 but no Vulkan device: " << e.what();
      }
      return nullptr;
    }
  }();
  return ctx;
}

inline double max_abs(std::span<const float> v) {
  double m = 0;
  for (float x : v) m = std::max(m, double(std::abs(x)));
  return m;
}

/// Largest sample difference; the two signals must have the same length.
inline double max_diff(std::span<const float> a, std::span<const float> b) {
  EXPECT_EQ(a.size(), b.size());
  double m = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    m = std::max(m, double(std::abs(a[i] - b[i])));
  }
  return m;
}

/// A path in this test process's own folder under the system's temporary one (made on first
/// use): ctest runs the tests side by side, and two processes writing and reading one file of
/// the same name raced.
inline std::string temp_path(const std::string& name) {
  static const std::filesystem::path dir = [] {
    const auto d =
        std::filesystem::temp_directory_path() / ("chladni_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return (dir / name).string();
}
/// The whole file as a string ("" when it cannot be read).
inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
/// Writes `text` to temp_path(name) and returns that path.
inline std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path) << text;
  return path;
}

#define CHLADNI_REQUIRE_GPU_OR_SKIP(ctx)     \
  auto ctx = ::chladni::test::gpu_context(); \
  if (!ctx) GTEST_SKIP() << "no Vulkan device on this machine"

}  // namespace chladni::test
