// Paper sheets: the control thread analyses and renders each posted frame (PaperRenderer, live)
// and writes its final samples to the sheet's ring; the audio thread mixes them in at their
// output sample, one frame period after the first frame was posted.
#include <algorithm>
#include <cmath>
#include <optional>

#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"
#include "handles.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace chladni::capi {

struct PaperSheet {
  PaperAnimation anim;  // the sheet; no frames
  std::optional<PaperSoundDb> db;
  std::unique_ptr<Filterbank> fb;  // modal voices: a CPU filterbank of the sheet's own
  std::unique_ptr<PaperRenderer> renderer;
  std::unique_ptr<PaperStream> stream;
  std::vector<float> scratch;
  std::vector<uint32_t> held;
  uint64_t id = 0;
  uint32_t frame_samples = 0;  // output samples per animation frame, rounded up
  std::size_t reserve = 0;     // ring frames kept for the tail after the last frame
  float gain = 1;
  bool follow = false;  // hears the runtime's listener
  uint64_t heard = 0;   // the listener's sequence count last taken
  bool ended = false;
};

void PaperSheetDeleter::operator()(PaperSheet* p) const {
  delete p;
}

}  // namespace chladni::capi

namespace {

using capi::PaperSheet;
using capi::PaperStream;

Vec3 unit(const double* v) {
  const Vec3 x{v[0], v[1], v[2]};
  return scale(x, 1 / norm(x));
}

// Planes from the C description; normals need not be unit.
std::vector<PaperObstacle> planes_of(const chladni_paper_desc& d) {
  if (d.plane_count && !d.planes) throw InputError("planes must not be null when plane_count > 0");
  if (d.plane_count > 1024) throw InputError("plane_count must be at most 1024");
  std::vector<PaperObstacle> out;
  for (uint32_t i = 0; i < d.plane_count; ++i) {
    const chladni_paper_plane& p = d.planes[i];
    const std::string at = "planes[" + std::to_string(i) + "]";
    capi::need_vector(p.point, (at + ".point").c_str(), false);
    capi::need_vector(p.normal, (at + ".normal").c_str());
    PaperObstacle o;
    o.name = at;
    o.point = {p.point[0], p.point[1], p.point[2]};
    o.normal = unit(p.normal);
    if (p.surface) o.friction = p.surface;
    out.push_back(std::move(o));
  }
  return out;
}

// The sheet: from the animation file, or inline.
PaperAnimation sheet_of(const chladni_paper_desc& d) {
  PaperAnimation a;
  if (d.animation) {
    a = load_paper_animation(d.animation);
    a.positions = {};  // its frames are not played
  } else {
    if (d.vertex_count > (1u << 22) || d.triangle_count > (1u << 23))
      throw InputError("a sheet of at most 2^22 vertices and 2^23 triangles");
    if (d.triangle_count && !d.triangles)
      throw InputError("triangles must not be null when triangle_count > 0");
    a.vertex_count = d.vertex_count;
    for (uint32_t t = 0; t < d.triangle_count; ++t)
      a.triangles.push_back({d.triangles[3 * t], d.triangles[3 * t + 1], d.triangles[3 * t + 2]});
    a.obstacles = planes_of(d);
    a.frame_rate = d.frame_rate == 0 ? 60 : d.frame_rate;
    a.contact_distance = d.contact_distance == 0 ? 0.002 : d.contact_distance;
  }
  if (std::any_of(d.listener, d.listener + 9, [](double x) { return x != 0; })) {
    capi::need_vector(d.listener, "listener position", false);
    capi::need_vector(d.listener + 3, "listener forward");
    capi::need_vector(d.listener + 6, "listener up");
    a.listener.position = {d.listener[0], d.listener[1], d.listener[2]};
    a.listener.forward = unit(d.listener + 3);
    a.listener.up = unit(d.listener + 6);
    if (norm(cross(a.listener.forward, a.listener.up)) < 1e-6)
      throw InputError("listener forward and up must not be parallel");
  }
  validate_sheet(a, d.animation ? d.animation : "the inline sheet");
  return a;
}

std::unique_ptr<PaperSheet> make_sheet(const chladni_runtime& rt, const chladni_paper_desc& d) {
  if (!(d.gain >= 0 && d.gain <= capi::kMaxGain)) throw InputError("gain must be in [0, 1e6]");
  auto s = std::make_unique<PaperSheet>();
  s->anim = sheet_of(d);
  PaperSynthOptions o;
  o.mode = d.mode       ? parse_paper_mode(d.mode)
           : d.database ? PaperSynthMode::Database
                        : PaperSynthMode::Modal;
  o.sample_rate = rt.config.sample_rate;
  o.seed = d.seed ? d.seed : 1;
  o.live = true;
  if (o.mode != PaperSynthMode::Modal) {
    if (!d.database) throw InputError("database mode needs desc.database, a paper sound database");
    s->db = load_paper_database(d.database);
  }
  if (o.mode != PaperSynthMode::Database) {
    FilterbankRequest r;
    r.backend = gpu::DeviceChoice::Cpu;
    r.channels = 2;
    r.capacity = 1u << 18;
    r.threads = 1;  // the control thread's own work
    r.max_frames = 1024;
    s->fb = runtime::make_filterbank(r);
  }
  s->renderer = std::make_unique<PaperRenderer>(s->anim, s->db ? &*s->db : nullptr, s->fb.get(), o);
  s->frame_samples = static_cast<uint32_t>(std::ceil(o.sample_rate / s->anim.frame_rate));
  // Half a second ahead of the audio thread (or more: the ring's size is a power of two), and
  // room kept for the tail after the last frame.
  s->reserve = static_cast<std::size_t>(std::ceil(o.tail_seconds * o.sample_rate));
  s->stream =
      std::make_unique<PaperStream>(2 * (static_cast<std::size_t>(std::ceil(0.5 * o.sample_rate)) +
                                         s->reserve + 2 * std::size_t{s->frame_samples}));
  s->gain = d.gain == 0 ? 1.0f : static_cast<float>(d.gain);
  if (d.follow_listener != 0 && d.follow_listener != 1)
    throw InputError("follow_listener must be 0 or 1");
  s->follow = d.follow_listener == 1;
  return s;
}

PaperSheet& live_sheet(chladni_runtime* rt, chladni_paper paper) {
  const uint32_t k = capi::place_of(paper.id);
  if (paper.id == 0 || k >= rt->papers.size() || !rt->papers[k] || rt->papers[k]->id != paper.id ||
      rt->papers[k]->ended)
    throw InputError("no paper sheet " + std::to_string(paper.id) + " (never added, or removed)");
  return *rt->papers[k];
}

// A follower takes the listener chladni_listener_set last posted, when it has moved since; a read
// torn by a concurrent set is left for the next frame.
void follow_listener(const chladni_runtime& rt, PaperSheet& s) {
  const uint64_t seq = rt.listener_seq.load(std::memory_order_acquire);
  if (!s.follow || seq == s.heard || seq % 2) return;
  double v[9];
  for (int i = 0; i < 9; ++i) v[i] = rt.listener[i].load(std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_acquire);
  if (rt.listener_seq.load(std::memory_order_relaxed) != seq) return;
  PaperListener l = s.anim.listener;  // its ear distance
  l.position = {v[0], v[1], v[2]};
  l.forward = {v[3], v[4], v[5]};
  l.up = {v[6], v[7], v[8]};
  s.renderer->set_listener(l);
  s.heard = seq;
}

// Moves up to `frames` of the renderer's final audio, scaled by the sheet's gain, to its ring.
void hand_over(PaperSheet& s, std::size_t frames) {
  s.scratch.resize(2 * frames);
  s.renderer->read(s.scratch.data(), frames);
  for (float& x : s.scratch) x *= s.gain;
  if (!s.stream->ring.write(s.scratch.data(), s.scratch.size()))
    throw InternalError("a paper sheet's ring overflowed");
}

}  // namespace

