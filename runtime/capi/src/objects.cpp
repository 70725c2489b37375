// Banks, objects and the command queue's producer side.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/core/soundbank.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "chladni/runtime/scene/scene_shakers.hpp"
#include "handles.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::capi::Command;
using chladni::capi::Kind;

namespace chladni::capi {

void need_vector(const double* v, const char* what, bool nonzero) {
  if (!v) throw InputError(std::string(what) + " must not be null");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i])) throw InputError(std::string(what) + " must be finite");
  if (nonzero && v[0] * v[0] + v[1] * v[1] + v[2] * v[2] == 0)
    throw InputError(std::string(what) + " must not be zero");
}

Quat unit_quaternion(const double* q) {
  if (!q) throw InputError("orientation must not be null");
  for (int i = 0; i < 4; ++i)
    if (!std::isfinite(q[i])) throw InputError("orientation must be finite (w, x, y, z)");
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 0)) throw InputError("orientation must not be zero");
  return {q[0] / n, q[1] / n, q[2] / n, q[3] / n};
}

}  // namespace chladni::capi

namespace {

chladni_bank* keep(chladni_runtime* rt, std::unique_ptr<chladni_bank> bank) {
  rt->banks.push_back(std::move(bank));
  return rt->banks.back().get();
}

// Volume enclosed by the bank's surface (divergence theorem over its triangles) times density.
double solid_mass(const Soundbank& bank) {
  double six_v = 0;
  for (const auto& t : bank.triangles) {
    const auto& a = bank.vertices[t[0]];
    const auto& b = bank.vertices[t[1]];
    const auto& c = bank.vertices[t[2]];
    six_v += double(a[0]) * (double(b[1]) * c[2] - double(b[2]) * c[1]) -
             double(a[1]) * (double(b[0]) * c[2] - double(b[2]) * c[0]) +
             double(a[2]) * (double(b[0]) * c[1] - double(b[1]) * c[0]);
  }
  return std::abs(six_v) / 6 * bank.material.density;
}

chladni_bank* bank_of(chladni_runtime* rt, Soundbank&& bank, const std::string& origin) {
  auto b = std::make_unique<chladni_bank>();
  b->mass = solid_mass(bank);
  b->model =
      std::make_unique<ModalModel>(playable_model(bank, origin, rt->config.sample_rate, origin));
  b->modes = object_modes(*b->model);
  return keep(rt, std::move(b));
}

// Validates a command's object and time (producer side).
void check_target(const chladni_runtime* rt, uint32_t object, double time) {
  if (object >= rt->player->object_count() || !rt->player->active(object))
    throw InputError("no object " + std::to_string(object));
  if (!std::isfinite(time)) throw InputError("time must be finite");
}

chladni_status post(chladni_runtime* rt, const Command& c) {
  return rt->queue.push(c) ? CHLADNI_OK
                           : capi::fail(CHLADNI_QUEUE_FULL, "the command queue is full");
}

}  // namespace

