// chladni_runtime: creation, the audio thread's side of the queues, and rendering.
#include <algorithm>
#include <cmath>

#include "chladni/runtime/filterbank/make_filterbank.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "handles.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::capi::Command;
using chladni::capi::Kind;

namespace {

thread_local std::string g_error;

// The application's device, its queue under its lock when it gives one.
std::shared_ptr<gpu::Context> shared_device(const chladni_vulkan_device& v) {
  gpu::ExternalDevice d;
  d.instance = static_cast<VkInstance>(v.instance);
  d.physical = static_cast<VkPhysicalDevice>(v.physical_device);
  d.device = static_cast<VkDevice>(v.device);
  d.queue_family = v.queue_family;
  d.queue_index = v.queue_index;
  d.get_instance_proc_addr = reinterpret_cast<PFN_vkGetInstanceProcAddr>(v.get_instance_proc_addr);
  // Context refuses one without the other.
  if (v.lock_queue) d.lock_queue = [f = v.lock_queue, u = v.user] { f(u); };
  if (v.unlock_queue) d.unlock_queue = [f = v.unlock_queue, u = v.user] { f(u); };
  try {
    return std::make_shared<gpu::Context>(d);
  } catch (const gpu::Error& e) {
    throw InputError(std::string("vulkan: ") + e.what());
  }
}

// GPU asked for explicitly fails without a device; AUTO takes a hardware GPU, else the CPU; a
// shared device is taken by both.
std::unique_ptr<Filterbank> make_filterbank(const chladni_config& c) {
  FilterbankRequest r;
  r.backend = c.backend == CHLADNI_BACKEND_CPU   ? gpu::DeviceChoice::Cpu
              : c.backend == CHLADNI_BACKEND_GPU ? gpu::DeviceChoice::Gpu
                                                 : gpu::DeviceChoice::Auto;
  r.gpu_falls_back = false;
  r.capacity = c.mode_budget + c.shaker_slots + c.contact_slots;
  r.channels = c.channels;
  r.threads = c.threads;
  r.max_frames = c.block_size;
  r.max_streams = (c.shaker_slots ? c.max_shakers : 0) + (c.contact_slots ? c.max_contacts : 0);
  r.gain_ramp = c.gain_ramp;
  r.pipelined = c.gpu_pipeline != 0;
  if (c.vulkan && c.backend != CHLADNI_BACKEND_CPU) r.device = shared_device(*c.vulkan);
  return runtime::make_filterbank(r);
}

// Places whose additions and removals may be in flight between the control and audio threads.
std::size_t places_in_flight(const chladni_config& c) {
  return std::size_t{c.max_objects} + (c.shaker_slots ? c.max_shakers : 0) + c.max_papers +
         (c.contact_slots ? c.max_contacts : 0);
}

void check_config(const chladni_config& c) {
  if (!(c.sample_rate >= 8000 && c.sample_rate <= 384000))
    throw InputError("sample_rate must be in [8000, 384000]");
  if (c.channels != 1 && c.channels != 2) throw InputError("channels must be 1 or 2");
  if (c.block_size < 1 || c.block_size > 16384)
    throw InputError("block_size must be in [1, 16384]");
  if (c.mode_budget < 1 || c.mode_budget > (1u << 24))
    throw InputError("mode_budget must be in [1, 2^24]");
  if (c.max_objects < 1 || c.max_objects > (1u << 20))
    throw InputError("max_objects must be in [1, 2^20]");
  if (c.queue_capacity < 1 || c.queue_capacity > (1u << 24))
    throw InputError("queue_capacity must be in [1, 2^24]");
  if (c.gain_ramp > 65536) throw InputError("gain_ramp must be at most 65536");
  if (c.threads < 0 || c.threads > 1024) throw InputError("threads must be in [0, 1024]");
  if (c.gpu_pipeline != 0 && c.gpu_pipeline != 1) throw InputError("gpu_pipeline must be 0 or 1");
  if (c.shaker_slots > (1u << 20)) throw InputError("shaker_slots must be at most 2^20");
  if (c.shaker_slots && (c.max_shakers < 1 || c.max_shakers > 4096))
    throw InputError("max_shakers must be in [1, 4096] when shaker_slots > 0");
  if (!(c.horizon > 0 && c.horizon <= 1e6)) throw InputError("horizon must be in (0, 1e6] s");
  if (c.max_papers > 256) throw InputError("max_papers must be at most 256");
  if (c.contact_slots > (1u << 22)) throw InputError("contact_slots must be at most 2^22");
  if (c.contact_slots && (c.max_contacts < 1 || c.max_contacts > 4096))
    throw InputError("max_contacts must be in [1, 4096] when contact_slots > 0");
  if (c.backend != CHLADNI_BACKEND_CPU && c.backend != CHLADNI_BACKEND_GPU &&
      c.backend != CHLADNI_BACKEND_AUTO)
    throw InputError("backend must be CPU, GPU or AUTO");
}

}  // namespace