void chladni_runtime::reclaim_paper(uint32_t place) {
  papers[place].reset();
  free_paper_places.push_back(place);
}

// Audio thread: each sheet's samples due in [start, start + frames), mixed into `out`; those
// whose time has passed are dropped. A sheet that has ended and played everything is retired.
void chladni_runtime::mix_papers(float* out, uint64_t start, uint32_t frames) {
  const int ch = config.channels;
  for (uint32_t k = 0; k < installed_papers.size(); ++k) {
    PaperStream* p = installed_papers[k];
    if (!p) continue;
    const bool ended = p->ended.load(std::memory_order_acquire);  // before the ring's size
    const std::size_t have = p->ring.size() / 2;
    if (have > 0) {
      const uint64_t at = p->start.load(std::memory_order_relaxed) + p->consumed;
      const std::size_t late = at < start ? std::min<uint64_t>(have, start - at) : 0;
      std::size_t play = 0;
      if (at + late >= start && at + late < start + frames) {
        play = std::min<uint64_t>(have - late, start + frames - (at + late));
        float* o = out + (at + late - start) * ch;
        for (std::size_t i = 0; i < play; ++i) {
          const float l = p->ring.at(2 * (late + i)), r = p->ring.at(2 * (late + i) + 1);
          if (ch == 2) {
            o[2 * i] += l;
            o[2 * i + 1] += r;
          } else {
            o[i] += 0.5f * (l + r);
          }
        }
      }
      p->ring.consume(2 * (late + play));
      p->consumed += late + play;
    }
    if (ended && p->ring.size() == 0) {
      installed_papers[k] = nullptr;
      give_back({capi::Return::Kind::PaperRetired, k});
    }
  }
}

