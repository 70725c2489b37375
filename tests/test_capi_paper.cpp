// Paper sound through the live renderer and the C API: frames posted one at a time give the
// samples `chladni paper` renders from the same animation, at the time the API promises.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "capi_fixtures.hpp"
#include "chladni/chladni.h"
#include "chladni/core/error.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"
#include "chladni/tools/paper_db_generate.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

const std::string kPaper = CHLADNI_SOURCE_DIR "/meshes/paper/";

// A small default-style database: one variant, short clips (fast to generate).
const PaperSoundDb& live_test_db() {
  static const PaperSoundDb db = [] {
    tools::PaperDbOptions o;
    o.variants = 1;
    o.clip_seconds = 0.1;
    o.clip_modes = 64;
    o.spectrum_modes = 128;
    return tools::generate_paper_database(o);
  }();
  return db;
}

// The same database as a folder, for the C API.
const std::string& live_test_db_dir() {
  static const std::string dir = [] {
    const std::string d = test::temp_path("paper_live_db");
    tools::write_paper_database(d, live_test_db());
    return d;
  }();
  return dir;
}

std::unique_ptr<CpuFilterbank> stereo_bank() {
  CpuFilterbankOptions o;
  o.channels = 2;
  o.capacity = 1 << 18;
  o.threads = 1;
  return std::make_unique<CpuFilterbank>(o);
}

PaperSynthOptions options(PaperSynthMode mode, bool live) {
  PaperSynthOptions o;
  o.mode = mode;
  o.live = live;
  return o;
}

}  // namespace

// A live renderer fed the animation's frames one at a time and read as it goes gives exactly the
// offline renderer's samples, in both modes, with friction (slide) and crumpling (crumple).
TEST(PaperLive, FramesOneAtATimeGiveTheOfflineSamples) {
  for (const PaperSynthMode mode : {PaperSynthMode::Database, PaperSynthMode::Modal}) {
    for (const char* name : {"slide", "crumple"}) {
      const PaperAnimation a = load_paper_animation(kPaper + name + ".json");
      auto fb = stereo_bank();
      const AudioBuffer offline = render_paper(a, &live_test_db(), fb.get(), options(mode, false));
      auto fb2 = stereo_bank();
      PaperRenderer live(a, &live_test_db(), fb2.get(), options(mode, true));
      std::vector<float> got, chunk;
      for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
        live.step(a.frame(f));
        chunk.resize(2 * live.ready());
        live.read(chunk.data(), live.ready());
        got.insert(got.end(), chunk.begin(), chunk.end());
      }
      live.end();
      chunk.resize(2 * live.ready());
      live.read(chunk.data(), live.ready());
      got.insert(got.end(), chunk.begin(), chunk.end());
      ASSERT_EQ(got.size(), offline.samples.size()) << name;
      EXPECT_GT(test::max_abs(got), 1e-3) << name;
      EXPECT_EQ(got, offline.samples) << name << ", mode " << int(mode);
      EXPECT_THROW(live.step(a.frame(0)), InputError);  // after its end
    }
  }
}

namespace {

// Posts every frame of `a` to a C API sheet, rendering one frame period after each post as an
// engine would, then removes it and renders its tail; returns the output. With `hold`, each
// frame names the vertices the animation's anchors hold then.
std::vector<float> post_animation(chladni_runtime* rt, const PaperAnimation& a,
                                  const chladni_paper_desc& desc, std::size_t tail,
                                  bool hold = false) {
  chladni_paper sheet{0};
  EXPECT_EQ(chladni_paper_add(rt, &desc, &sheet), CHLADNI_OK) << chladni_last_error();
  const uint32_t period = 735;  // 44100 / 60
  std::vector<float> out, block(2 * period);
  for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
    const std::span<const float> x = a.frame(f);
    std::vector<uint32_t> held;
    for (uint32_t v = 0; v < a.vertex_count; ++v)
      if (a.anchored(v, f)) held.push_back(v);
    EXPECT_EQ(
        chladni_paper_post_frame(rt, sheet, x.data(), a.vertex_count, hold ? held.data() : nullptr,
                                 hold ? uint32_t(held.size()) : 0),
        CHLADNI_OK)
        << chladni_last_error();
    EXPECT_EQ(chladni_runtime_render(rt, block.data(), period), CHLADNI_OK);
    out.insert(out.end(), block.begin(), block.end());
  }
  EXPECT_EQ(chladni_paper_remove(rt, sheet), CHLADNI_OK) << chladni_last_error();
  std::vector<float> rest(2 * tail);
  EXPECT_EQ(chladni_runtime_render(rt, rest.data(), uint32_t(tail)), CHLADNI_OK);
  out.insert(out.end(), rest.begin(), rest.end());
  // Gone: its handle is refused.
  EXPECT_EQ(chladni_paper_post_frame(rt, sheet, a.frame(0).data(), a.vertex_count, nullptr, 0),
            CHLADNI_INPUT_ERROR);
  return out;
}

}  // namespace

