#pragma once
// A C API runtime for a test: the CPU backend on one thread, the defaults changed by `adjust`,
// destroyed with the fixture.
#include <gtest/gtest.h>

#include <functional>
#include <vector>

#include "chladni/chladni.h"

namespace chladni::test {

struct CApiRuntime {
  explicit CApiRuntime(const std::function<void(chladni_config&)>& adjust = {}) {
    chladni_config c;
    chladni_config_default(&c);
    c.threads = 1;
    if (adjust) adjust(c);
    EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK) << chladni_last_error();
  }
  ~CApiRuntime() { chladni_runtime_destroy(rt); }
  CApiRuntime(const CApiRuntime&) = delete;
  CApiRuntime& operator=(const CApiRuntime&) = delete;
  /// `frames` interleaved stereo frames.
  std::vector<float> render(uint32_t frames) {
    std::vector<float> out(2 * frames);
    EXPECT_EQ(chladni_runtime_render(rt, out.data(), frames), CHLADNI_OK) << chladni_last_error();
    return out;
  }
  chladni_runtime* rt = nullptr;
};

}  // namespace chladni::test