extern "C" {

chladni_status chladni_paper_add(chladni_runtime* rt, const chladni_paper_desc* desc,
                                 chladni_paper* paper) {
  return capi::guarded("chladni_paper_add", [&] {
    if (!rt || !desc || !paper) throw InputError("runtime, desc and paper must not be null");
    *paper = chladni_paper{0};
    rt->reclaim();
    if (rt->free_paper_places.empty()) {
      capi::fail(CHLADNI_QUEUE_FULL, "chladni_paper_add: max_papers (" +
                                         std::to_string(rt->config.max_papers) +
                                         ") sheets are alive or ringing out");
      return CHLADNI_QUEUE_FULL;
    }
    std::unique_ptr<PaperSheet> s = make_sheet(*rt, *desc);
    const uint32_t k = rt->free_paper_places.back();
    const uint32_t g = capi::next_generation(rt->paper_generations[k]);
    capi::Change c{capi::Change::Kind::AddPaper, k, capi::handle_id(k, g)};
    c.paper = s->stream.get();
    if (!rt->changes.push(c)) throw InternalError("the change queue is full");
    rt->free_paper_places.pop_back();
    rt->paper_generations[k] = g;
    s->id = c.id;
    rt->papers[k].reset(s.release());
    *paper = chladni_paper{c.id};
    return CHLADNI_OK;
  });
}

chladni_status chladni_paper_post_frame(chladni_runtime* rt, chladni_paper paper, const float* xyz,
                                        uint32_t vertex_count, const uint32_t* held,
                                        uint32_t held_count) {
  return capi::guarded("chladni_paper_post_frame", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->reclaim();
    PaperSheet& s = live_sheet(rt, paper);
    if (!xyz) throw InputError("xyz must not be null");
    if (vertex_count != s.anim.vertex_count)
      throw InputError("vertex_count " + std::to_string(vertex_count) + " is not the sheet's " +
                       std::to_string(s.anim.vertex_count));
    for (std::size_t i = 0; i < std::size_t(vertex_count) * 3; ++i)
      if (!(std::abs(xyz[i]) <= capi::kMaxCoordinate))
        throw InputError("xyz[" + std::to_string(i) + "] (vertex " + std::to_string(i / 3) +
                         ") must be finite and within 1e9 m");
    if (held_count && !held) throw InputError("held must not be null when held_count > 0");
    if (held) s.held.assign(held, held + held_count);
    // Room for what this frame makes final, checked before the frame is taken.
    const std::size_t frames = s.renderer->ready() + s.frame_samples + 1;
    if (2 * (frames + s.reserve) > s.stream->ring.room()) {
      capi::fail(CHLADNI_QUEUE_FULL,
                 "chladni_paper_post_frame: the sheet's audio is half a second or more ahead of "
                 "the audio thread; post this frame again after a render");
      return CHLADNI_QUEUE_FULL;
    }
    follow_listener(*rt, s);
    s.renderer->step({xyz, std::size_t(vertex_count) * 3}, held ? &s.held : nullptr);
    if (s.stream->start.load(std::memory_order_relaxed) == PaperStream::kNotStarted)
      s.stream->start.store(
          rt->clock.load(std::memory_order_acquire) + rt->fb->latency() + s.frame_samples,
          std::memory_order_relaxed);
    hand_over(s, s.renderer->ready());
    return CHLADNI_OK;
  });
}

chladni_status chladni_paper_remove(chladni_runtime* rt, chladni_paper paper) {
  return capi::guarded("chladni_paper_remove", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->reclaim();
    PaperSheet& s = live_sheet(rt, paper);
    s.ended = true;  // its handle is refused from now on, whatever follows
    s.renderer->end();
    // The tail: posts kept room for it.
    if (s.stream->start.load(std::memory_order_relaxed) != PaperStream::kNotStarted)
      hand_over(s, std::min(s.renderer->ready(), s.stream->ring.room() / 2));
    s.stream->ended.store(true, std::memory_order_release);
    return CHLADNI_OK;
  });
}

}  // extern "C"