namespace chladni::capi {

chladni_status fail(chladni_status status, std::string message) {
  g_error = std::move(message);
  return status;
}

}  // namespace chladni::capi

chladni_runtime::chladni_runtime(const chladni_config& c)
    : config(c),
      fb(make_filterbank(c)),
      name(fb->name()),
      places(std::make_unique<capi::Place[]>(c.max_objects)),
      shakers(std::make_unique<capi::ShakerPlace[]>(c.shaker_slots ? c.max_shakers : 0)),
      contacts(std::make_unique<capi::ContactPlace[]>(c.contact_slots ? c.max_contacts : 0)),
      queue(c.queue_capacity),
      // Each place has at most an addition and a removal in flight, and as many returns.
      changes(2 * places_in_flight(c)),
      returns(2 * places_in_flight(c) + 2) {
  PlayerOptions po;
  po.sample_rate = c.sample_rate;
  po.synth.sample_rate = c.sample_rate;
  po.synth.max_modes = c.mode_budget;
  po.synth.max_voices = c.max_objects;
  po.shaker_slots = c.shaker_slots;
  po.max_shakers = c.shaker_slots ? c.max_shakers : 0;
  po.max_objects = c.max_objects;
  po.contact_slots = c.contact_slots;
  po.max_contacts = max_contacts();
  player = std::make_unique<ScenePlayer>(*fb, po);
  player->finish_objects();  // the shared tables, empty: live objects carry their own
  pending.reserve(queue.capacity());
  installed_ids.assign(c.max_objects, 0);
  installed_shaker_ids.assign(max_shakers(), 0);
  free_places.reserve(c.max_objects);
  for (uint32_t k = c.max_objects; k-- > 0;) free_places.push_back(k);
  free_shaker_places.reserve(max_shakers());
  for (uint32_t k = max_shakers(); k-- > 0;) free_shaker_places.push_back(k);
  installed_contact_ids.assign(max_contacts(), 0);
  free_contact_places.reserve(max_contacts());
  for (uint32_t k = max_contacts(); k-- > 0;) free_contact_places.push_back(k);
  papers.resize(c.max_papers);
  paper_generations.assign(c.max_papers, 0);
  installed_papers.assign(c.max_papers, nullptr);
  free_paper_places.reserve(c.max_papers);
  for (uint32_t k = c.max_papers; k-- > 0;) free_paper_places.push_back(k);
}

chladni_runtime::~chladni_runtime() {
  // Nothing renders now: whatever is still in flight is freed here.
  while (const capi::Change* c = changes.front()) {
    delete c->prepared;
    delete c->shaker;
    delete c->contact;
    changes.pop();
  }
  while (const capi::Return* r = returns.front()) {
    delete r->prepared;
    delete r->shaker;
    delete r->contact;
    returns.pop();
  }
  player.reset();  // before the banks its objects point into
}