// Frames posted through the C API sound as `chladni paper` renders the same animation, one frame
// period after the first was posted: database mode from a database folder, modal mode on the
// sheet's own filterbank.
TEST(CApiPaper, PostedFramesSoundAsTheAnimationRenders) {
  for (const char* mode : {"database", "modal"}) {
    const PaperAnimation a = load_paper_animation(kPaper + "crumple.json");
    auto fb = stereo_bank();
    const PaperSoundDb db = load_paper_database(live_test_db_dir());  // as the runtime reads it
    const AudioBuffer offline =
        render_paper(a, &db, fb.get(), options(parse_paper_mode(mode), false));
    test::CApiRuntime rt([](chladni_config& c) {
      c.sample_rate = 44100;
      c.max_papers = 1;
    });
    chladni_paper_desc d{};
    const std::string path = kPaper + "crumple.json";
    d.animation = path.c_str();
    d.mode = mode;
    d.database = live_test_db_dir().c_str();
    const std::size_t tail = offline.frames() + 4410 - 735 * a.frame_count();
    const std::vector<float> got = post_animation(rt.rt, a, d, tail);
    ASSERT_EQ(got.size(), 2 * (offline.frames() + 4410));
    const double peak = test::max_abs(offline.samples);
    ASSERT_GT(peak, 1e-3);
    double diff = 0, before = 0, after = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
      const std::size_t t = i / 2;
      if (t < 735) {
        before = std::max(before, double(std::abs(got[i])));
      } else if (t - 735 < offline.frames()) {
        diff = std::max(diff, double(std::abs(got[i] - offline.samples[i - 2 * 735])));
      } else {
        after = std::max(after, double(std::abs(got[i])));
      }
    }
    EXPECT_EQ(before, 0) << mode << ": sound before the first frame's period";
    EXPECT_LT(diff, 1e-6 * peak) << mode;
    EXPECT_EQ(after, 0) << mode << ": sound after the sheet's end";
    // The place came back once its tail played: a new sheet fits in max_papers = 1.
    chladni_paper again{0};
    EXPECT_EQ(chladni_paper_add(rt.rt, &d, &again), CHLADNI_OK) << chladni_last_error();
  }
}

// An inline sheet (a game's cloth), its held vertices posted with each frame, sounds as the
// animation file of the same sheet and frames.
TEST(CApiPaper, InlineSheetSoundsAsTheSameAnimation) {
  PaperAnimation a = load_paper_animation(kPaper + "slide.json");
  test::CApiRuntime file([](chladni_config& c) { c.sample_rate = 44100; });
  test::CApiRuntime inline_([](chladni_config& c) { c.sample_rate = 44100; });
  chladni_paper_desc d{};
  const std::string path = kPaper + "slide.json";
  d.animation = path.c_str();
  d.database = live_test_db_dir().c_str();
  const std::vector<float> from_file = post_animation(file.rt, a, d, 30000);
  std::vector<uint32_t> tris;
  for (const auto& t : a.triangles) tris.insert(tris.end(), t.begin(), t.end());
  std::vector<chladni_paper_plane> planes;
  for (const PaperObstacle& o : a.obstacles)
    planes.push_back({{o.point[0], o.point[1], o.point[2]},
                      {2 * o.normal[0], 2 * o.normal[1], 2 * o.normal[2]},  // not unit
                      o.friction.c_str()});
  chladni_paper_desc in{};
  in.vertex_count = a.vertex_count;
  in.triangles = tris.data();
  in.triangle_count = uint32_t(a.triangles.size());
  in.planes = planes.data();
  in.plane_count = uint32_t(planes.size());
  in.frame_rate = a.frame_rate;
  in.contact_distance = a.contact_distance;
  const PaperListener& l = a.listener;
  const double listener[9] = {l.position[0], l.position[1], l.position[2],
                              l.forward[0],  l.forward[1],  l.forward[2],
                              l.up[0],       l.up[1],       l.up[2]};
  std::copy(listener, listener + 9, in.listener);
  in.database = d.database;
  ASSERT_FALSE(a.anchors.empty());  // a hand drags it: held through every post
  const std::vector<float> from_inline = post_animation(inline_.rt, a, in, 30000, true);
  EXPECT_GT(test::max_abs(from_file), 1e-3);
  EXPECT_EQ(from_inline, from_file);
}

