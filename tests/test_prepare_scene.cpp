// The one path from a scene to sound: prepare_scene sizes one filterbank for a scene's modes and
// shake voices, and playing the prepared scene equals playing its parts by hand; the filterbank
// factory's device choice.
#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "chladni/runtime/scene/prepare_scene.hpp"
#include "chladni/runtime/scene/scene_timeline.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

Scene shaken_scene() {
  return parse_scene(nlohmann::json::parse(R"({
    "sample_rate": 44100, "channels": 2, "duration": 1.0,
    "listener": {"position": [0, 1.2, 0.5]},
    "objects": [
      {"name": "rod", "position": [0.2, 1, 0], "bar": {"length": 0.25}},
      {"name": "glass", "position": [-0.4, 1, 0],
       "modes": [{"frequency": 1200, "decay": 5, "amplitude": 0.1},
                 {"frequency": 2650, "decay": 9, "amplitude": 0.05}]}
    ],
    "events": [
      {"time": 0.0, "type": "shake", "object": "rod", "instrument": "gravel", "energy": 0.8},
      {"time": 0.1, "type": "impact", "object": "rod", "impulse": 0.01},
      {"time": 0.3, "type": "shake", "object": "rod", "instrument": "gravel", "energy": 0.5},
      {"time": 0.4, "type": "shake", "object": "glass", "instrument": "coins"},
      {"time": 0.6, "type": "impact", "object": "glass", "impulse": 0.01}
    ]})"),
                     ".");
}

// Sets an environment variable for a scope.
struct ScopedEnv {
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value, 1);
  }
  ~ScopedEnv() { old_.empty() ? unsetenv(name_) : setenv(name_, old_.c_str(), 1); }
  const char* name_;
  std::string old_;
};

}  // namespace

TEST(PrepareScene, SizesOneFilterbankAndPlaysAsThePartsByHand) {
  const Scene scene = shaken_scene();
  SceneSettings s;
  s.filterbank.threads = 1;
  PreparedScene p = prepare_scene(scene, s);
  ASSERT_EQ(p.objects.size(), 2u);
  EXPECT_NE(p.playable[0].summary.find("modes"), std::string::npos) << p.playable[0].summary;
  ASSERT_EQ(p.shakers.voices.size(), 2u);  // the two gravel shakes share a voice
  // Fewer than 1024 modes: the budget is 1024, and the shake voices sit in slots above it.
  EXPECT_EQ(p.options.synth.max_modes, 1024u);
  EXPECT_EQ(p.filterbank->capacity(), 1024u + p.shakers.slots);
  EXPECT_EQ(p.filterbank->channels(), 2);
  const AudioBuffer prepared = render_scene(scene, p);
  ASSERT_GT(test::max_abs(prepared.samples), 0.0);

  // The parts by hand: the same objects, a filterbank of the same size, shakers built inside.
  CpuFilterbank by_hand({.capacity = 1024 + p.shakers.slots, .channels = 2, .threads = 1});
  const AudioBuffer parts = render_scene(scene, p.objects, by_hand, p.options);
  ASSERT_EQ(parts.samples.size(), prepared.samples.size());
  EXPECT_EQ(test::max_diff(parts.samples, prepared.samples), 0.0);

  // Live, block by block, from a second preparation: the same samples.
  PreparedScene q = prepare_scene(scene, s);
  SceneTimeline timeline(scene, q);
  std::vector<float> live(prepared.samples.size());
  timeline.render(static_cast<uint32_t>(prepared.frames()), live.data());
  EXPECT_EQ(test::max_diff(live, prepared.samples), 0.0);
}

TEST(PrepareScene, GpuPlaysAsTheCpuOrFallsBackWithOneWarning) {
  const Scene scene = shaken_scene();
  SceneSettings s;
  s.filterbank.backend = gpu::DeviceChoice::Gpu;
  std::vector<std::string> warnings;
  s.filterbank.warn = [&](const std::string& w) { warnings.push_back(w); };
  PreparedScene g = prepare_scene(scene, s);
  PreparedScene c = prepare_scene(scene, {});
  const AudioBuffer a = render_scene(scene, c), b = render_scene(scene, g);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  EXPECT_LT(test::max_diff(a.samples, b.samples), 1e-4 * test::max_abs(a.samples));
  if (test::gpu_context()) {
    EXPECT_TRUE(g.filterbank->name().starts_with("gpu")) << g.filterbank->name();
    EXPECT_TRUE(warnings.empty());
  } else {
    EXPECT_TRUE(g.filterbank->name().starts_with("cpu")) << g.filterbank->name();
    ASSERT_EQ(warnings.size(), 1u);
  }
}

TEST(MakeFilterbank, AutoTakesAHardwareGpuOnlyAndGpuFailsOrFallsBackAsAsked) {
  FilterbankRequest r;
  r.capacity = 64;
  r.backend = gpu::DeviceChoice::Auto;
  const auto ctx = test::gpu_context();
  const bool hardware = ctx && gpu::is_hardware_gpu(ctx->info());
  EXPECT_EQ(make_filterbank(r)->name().starts_with("gpu"), hardware);  // lavapipe: the CPU

  // No device: a selector that matches none, as a machine without one looks to the factory.
  const ScopedEnv none("CHLADNI_VULKAN_DEVICE", "no-such-gpu");
  std::vector<std::string> warnings;
  r.warn = [&](const std::string& w) { warnings.push_back(w); };
  EXPECT_TRUE(make_filterbank(r)->name().starts_with("cpu"));  // auto: silently
  EXPECT_TRUE(warnings.empty());
  r.backend = gpu::DeviceChoice::Gpu;
  EXPECT_TRUE(make_filterbank(r)->name().starts_with("cpu"));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("using the CPU filterbank instead"), std::string::npos);
  r.gpu_falls_back = false;  // the C API's GPU: an error, not a slower path
  EXPECT_THROW(make_filterbank(r), gpu::NoDeviceError);
}

TEST(MakeFilterbank, NamesAnUnknownOrUnsupportedInstructionSet) {
  try {
    parse_cpu_isa("sse", "--isa");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--isa: unknown instruction set 'sse' (auto, scalar, avx2, avx512)");
  }
  for (CpuIsa isa : {CpuIsa::Avx2, CpuIsa::Avx512}) {
    FilterbankRequest r;
    r.capacity = 64;
    r.isa = isa;
    if (CpuFilterbank::supports(isa))
      EXPECT_NO_THROW(make_filterbank(r));
    else
      EXPECT_THROW(make_filterbank(r), InputError);
  }
}
