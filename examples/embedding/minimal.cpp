// The same from C++, one layer down: a filterbank, a ScenePlayer and a soundbank's modes.
// Built by the tests; run it with a soundbank path or without (an analytic steel bar).
#include <chladni/core.hpp>
#include <chladni/runtime.hpp>
#include <cmath>
#include <cstdio>
#include <vector>

int main(int argc, char** argv) try {
  using namespace chladni;
  const double fs = 48000;
  // A soundbank's modes below Nyquist, or a bar's with its material's damping.
  ModalModel model = argc > 1
                         ? runtime::playable_model(read_soundbank(argv[1]), "bowl", fs, argv[1])
                         : analytic_bar(BarSpec{});
  if (argc == 1) keep_modes(model, apply_damping(model, BarSpec{}.damping, 20.0, 20000.0, fs).kept);

  // A hardware GPU where there is one, else the CPU filterbank.
  const auto fb = runtime::make_filterbank(
      {.backend = gpu::DeviceChoice::Auto, .capacity = 1 << 16, .channels = 2, .max_frames = 256});
  runtime::ScenePlayer player(*fb, {.sample_rate = fs, .synth = {.sample_rate = fs}});
  const std::size_t k =
      player.add_object(runtime::object_modes(model), {0.3, 1.0, 0.0}, {1, 0, 0, 0});
  player.finish_objects();  // control thread: allocates

  ImpactEvent hit;  // audio thread from here on: nothing allocates
  hit.impulse = 0.01;
  hit.direction = {0, 0, -1};
  hit.point = Vec3{0.0, 0.0, 0.0};
  hit.contact_time = 0.0005;
  player.impact(k, hit, 10.5);  // at fractional sample 10.5 of the next render
  std::vector<float> buffer(256 * 2);
  double peak = 0;
  for (int b = 0; b < 188; ++b) {
    player.render(256, buffer.data());
    for (float x : buffer) peak = std::max(peak, double(std::abs(x)));
  }
  std::printf("%s: 1 s rendered, peak %.3g Pa\n", fb->name().c_str(), peak);
  return peak > 0 ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 2;
}