extern "C" {

chladni_status chladni_bank_load_file(chladni_runtime* rt, const char* path, chladni_bank** out) {
  return capi::guarded("chladni_bank_load_file", [&] {
    if (!rt || !path || !out) throw InputError("runtime, path and out must not be null");
    *out = bank_of(rt, read_soundbank(path), path);
    return CHLADNI_OK;
  });
}

chladni_status chladni_bank_load_memory(chladni_runtime* rt, const void* bytes, size_t size,
                                        chladni_bank** out) {
  return capi::guarded("chladni_bank_load_memory", [&] {
    if (!rt || (!bytes && size) || !out)
      throw InputError("runtime, bytes and out must not be null");
    const auto* p = static_cast<const uint8_t*>(bytes);
    *out = bank_of(rt, parse_soundbank(std::vector<uint8_t>(p, p + size), "memory"), "memory");
    return CHLADNI_OK;
  });
}

chladni_status chladni_bank_from_modes(chladni_runtime* rt, const double* frequency_hz,
                                       const double* decay, const double* amplitude, size_t count,
                                       chladni_bank** out) {
  return capi::guarded("chladni_bank_from_modes", [&] {
    if (!rt || !out || (count && (!frequency_hz || !decay || !amplitude)))
      throw InputError("runtime, arrays and out must not be null");
    if (count == 0) throw InputError("a bank needs at least one mode");
    auto b = std::make_unique<chladni_bank>();
    for (size_t i = 0; i < count; ++i) {
      const std::string at = "mode " + std::to_string(i);
      if (!(frequency_hz[i] > 0 && frequency_hz[i] < rt->config.sample_rate / 2))
        throw InputError(at + ": frequency must be in (0, Nyquist)");
      if (!(decay[i] >= 0 && std::isfinite(decay[i])))
        throw InputError(at + ": decay must be finite and >= 0");
      if (!std::isfinite(amplitude[i])) throw InputError(at + ": amplitude must be finite");
      b->inline_modes.push_back({frequency_hz[i], decay[i], amplitude[i]});
    }
    b->modes = object_modes(b->inline_modes);
    *out = keep(rt, std::move(b));
    return CHLADNI_OK;
  });
}

void chladni_bar_default(chladni_bar* bar) {
  if (!bar) return;
  const BarSpec d;
  *bar = chladni_bar{d.length,
                     d.width,
                     d.thickness,
                     d.youngs_modulus,
                     d.poisson_ratio,
                     d.density,
                     {d.damping.alpha[0], d.damping.alpha[1]},
                     d.max_frequency};
}

chladni_status chladni_bank_bar(chladni_runtime* rt, const chladni_bar* bar, chladni_bank** out) {
  return capi::guarded("chladni_bank_bar", [&] {
    if (!rt || !bar || !out) throw InputError("runtime, bar and out must not be null");
    for (double v : {bar->length, bar->width, bar->thickness, bar->youngs_modulus, bar->density,
                     bar->max_frequency})
      if (!(v > 0 && std::isfinite(v)))
        throw InputError(
            "bar: dimensions, Young's modulus, density and max_frequency must be "
            "finite and > 0");
    if (!(bar->poisson_ratio > -1 && bar->poisson_ratio < 0.5))
      throw InputError("bar: poisson_ratio must be in (-1, 0.5)");
    if (!(bar->rayleigh[0] >= 0 && bar->rayleigh[1] >= 0 && std::isfinite(bar->rayleigh[0]) &&
          std::isfinite(bar->rayleigh[1])))
      throw InputError("bar: the Rayleigh coefficients must be finite and >= 0");
    SceneObject obj;
    obj.name = "bar";
    obj.json_path = "bar";
    obj.source = SceneObject::Source::Bar;
    obj.bar = {bar->length,
               bar->width,
               bar->thickness,
               bar->youngs_modulus,
               bar->poisson_ratio,
               bar->density,
               DampingModel{DampingModel::Kind::Rayleigh, {bar->rayleigh[0], bar->rayleigh[1]}},
               bar->max_frequency};
    PlayableObject p = resolve_object(obj, rt->config.sample_rate);
    auto b = std::make_unique<chladni_bank>();
    b->mass = bar->density * bar->length * bar->width * bar->thickness;
    b->model = std::move(p.model);
    b->modes = object_modes(*b->model);
    *out = keep(rt, std::move(b));
    return CHLADNI_OK;
  });
}

size_t chladni_bank_mode_count(const chladni_bank* bank) {
  return bank ? bank->modes.modes.size() : 0;
}

size_t chladni_bank_point_count(const chladni_bank* bank) {
  return bank && bank->model ? bank->model->points.size() : 0;
}

chladni_status chladni_bank_bounds(const chladni_bank* bank, double lo[3], double hi[3]) {
  return capi::guarded("chladni_bank_bounds", [&] {
    if (!bank || !lo || !hi) throw InputError("bank, min and max must not be null");
    if (!bank->model || bank->model->points.empty())
      throw InputError("the bank has no surface points (inline modes)");
    for (int c = 0; c < 3; ++c) {
      lo[c] = bank->model->points[0][c];
      hi[c] = lo[c];
    }
    for (const Vec3& p : bank->model->points) {
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
      }
    }
    return CHLADNI_OK;
  });
}

double chladni_bank_mass(const chladni_bank* bank) {
  return bank ? bank->mass : 0.0;
}

chladni_status chladni_spawn(chladni_runtime* rt, chladni_bank* bank, const double position[3],
                             const double orientation[4], double gain, uint32_t* object) {
  return capi::guarded("chladni_spawn", [&] {
    if (!rt || !bank || !object) throw InputError("runtime, bank and object must not be null");
    capi::need_vector(position, "position", false);
    const Quat q = capi::unit_quaternion(orientation);
    if (!std::isfinite(gain)) throw InputError("gain must be finite");
    if (rt->player->object_count() >= rt->config.max_objects)
      throw InputError("max_objects (" + std::to_string(rt->config.max_objects) + ") reached");
    const std::size_t k =
        rt->player->add_object(bank->modes, {position[0], position[1], position[2]}, q, gain);
    rt->player->finish_objects();
    *object = static_cast<uint32_t>(k);
    return CHLADNI_OK;
  });
}

chladni_status chladni_remove(chladni_runtime* rt, uint32_t object) {
  return capi::guarded("chladni_remove", [&] {
    if (!rt) throw InputError("runtime must not be null");
    check_target(rt, object, 0.0);
    rt->player->remove(object);
    return CHLADNI_OK;
  });
}

