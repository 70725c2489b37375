// Banks: loading, queries and release (control thread).
#include <algorithm>
#include <cmath>

#include "chladni/core/soundbank.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "handles.hpp"

using namespace chladni;
using namespace chladni::runtime;
using chladni::capi::Bank;

namespace {

// Instances of a bank share one transfer table; its far-field maps pay for their build from as
// many modes as the offline player builds them for.
constexpr std::size_t kMapModes = 4096;

chladni_bank keep(chladni_runtime* rt, std::unique_ptr<Bank> bank) {
  rt->reclaim();
  if (bank->modes.transfer)
    bank->table =
        object_transfer_table(*bank->modes.transfer, bank->modes.modes.size() >= kMapModes);
  const uint64_t id = rt->next_bank++;
  bank->id = id;
  rt->banks.emplace(id, std::move(bank));
  return chladni_bank{id};
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

chladni_bank bank_of(chladni_runtime* rt, Soundbank&& bank, const std::string& origin) {
  auto b = std::make_unique<Bank>();
  b->mass = solid_mass(bank);
  b->model =
      std::make_unique<ModalModel>(playable_model(bank, origin, rt->config.sample_rate, origin));
  b->modes = object_modes(*b->model);
  return keep(rt, std::move(b));
}

// The bank of a handle, or null (queries answer 0 for it).
const Bank* find(const chladni_runtime* rt, chladni_bank h) {
  if (!rt) return nullptr;
  const auto it = rt->banks.find(h.id);
  return it == rt->banks.end() || it->second->released ? nullptr : it->second.get();
}

void check_bar(const chladni_bar& bar) {
  for (double v :
       {bar.length, bar.width, bar.thickness, bar.youngs_modulus, bar.density, bar.max_frequency})
    if (!(v > 0 && std::isfinite(v)))
      throw InputError(
          "bar: dimensions, Young's modulus, density and max_frequency must be finite and > 0");
  if (!(bar.poisson_ratio > -1 && bar.poisson_ratio < 0.5))
    throw InputError("bar: poisson_ratio must be in (-1, 0.5)");
  if (!(bar.rayleigh[0] >= 0 && bar.rayleigh[1] >= 0 && std::isfinite(bar.rayleigh[0]) &&
        std::isfinite(bar.rayleigh[1])))
    throw InputError("bar: the Rayleigh coefficients must be finite and >= 0");
}

}  // namespace

Bank& chladni_runtime::bank(chladni_bank h) const {
  const auto it = banks.find(h.id);
  if (it == banks.end() || it->second->released)
    throw InputError("no bank " + std::to_string(h.id) +
                     (it == banks.end() ? "" : " (it was released)"));
  return *it->second;
}

extern "C" {

chladni_status chladni_bank_load_file(chladni_runtime* rt, const char* path, chladni_bank* out) {
  return capi::guarded("chladni_bank_load_file", [&] {
    if (!rt || !path || !out) throw InputError("runtime, path and out must not be null");
    *out = bank_of(rt, read_soundbank(path), path);
    return CHLADNI_OK;
  });
}

chladni_status chladni_bank_load_memory(chladni_runtime* rt, const void* bytes, size_t size,
                                        chladni_bank* out) {
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
                                       chladni_bank* out) {
  return capi::guarded("chladni_bank_from_modes", [&] {
    if (!rt || !out || (count && (!frequency_hz || !decay || !amplitude)))
      throw InputError("runtime, arrays and out must not be null");
    if (count == 0) throw InputError("a bank needs at least one mode");
    auto b = std::make_unique<Bank>();
    for (size_t i = 0; i < count; ++i) {
      const std::string at = "mode " + std::to_string(i);
      if (!(frequency_hz[i] > 0 && frequency_hz[i] < rt->config.sample_rate / 2))
        throw InputError(at + ": frequency must be in (0, Nyquist)");
      if (!(decay[i] >= 0 && std::isfinite(decay[i])))
        throw InputError(at + ": decay must be finite and >= 0");
      if (!(std::abs(amplitude[i]) <= capi::kMaxGain))
        throw InputError(at + ": amplitude must be finite and within 1e6 Pa");
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

chladni_status chladni_bank_from_bar(chladni_runtime* rt, const chladni_bar* bar,
                                     chladni_bank* out) {
  return capi::guarded("chladni_bank_from_bar", [&] {
    if (!rt || !bar || !out) throw InputError("runtime, bar and out must not be null");
    check_bar(*bar);
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
    auto b = std::make_unique<Bank>();
    b->mass = bar->density * bar->length * bar->width * bar->thickness;
    b->model = std::move(p.model);
    b->modes = object_modes(*b->model);
    *out = keep(rt, std::move(b));
    return CHLADNI_OK;
  });
}

chladni_status chladni_bank_release(chladni_runtime* rt, chladni_bank h) {
  return capi::guarded("chladni_bank_release", [&] {
    if (!rt) throw InputError("runtime must not be null");
    rt->reclaim();
    Bank& b = rt->bank(h);
    b.released = true;
    if (b.objects == 0) rt->banks.erase(h.id);  // else the last retired object frees it
    return CHLADNI_OK;
  });
}

size_t chladni_bank_mode_count(const chladni_runtime* rt, chladni_bank h) {
  const Bank* b = find(rt, h);
  return b ? b->modes.modes.size() : 0;
}

size_t chladni_bank_point_count(const chladni_runtime* rt, chladni_bank h) {
  const Bank* b = find(rt, h);
  return b && b->model ? b->model->points.size() : 0;
}

chladni_status chladni_bank_bounds(const chladni_runtime* rt, chladni_bank h, double lo[3],
                                   double hi[3]) {
  return capi::guarded("chladni_bank_bounds", [&] {
    if (!rt || !lo || !hi) throw InputError("runtime, min and max must not be null");
    const Bank& b = rt->bank(h);
    if (!b.model || b.model->points.empty())
      throw InputError("the bank has no surface points (inline modes)");
    const auto [l, h] = b.model->surface_box();
    for (int c = 0; c < 3; ++c) lo[c] = l[c], hi[c] = h[c];
    return CHLADNI_OK;
  });
}

double chladni_bank_mass(const chladni_runtime* rt, chladni_bank h) {
  const Bank* b = find(rt, h);
  return b ? b->mass : 0.0;
}

}  // extern "C"