// Places the control thread's new objects and shakers and removes the ones it removed.
void chladni_runtime::take_changes() {
  using capi::Change;
  using capi::Return;
  while (const Change* c = changes.front()) {
    const Change ch = *c;
    changes.pop();
    switch (ch.kind) {
      case Change::Kind::Spawn:
        if (player->install(ch.place, *ch.prepared)) {
          installed_ids[ch.place] = ch.id;
          give_back({Return::Kind::Garbage, ch.place, ch.prepared});
        } else {
          give_back({Return::Kind::Refused, ch.place, ch.prepared});
        }
        break;
      case Change::Kind::Remove:
        if (installed_ids[ch.place] == ch.id) {
          player->remove(ch.place);
          installed_ids[ch.place] = 0;
        }
        break;
      case Change::Kind::AddShaker:
        if (installed(ch.object) && player->install_shaker(static_cast<int>(ch.place),
                                                           capi::place_of(ch.object), *ch.shaker)) {
          installed_shaker_ids[ch.place] = ch.id;
          give_back({Return::Kind::ShakerGarbage, ch.place, nullptr, ch.shaker});
        } else {  // its object went first: the place is free again at once
          give_back({Return::Kind::ShakerRetired, ch.place, nullptr, ch.shaker});
        }
        break;
      case Change::Kind::RemoveShaker:
        if (installed_shaker_ids[ch.place] == ch.id) player->remove_shaker(int(ch.place));
        break;
      case Change::Kind::AddPaper:
        installed_papers[ch.place] = ch.paper;
        break;
      case Change::Kind::AddContact: {
        const bool bodies = installed(ch.object) && (ch.other == 0 || installed(ch.other));
        const long other = ch.other ? long(capi::place_of(ch.other)) : -1;
        if (bodies &&
            player->install_contact(int(ch.place), capi::place_of(ch.object), other, *ch.contact)) {
          installed_contact_ids[ch.place] = ch.id;
          give_back({Return::Kind::ContactGarbage, ch.place, nullptr, nullptr, ch.contact});
        } else {  // an object went first: the place is free again at once
          give_back({Return::Kind::ContactRetired, ch.place, nullptr, nullptr, ch.contact});
        }
        break;
      }
      case Change::Kind::RemoveContact:
        if (installed_contact_ids[ch.place] == ch.id) {
          player->remove_contact(int(ch.place));
          installed_contact_ids[ch.place] = 0;  // posts still queued for it are dropped
        }
        break;
    }
  }
}

// Moves the queued commands into `pending`, keeping it sorted by time (stable).
void chladni_runtime::drain() {
  while (const Command* c = queue.front()) {
    if (pending.size() == pending.capacity()) break;  // the rest waits for the next render
    auto at = std::upper_bound(pending.begin(), pending.end(), c->time,
                               [](double t, const Command& x) { return t < x.time; });
    pending.insert(at, *c);
    queue.pop();
  }
}

// A command's first sample (negative times are now).
uint64_t chladni_runtime::sample_of(const Command& c) const {
  return first_sample(std::max(c.time, 0.0), config.sample_rate);
}

// Frames up to the next pending pose change after `now` (at most `frames`): a block ends there,
// so that moves take effect on their sample as in the offline renderer.
uint32_t chladni_runtime::until_next_pose(uint32_t frames) const {
  for (const Command& c : pending) {
    if (c.kind == Kind::Impact || c.kind == Kind::Shake || c.kind == Kind::Contact) continue;
    const uint64_t at = sample_of(c);
    if (at > now) return static_cast<uint32_t>(std::min<uint64_t>(frames, at - now));
  }
  return frames;
}

// Applies the poses due by sample t, then the shakes and impacts due before t + frames.
void chladni_runtime::apply_due(uint64_t t, uint32_t frames) {
  auto keep_if = [&](auto&& applied) {  // compacts `pending`; shrinking keeps the capacity
    std::size_t kept = 0;
    for (std::size_t i = 0; i < pending.size(); ++i)
      if (!applied(pending[i])) pending[kept++] = pending[i];
    pending.resize(kept);
  };
  apply_contacts(t);
  keep_if([&](const Command& c) {
    if (c.kind == Kind::Impact || c.kind == Kind::Shake || sample_of(c) > t) return false;
    if (c.kind == Kind::Move) {
      if (installed(c.object))
        player->move(capi::place_of(c.object), {c.a[0], c.a[1], c.a[2]},
                     {c.q[0], c.q[1], c.q[2], c.q[3]});
    } else {
      player->set_listener(
          {{c.a[0], c.a[1], c.a[2]}, {c.b[0], c.b[1], c.b[2]}, {c.c[0], c.c[1], c.c[2]}});
    }
    return true;
  });
  const Synth& synth = player->synth();
  keep_if([&](const Command& c) {
    if (c.kind != Kind::Shake) return false;
    const uint64_t at = sample_of(c);
    if (at >= t + frames) return false;
    const uint32_t s = capi::place_of(c.shaker);
    if (s >= installed_shaker_ids.size() || installed_shaker_ids[s] != c.shaker) return true;
    // false: the block's shake list is full; it waits for the next block.
    return player->shake(static_cast<int>(s), static_cast<float>(c.impulse),
                         at <= t ? 0u : static_cast<uint32_t>(at - t));
  });
  keep_if([&](const Command& c) {
    if (c.kind != Kind::Impact) return false;
    const uint64_t at = sample_of(c);
    if (at >= t + frames) return false;
    if (!installed(c.object)) return true;
    const uint32_t k = capi::place_of(c.object);
    // The filterbank takes so many kicks per call: the rest wait for the next block.
    if (synth.pending_excitations() + player->mode_count(k) > synth.excitation_capacity())
      return false;
    ImpactEvent ev;
    ev.impulse = c.impulse;
    ev.direction = {c.a[0], c.a[1], c.a[2]};
    if (c.vertex >= 0)
      ev.vertex = static_cast<std::size_t>(c.vertex);
    else
      ev.point = Vec3{c.b[0], c.b[1], c.b[2]};
    ev.contact_time = c.contact;
    // A late impact (its first sample has passed) is struck at once. One the player cannot
    // take (a kick past what a float holds, which the calls' bounds should prevent) is dropped,
    // so that it cannot fail every render after it.
    try {
      player->impact(k, ev, at <= t ? 0.0 : c.time * config.sample_rate - static_cast<double>(t));
    } catch (const InputError&) {
      ++dropped_commands;
    }
    return true;
  });
}