chladni_status chladni_shaker_add(chladni_runtime* rt, const chladni_shaker_desc* desc,
                                  uint32_t* shaker) {
  return capi::guarded("chladni_shaker_add", [&] {
    if (!rt || !desc || !shaker || !desc->instrument)
      throw InputError("runtime, desc, desc->instrument and shaker must not be null");
    check_target(rt, desc->object, 0.0);
    if (rt->config.shaker_slots == 0)
      throw InputError("the runtime was created with shaker_slots = 0: no room for shakers");
    if (rt->player->shaker_count() >= rt->config.max_shakers)
      throw InputError("max_shakers (" + std::to_string(rt->config.max_shakers) + ") reached");
    if (!(desc->particles >= 0 && desc->particles <= 1e6))
      throw InputError("particles must be in [0, 1e6]");
    if (!(desc->impulse >= 0 && desc->impulse <= 1e3))
      throw InputError("impulse must be in [0, 1e3] N s");
    ShakeEvent ev;
    ev.json_path = "shaker";
    ev.object = desc->object;
    ev.instrument = desc->instrument;
    ev.particles = desc->particles;
    ev.resonate_object = desc->resonate_object != 0;
    if (desc->impulse > 0) ev.impulse = desc->impulse;
    const std::size_t k = rt->player->shaker_count();
    const ShakerVoice voice =
        shake_voice(ev, rt->player->modes(desc->object), rt->config.sample_rate, 1 + k);
    *shaker =
        static_cast<uint32_t>(rt->player->add_shaker(desc->object, voice, ev.resonate_object));
    return CHLADNI_OK;
  });
}

chladni_status chladni_post_shake(chladni_runtime* rt, uint32_t shaker, double time,
                                  double energy) {
  return capi::guarded("chladni_post_shake", [&] {
    if (!rt) throw InputError("runtime must not be null");
    if (shaker >= rt->player->shaker_count())
      throw InputError("no shaker " + std::to_string(shaker));
    check_target(rt, static_cast<uint32_t>(rt->player->shaker_object(static_cast<int>(shaker))),
                 time);
    if (!(energy > 0 && energy <= 1)) throw InputError("energy must be in (0, 1]");
    Command c{};
    c.kind = Kind::Shake;
    c.object = shaker;
    c.time = time;
    c.impulse = energy;
    return post(rt, c);
  });
}

chladni_status chladni_post_impact(chladni_runtime* rt, const chladni_impact* im) {
  return capi::guarded("chladni_post_impact", [&] {
    if (!rt || !im) throw InputError("runtime and impact must not be null");
    check_target(rt, im->object, im->time);
    if (!(im->impulse > 0 && std::isfinite(im->impulse)))
      throw InputError("impulse must be finite and > 0");
    if (!(im->contact_time >= 0 && im->contact_time <= 0.1))
      throw InputError("contact_time must be in [0, 0.1] s");
    capi::need_vector(im->direction, "direction");
    Command c{};
    c.kind = Kind::Impact;
    c.object = im->object;
    c.time = im->time;
    c.impulse = im->impulse;
    c.contact = im->contact_time;
    c.vertex = im->vertex;
    const double n =
        std::sqrt(im->direction[0] * im->direction[0] + im->direction[1] * im->direction[1] +
                  im->direction[2] * im->direction[2]);
    for (int i = 0; i < 3; ++i) c.a[i] = im->direction[i] / n;
    if (im->vertex >= 0) {
      const std::size_t points = rt->player->points(im->object);
      if (static_cast<uint64_t>(im->vertex) >= points)
        throw InputError("vertex " + std::to_string(im->vertex) + " is out of range (object " +
                         std::to_string(im->object) + " has " + std::to_string(points) +
                         " surface points)");
    } else {
      capi::need_vector(im->point, "point", false);
      for (int i = 0; i < 3; ++i) c.b[i] = im->point[i];
    }
    return post(rt, c);
  });
}

chladni_status chladni_post_move(chladni_runtime* rt, uint32_t object, double time,
                                 const double position[3], const double orientation[4]) {
  return capi::guarded("chladni_post_move", [&] {
    if (!rt) throw InputError("runtime must not be null");
    check_target(rt, object, time);
    capi::need_vector(position, "position", false);
    const Quat q = capi::unit_quaternion(orientation);
    Command c{};
    c.kind = Kind::Move;
    c.object = object;
    c.time = time;
    for (int i = 0; i < 3; ++i) c.a[i] = position[i];
    for (int i = 0; i < 4; ++i) c.q[i] = q[i];
    return post(rt, c);
  });
}

chladni_status chladni_post_listener(chladni_runtime* rt, double time, const double position[3],
                                     const double forward[3], const double up[3]) {
  return capi::guarded("chladni_post_listener", [&] {
    if (!rt) throw InputError("runtime must not be null");
    if (!std::isfinite(time)) throw InputError("time must be finite");
    capi::need_vector(position, "position", false);
    capi::need_vector(forward, "forward");
    capi::need_vector(up, "up");
    Vec3 f{forward[0], forward[1], forward[2]}, u{up[0], up[1], up[2]};
    const Vec3 side = cross(f, u);
    if (dot(side, side) < 1e-18 * dot(f, f) * dot(u, u))
      throw InputError("forward and up must not be parallel");
    Command c{};
    c.kind = Kind::Listener;
    c.time = time;
    const double fn = std::sqrt(dot(f, f)), un = std::sqrt(dot(u, u));
    for (int i = 0; i < 3; ++i) {
      c.a[i] = position[i];
      c.b[i] = f[i] / fn;
      c.c[i] = u[i] / un;
    }
    return post(rt, c);
  });
}

}  // extern "C"
