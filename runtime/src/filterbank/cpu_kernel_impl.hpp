#pragma once
// Included by exactly one translation unit per instruction set, each compiled with its own
// target flags; everything here has internal linkage so the instantiations never merge.
#include <algorithm>
#include <cstring>

#include "filterbank/cpu_kernels.hpp"

namespace chladni::runtime::cpu {
namespace {

// S: a SIMD "ops" struct with type V, width W, load/store/set1/zero/add/sub/mul/min/fmadd/fmsub.
template <class S, int CH, int NV, bool DRIVEN, bool RAMP>
void run_tile(const KernelArgs& a, uint32_t t0, const Excitation* ex, const Excitation* ex_end) {
  using V = typename S::V;
  constexpr int W = S::W;
  constexpr uint32_t T = W * NV;
  V pr[NV], pi[NV], zr[NV], zi[NV], g0[NV], g1[NV];
  for (int v = 0; v < NV; ++v) {
    const uint32_t s = t0 + v * W;
    pr[v] = S::load(a.pr + s);
    pi[v] = S::load(a.pi + s);
    zr[v] = S::load(a.zr + s);
    zi[v] = S::load(a.zi + s);
    g0[v] = S::load(a.g0 + s);
    g1[v] = CH == 2 ? S::load(a.g1 + s) : S::zero();
  }
  // Ramping tiles: the gain at sample n is g + w (target - g), w = min(1, (el + n + 1) / R).
  [[maybe_unused]] V d0[RAMP ? NV : 1], d1[RAMP ? NV : 1], c[RAMP ? NV : 1];
  [[maybe_unused]] const V inv = S::set1(a.inv_ramp), one = S::set1(1.0f);
  if constexpr (RAMP) {
    for (int v = 0; v < NV; ++v) {
      d0[v] = S::sub(S::load(a.t0 + t0 + v * W), g0[v]);
      d1[v] = CH == 2 ? S::sub(S::load(a.t1 + t0 + v * W), g1[v]) : S::zero();
      c[v] = S::fmadd(S::load(a.el + t0 + v * W), inv, inv);
    }
  }
  // Driven tiles: input gains, and per lane the row of its stream (nullptr when undriven).
  // Usually every driven lane of a tile reads one stream (a voice's modes are consecutive): then
  // one broadcast per sample replaces the per-lane gather (undriven lanes have zero gains).
  [[maybe_unused]] V ar[DRIVEN ? NV : 1], ai[DRIVEN ? NV : 1];
  [[maybe_unused]] const float* row[DRIVEN ? T : 1];
  [[maybe_unused]] const float* shared = nullptr;
  if constexpr (DRIVEN) {
    for (int v = 0; v < NV; ++v) {
      ar[v] = S::load(a.ar + t0 + v * W);
      ai[v] = S::load(a.ai + t0 + v * W);
    }
    bool uniform = true;
    for (uint32_t l = 0; l < T; ++l) {
      const uint32_t k = a.src[t0 + l];
      row[l] = k == kNoStream ? nullptr : a.in + static_cast<std::size_t>(k) * a.frames;
      if (row[l]) {
        if (shared && row[l] != shared) uniform = false;
        shared = row[l];
      }
    }
    if (!uniform) shared = nullptr;
  }
  // z <- p z (Eq. of DESIGN.md), written as the GPU does: (pr zr - pi zi, pr zi + pi zr).
  // Driven: z <- p z + a x[n], the input term added after the pole product as on the GPU.
  auto step = [&](uint32_t n) {
    [[maybe_unused]] alignas(64) float x[DRIVEN ? T : 1];
    [[maybe_unused]] V xs = S::zero();
    if constexpr (DRIVEN) {
      if (shared)
        xs = S::set1(shared[n]);
      else
        for (uint32_t l = 0; l < T; ++l) x[l] = row[l] ? row[l][n] : 0.0f;
    }
    for (int v = 0; v < NV; ++v) {
      V nr = S::fmsub(pr[v], zr[v], S::mul(pi[v], zi[v]));
      V ni = S::fmadd(pr[v], zi[v], S::mul(pi[v], zr[v]));
      if constexpr (DRIVEN) {
        const V xv = shared ? xs : S::load(x + v * W);
        nr = S::fmadd(ar[v], xv, nr);
        ni = S::fmadd(ai[v], xv, ni);
      }
      zr[v] = nr;
      zi[v] = ni;
    }
  };
  auto emit = [&](uint32_t n) {
    V acc0 = S::zero(), acc1 = S::zero();
    if constexpr (RAMP) {
      const V nv = S::set1(static_cast<float>(n));
      for (int v = 0; v < NV; ++v) {
        const V w = S::min(one, S::fmadd(nv, inv, c[v]));
        acc0 = S::fmadd(S::fmadd(w, d0[v], g0[v]), zi[v], acc0);
        if constexpr (CH == 2) acc1 = S::fmadd(S::fmadd(w, d1[v], g1[v]), zi[v], acc1);
      }
    } else {
      for (int v = 0; v < NV; ++v) {
        acc0 = S::fmadd(g0[v], zi[v], acc0);
        if constexpr (CH == 2) acc1 = S::fmadd(g1[v], zi[v], acc1);
      }
    }
    float* l = a.lanes + static_cast<std::size_t>(n) * CH * W;
    S::store(l, S::add(S::load(l), acc0));
    if constexpr (CH == 2) S::store(l + W, S::add(S::load(l + W), acc1));
  };

  // Only excitations of this tile matter; they come in offset order.
  auto next_in_tile = [&](const Excitation* e) {
    while (e != ex_end && (e->slot < t0 || e->slot >= t0 + T)) ++e;
    return e;
  };
  const Excitation* e = next_in_tile(ex);
  uint32_t n = 0;
  while (n < a.frames) {
    const uint32_t stop = e != ex_end ? e->offset : a.frames;
    for (; n < stop; ++n) {  // the hot loop: no excitation in [n, stop)
      step(n);
      emit(n);
    }
    if (n == a.frames) break;
    // Sample n carries excitations: step, add them lane by lane, emit.
    step(n);
    alignas(64) float br[T], bi[T];
    for (int v = 0; v < NV; ++v) {
      S::store(br + v * W, zr[v]);
      S::store(bi + v * W, zi[v]);
    }
    for (; e != ex_end && e->offset == n; e = next_in_tile(e + 1)) {
      br[e->slot - t0] += e->re;
      bi[e->slot - t0] += e->im;
    }
    for (int v = 0; v < NV; ++v) {
      zr[v] = S::load(br + v * W);
      zi[v] = S::load(bi + v * W);
    }
    emit(n);
    ++n;
  }
  for (int v = 0; v < NV; ++v) {
    S::store(a.zr + t0 + v * W, zr[v]);
    S::store(a.zi + t0 + v * W, zi[v]);
  }
}

template <class S, int CH, int NV>
void run_range(const KernelArgs& a) {
  constexpr int W = S::W;
  constexpr uint32_t T = W * NV;
  static_assert(kGroup % T == 0, "tiles must divide the excitation group");
  std::memset(a.lanes, 0, sizeof(float) * a.frames * CH * W);
  const Excitation* ex = a.exc;
  const Excitation* ex_all_end = a.exc + a.exc_count;
  for (uint32_t g0 = a.begin; g0 < a.end; g0 += kGroup) {
    // This group's excitations, [ex, gend), sorted by offset.
    while (ex != ex_all_end && ex->slot < g0) ++ex;
    const Excitation* gend = ex;
    while (gend != ex_all_end && gend->slot < g0 + kGroup) ++gend;
    for (uint32_t t0 = g0; t0 < g0 + kGroup; t0 += T) {
      bool driven = false, ramp = false;
      if (a.in) {
        for (uint32_t l = 0; l < T && !driven; ++l) driven = a.src[t0 + l] != kNoStream;
      }
      if (a.el) {
        for (uint32_t l = 0; l < T && !ramp; ++l)
          ramp = a.t0[t0 + l] != a.g0[t0 + l] || (CH == 2 && a.t1[t0 + l] != a.g1[t0 + l]);
      }
      if (driven)
        ramp ? run_tile<S, CH, NV, true, true>(a, t0, ex, gend)
             : run_tile<S, CH, NV, true, false>(a, t0, ex, gend);
      else
        ramp ? run_tile<S, CH, NV, false, true>(a, t0, ex, gend)
             : run_tile<S, CH, NV, false, false>(a, t0, ex, gend);
    }
    ex = gend;
  }
  // Flush states far below audibility (denormals are slow and inaudible).
  for (uint32_t s = a.begin; s < a.end; ++s) {
    if (a.zr[s] * a.zr[s] + a.zi[s] * a.zi[s] < 1e-30f) a.zr[s] = a.zi[s] = 0.0f;
  }
  for (uint32_t n = 0; n < a.frames; ++n) {
    for (int c = 0; c < CH; ++c) {
      const float* l = a.lanes + (static_cast<std::size_t>(n) * CH + c) * W;
      float sum = 0.0f;
      for (int w = 0; w < W; ++w) sum += l[w];
      a.out[n * CH + c] = sum;
    }
  }
}

template <class S, int NV>
void kernel_entry(const KernelArgs& a) {
  if (a.channels == 2)
    run_range<S, 2, NV>(a);
  else
    run_range<S, 1, NV>(a);
}

}  // namespace
}  // namespace chladni::runtime::cpu