extern "C" {

void chladni_config_default(chladni_config* c) {
  if (c)
    *c = chladni_config{CHLADNI_BACKEND_CPU,
                        48000,
                        256,
                        2,
                        65536,
                        256,
                        4096,
                        256,
                        0,
                        4096,
                        64,
                        1,
                        60.0,
                        nullptr,
                        4,
                        0,
                        64};
}

const char* chladni_last_error(void) {
  return g_error.c_str();
}

chladni_status chladni_runtime_create(const chladni_config* config, chladni_runtime** out) {
  return capi::guarded("chladni_runtime_create", [&] {
    if (!config || !out) throw InputError("config and out must not be null");
    *out = nullptr;
    check_config(*config);
    *out = new chladni_runtime(*config);
    return CHLADNI_OK;
  });
}

void chladni_runtime_destroy(chladni_runtime* rt) {
  delete rt;
}

const char* chladni_runtime_backend(const chladni_runtime* rt) {
  return rt ? rt->name.c_str() : "";
}

chladni_status chladni_runtime_render(chladni_runtime* rt, float* out, uint32_t frames) {
  if (!rt || (!out && frames))
    return capi::fail(CHLADNI_INPUT_ERROR, "chladni_runtime_render: null");
  return capi::guarded("chladni_runtime_render", [&] {
    // Commands first: a spawn that a drained command's poster saw is then in `changes` too.
    rt->drain();
    rt->take_changes();
    const int ch = rt->config.channels;
    float* const first = out;
    const uint64_t start = rt->now;
    const uint32_t all = frames;
    while (frames > 0) {
      const uint32_t n = rt->until_next_pose(std::min(frames, rt->fb->max_frames()));
      rt->apply_due(rt->now, n);
      rt->player->render(n, out);
      out += static_cast<std::size_t>(n) * ch;
      frames -= n;
      rt->now += n;
    }
    for (uint32_t k : rt->player->retired()) rt->give_back({capi::Return::Kind::Retired, k});
    for (uint32_t k : rt->player->retired_shakers()) {
      rt->installed_shaker_ids[k] = 0;
      rt->give_back({capi::Return::Kind::ShakerRetired, k});
    }
    for (uint32_t k : rt->player->retired_contacts())
      rt->give_back({capi::Return::Kind::ContactRetired, k});
    rt->player->clear_retired();
    rt->mix_papers(first, start, all);
    rt->clock.store(rt->now, std::memory_order_release);
    return CHLADNI_OK;
  });
}

double chladni_runtime_latency(const chladni_runtime* rt) {
  return rt ? rt->fb->latency() / rt->config.sample_rate : 0.0;
}

double chladni_runtime_time(const chladni_runtime* rt) {
  return rt ? static_cast<double>(rt->clock.load(std::memory_order_acquire)) /
                  rt->config.sample_rate
            : 0.0;
}

}  // extern "C"