// What cannot play is refused, naming the argument, and leaves the sheet as it was.
TEST(CApiPaper, RefusesWhatCannotPlay) {
  test::CApiRuntime rt([](chladni_config& c) {
    c.sample_rate = 44100;
    c.max_papers = 1;
  });
  const PaperAnimation a = load_paper_animation(kPaper + "crumple.json");
  const std::string path = kPaper + "crumple.json";
  chladni_paper_desc d{};
  d.animation = path.c_str();
  chladni_paper sheet{0};
  auto refused = [&](chladni_status s, const std::string& says) {
    EXPECT_EQ(s, CHLADNI_INPUT_ERROR) << says;
    EXPECT_NE(std::string(chladni_last_error()).find(says), std::string::npos)
        << chladni_last_error();
  };
  d.mode = "granular";
  refused(chladni_paper_add(rt.rt, &d, &sheet), "granular");
  d.mode = "database";
  refused(chladni_paper_add(rt.rt, &d, &sheet), "desc.database");
  d.database = "/nonexistent/paper_db";
  refused(chladni_paper_add(rt.rt, &d, &sheet), "/nonexistent/paper_db");
  d.mode = nullptr;
  d.database = nullptr;
  d.gain = -1;
  refused(chladni_paper_add(rt.rt, &d, &sheet), "gain");
  d.gain = 0;
  d.listener[0] = NAN;
  refused(chladni_paper_add(rt.rt, &d, &sheet), "listener position");
  d.listener[0] = 0;
  chladni_paper_desc in{};
  const uint32_t bad[3] = {0, 1, 7};
  in.vertex_count = 3;
  in.triangles = bad;
  in.triangle_count = 1;
  refused(chladni_paper_add(rt.rt, &in, &sheet), "refers to vertex 7");
  EXPECT_EQ(sheet.id, 0u);

  ASSERT_EQ(chladni_paper_add(rt.rt, &d, &sheet), CHLADNI_OK) << chladni_last_error();
  chladni_paper second{0};
  EXPECT_EQ(chladni_paper_add(rt.rt, &d, &second), CHLADNI_QUEUE_FULL);
  std::vector<float> x(a.frame(0).begin(), a.frame(0).end());
  refused(chladni_paper_post_frame(rt.rt, sheet, x.data(), a.vertex_count - 1, nullptr, 0),
          "vertex_count");
  x[7] = INFINITY;
  refused(chladni_paper_post_frame(rt.rt, sheet, x.data(), a.vertex_count, nullptr, 0),
          "xyz[7] (vertex 2)");
  x[7] = a.frame(0)[7];
  const uint32_t held = a.vertex_count;
  refused(chladni_paper_post_frame(rt.rt, sheet, x.data(), a.vertex_count, &held, 1),
          "holds vertex");
  refused(chladni_paper_post_frame(rt.rt, chladni_paper{sheet.id + (1ull << 32)}, x.data(),
                                   a.vertex_count, nullptr, 0),
          "no paper sheet");
  // Frames posted with no render in between fill half a second, then wait for the audio thread.
  std::uint32_t taken = 0;
  chladni_status s = CHLADNI_OK;
  for (; taken < 100 && s == CHLADNI_OK; ++taken)
    s = chladni_paper_post_frame(rt.rt, sheet, a.frame(taken % 2).data(), a.vertex_count, nullptr,
                                 0);
  EXPECT_EQ(s, CHLADNI_QUEUE_FULL);
  EXPECT_GE(taken, 30u);  // half a second at 60 frames/s
  std::vector<float> out(2 * 44100);
  ASSERT_EQ(chladni_runtime_render(rt.rt, out.data(), 44100), CHLADNI_OK);
  EXPECT_EQ(chladni_paper_post_frame(rt.rt, sheet, a.frame(0).data(), a.vertex_count, nullptr, 0),
            CHLADNI_OK)
      << chladni_last_error();
  for (float v : out) ASSERT_TRUE(std::isfinite(v));
}

// A sheet that follows the listener is heard from where chladni_listener_set puts it: from the
// sheet's right the right ear is louder, from its left the left one; without following, the
// animation's own listener hears it the same both times.
TEST(CApiPaper, AFollowerHearsTheListenerWhereTheGameMovesIt) {
  const PaperAnimation a = load_paper_animation(kPaper + "crumple.json");
  const auto energies = [&](double x, int follow) {
    test::CApiRuntime rt([](chladni_config& c) { c.sample_rate = 44100; });
    const double at[3] = {x, -0.3, 0.2}, forward[3] = {0, 1, 0}, up[3] = {0, 0, 1};
    EXPECT_EQ(chladni_listener_set(rt.rt, 0, at, forward, up), CHLADNI_OK);
    chladni_paper_desc d{};
    const std::string path = kPaper + "crumple.json";
    d.animation = path.c_str();
    d.follow_listener = follow;
    const std::vector<float> out = post_animation(rt.rt, a, d, 30000);
    std::array<double, 2> e{0, 0};
    for (std::size_t i = 0; i < out.size(); ++i) e[i % 2] += double(out[i]) * out[i];
    return e;
  };
  const auto right = energies(0.6, 1), left = energies(-0.6, 1);
  EXPECT_GT(right[0], 1.5 * right[1]) << "the sheet on the listener's left";
  EXPECT_GT(left[1], 1.5 * left[0]) << "the sheet on the listener's right";
  EXPECT_EQ(energies(0.6, 0), energies(-0.6, 0));
}
