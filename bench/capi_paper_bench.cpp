// Paper sheets through the C API (docs/PERFORMANCE.md, "Paper through the C API"): N sheets
// each posting a paper animation's frames, forwards then backwards so the motion never jumps,
// for S seconds of audio; the control thread's chladni_paper_post_frame time per frame (the
// analysis and synthesis of one sheet's frame) and the audio thread's render time per block,
// against the same runtime rendering with no sheet.
// Usage: chladni_capi_paper_bench [--animation meshes/paper/crumple.json] [--mode modal|database]
//                                 [--db DIR] [--sheets 4] [--seconds 20] [--block 256]
#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "chladni/chladni.h"
#include "chladni/core/paper_animation.hpp"

using chladni::bench::clock_type;

namespace {

struct Args {
  std::string animation = "meshes/paper/crumple.json", mode = "modal", db;
  uint32_t sheets = 4, block = 256;
  double seconds = 20;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; i += 2) {
    if (i + 1 >= argc) throw std::invalid_argument(std::string(argv[i]) + " needs a value");
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--animation")
      a.animation = v;
    else if (k == "--mode")
      a.mode = v;
    else if (k == "--db")
      a.db = v;
    else if (k == "--sheets")
      a.sheets = static_cast<uint32_t>(std::stoul(v));
    else if (k == "--seconds")
      a.seconds = std::stod(v);
    else if (k == "--block")
      a.block = static_cast<uint32_t>(std::stoul(v));
    else
      throw std::invalid_argument("unknown option " + k);
  }
  return a;
}

struct Stats {
  std::vector<double> ms;
  void add(clock_type::time_point t0) { ms.push_back(1e3 * chladni::bench::seconds_since(t0)); }
  void print(const char* what) {
    std::sort(ms.begin(), ms.end());
    double mean = 0;
    for (double x : ms) mean += x / double(ms.size());
    std::printf("%-34s mean %8.4f ms  p99 %8.4f ms  max %8.4f ms  (%zu)\n", what, mean,
                ms[ms.size() * 99 / 100], ms.back(), ms.size());
  }
};

void check(chladni_status s, const char* what) {
  if (s != CHLADNI_OK) throw std::runtime_error(std::string(what) + ": " + chladni_last_error());
}

// Renders `seconds` block by block with `sheets` sheets posting a frame each frame period.
Stats run(const Args& a, const chladni::PaperAnimation& anim, uint32_t sheets, Stats* posts) {
  chladni_config c;
  chladni_config_default(&c);
  c.sample_rate = 44100;
  c.block_size = a.block;
  c.threads = 1;
  c.max_papers = std::max(sheets, 1u);
  chladni_runtime* rt = nullptr;
  check(chladni_runtime_create(&c, &rt), "chladni_runtime_create");
  chladni_paper_desc d{};
  d.animation = a.animation.c_str();
  d.mode = a.mode.c_str();
  d.database = a.db.empty() ? nullptr : a.db.c_str();
  std::vector<chladni_paper> ids(sheets);
  for (uint32_t s = 0; s < sheets; ++s) {
    d.seed = s + 1;
    check(chladni_paper_add(rt, &d, &ids[s]), "chladni_paper_add");
  }
  const double period = c.sample_rate / anim.frame_rate;
  const uint32_t n = anim.frame_count(), frames = uint32_t(a.seconds * anim.frame_rate);
  std::vector<float> out(2 * a.block);
  Stats render;
  uint64_t rendered = 0;
  for (uint32_t f = 0; f < frames; ++f) {
    const uint32_t k = f % (2 * n - 2), at = k < n ? k : 2 * n - 2 - k;  // forwards, backwards
    for (uint32_t s = 0; s < sheets; ++s) {
      const auto t0 = clock_type::now();
      check(chladni_paper_post_frame(rt, ids[s], anim.frame(at).data(), anim.vertex_count, nullptr,
                                     0),
            "chladni_paper_post_frame");
      posts->add(t0);
    }
    for (const uint64_t end = uint64_t((f + 1) * period); rendered < end;) {
      const uint32_t m = uint32_t(std::min<uint64_t>(a.block, end - rendered));
      const auto t0 = clock_type::now();
      check(chladni_runtime_render(rt, out.data(), m), "chladni_runtime_render");
      if (m == a.block) render.add(t0);
      rendered += m;
    }
  }
  chladni_runtime_destroy(rt);
  return render;
}

}  // namespace

int main(int argc, char** argv) try {
  const Args a = chladni::bench::parse_or_exit(parse, argc, argv);
  const chladni::PaperAnimation anim = chladni::load_paper_animation(a.animation);
  std::printf(
      "%s: %zu triangles, %u frames at %g frames/s; %u sheets, %s mode, %g s, blocks of "
      "%u at 44.1 kHz (%.3f ms)\n",
      a.animation.c_str(), anim.triangles.size(), anim.frame_count(), anim.frame_rate, a.sheets,
      a.mode.c_str(), a.seconds, a.block, 1e3 * a.block / 44100.0);
  Stats posts, none;
  Stats idle = run(a, anim, 0, &none);
  Stats busy = run(a, anim, a.sheets, &posts);
  posts.print("control: chladni_paper_post_frame");
  idle.print("audio: render, no sheet");
  busy.print("audio: render, the sheets mixed in");
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "%s\n", e.what());
  return 1;
}
