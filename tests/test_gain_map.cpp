// Far-field maps for listener gains (runtime/gain_map.hpp): against the exact field of point
// sources (known in closed form) beyond each mode's valid radius, bit-identical to the series
// nearer in, shared between instances, and the harmonics a frame computes only where needed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "chladni/core/spherical.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/runtime/modal/transfer_gains.hpp"
#include "chladni/runtime/thread_pool.hpp"
#include "test_support.hpp"

namespace chladni {
namespace {

using cd = std::complex<double>;

// A few monopoles of random strength inside radius `spread` R about `centre`: the exact field is
// sum_j q_j h_0(k |x - y_j|); its expansion about the centre follows from the addition theorem,
// h_0(k |x - y|) = 4 pi sum_lm j_l(k |y|) Y_lm(y^) h_l(k |x|) Y_lm(x^) for |x| > |y|.
struct Sources {
  double k = 0;
  std::vector<Vec3> at;
  std::vector<cd> q;
  cd field(const Vec3& x) const {
    cd p = 0;
    for (std::size_t j = 0; j < at.size(); ++j) {
      const Vec3 d = sub(x, at[j]);
      const double r = std::sqrt(dot(d, d));
      p += q[j] * std::exp(cd(0, k * r)) / cd(0, k * r);  // h_0(kr) = e^(ikr) / (ikr)
    }
    return p;
  }
};

Sources random_sources(std::mt19937& rng, const Vec3& centre, double radius, double k,
                       double spread = 0.5) {
  std::uniform_real_distribution<double> u(-1, 1);
  Sources s;
  s.k = k;
  for (int j = 0; j < 5; ++j) {
    Vec3 d;
    do d = {u(rng), u(rng), u(rng)};
    while (dot(d, d) > 1);
    s.at.push_back(add(centre, scale(d, spread * radius)));
    s.q.push_back(cd(u(rng), u(rng)));
  }
  return s;
}

void add_sources(Transfer& t, const Sources& s) {
  const double kr = s.k * t.radius;
  double spread = 0;
  for (const Vec3& y : s.at)
    spread = std::max(spread, std::sqrt(dot(sub(y, t.centre), sub(y, t.centre))));
  ModeTransfer m;
  m.wavenumber = s.k;
  // j_l(k |y|) has fallen below 1e-7 of its peak by this order.
  m.order = static_cast<uint32_t>(std::ceil(s.k * spread + 10));
  const int L = static_cast<int>(m.order);
  std::vector<cd> a(sh_count(L), 0.0), h(L + 1);
  std::vector<double> j(L + 1), y(sh_count(L));
  sph_hankel1(L, kr, h.data());
  for (std::size_t n = 0; n < s.at.size(); ++n) {
    const Vec3 d = sub(s.at[n], t.centre);
    sph_bessel_j(L, s.k * std::sqrt(dot(d, d)), j.data());
    real_sh(L, d, y.data());
    for (int l = 0; l <= L; ++l)
      for (int mm = -l; mm <= l; ++mm)
        a[sh_index(l, mm)] += 4 * std::numbers::pi * s.q[n] * j[l] * y[sh_index(l, mm)] * h[l];
  }
  t.add_mode(m, a);
}

Vec3 direction(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Vec3 d{g(rng), g(rng), g(rng)};
  return scale(d, 1.0 / std::sqrt(dot(d, d)));
}

TEST(GainMap, MatchesTheExactFieldBeyondItsValidRadius) {
  std::mt19937 rng(5);
  Transfer t;
  t.centre = {0.02, -0.01, 0.05};
  t.radius = 0.1;
  std::vector<Sources> src;
  for (double kr : {0.3, 1.0, 3.0, 8.0, 15.0, 25.0}) {
    src.push_back(random_sources(rng, t.centre, t.radius, kr / t.radius));
    add_sources(t, src.back());
  }
  runtime::ThreadPool pool(2);
  runtime::TransferTable table;
  table.add(t, &pool);
  const runtime::GainMap& map = table.maps.at(0);
  ASSERT_EQ(map.series_modes, 0u) << "every mode should get a map";
  runtime::ListenerFrame frame;
  std::vector<float> g(t.mode_count());
  std::vector<double> errors;
  for (std::size_t i = 0; i < t.mode_count(); ++i) {
    EXPECT_LE(map.valid_radius[i], 32 * t.radius) << "mode " << i;
    for (double f : {1.0, 1.7, 4.0, 20.0}) {
      const double r = f * map.valid_radius[i];
      // The largest |p| over many directions at this radius: the scale errors are judged on.
      std::vector<Vec3> dirs;
      double peak = 0;
      for (int n = 0; n < 200; ++n) {
        dirs.push_back(direction(rng));
        peak = std::max(peak, std::abs(src[i].field(add(t.centre, scale(dirs.back(), r)))));
      }
      for (const Vec3& d : dirs) {
        const Vec3 x = add(t.centre, scale(d, r));
        frame.update(table, std::vector<Vec3>{x});
        runtime::transfer_gains(table, frame, g);
        const double exact = std::abs(src[i].field(x));
        if (exact < 0.1 * peak) continue;  // near the pattern's nulls
        errors.push_back(std::abs(20 * std::log10(g[i] / exact)));
        EXPECT_LT(errors.back(), 1.5) << "mode " << i << " at " << f << " r_valid";
      }
    }
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() * 99 / 100], 0.7) << "99th percentile over the sampled points";
  EXPECT_LT(errors[errors.size() / 2], 0.2) << "median";
}

TEST(GainMap, NearerListenersGetTheSeriesBitForBit) {
  std::mt19937 rng(9);
  Transfer t;
  t.radius = 0.2;
  for (double kr : {0.5, 3.0, 6.0, 12.0, 20.0})
    add_sources(t, random_sources(rng, t.centre, t.radius, kr / 0.2, 0.95));
  runtime::TransferTable maps, series;
  series.map_options.reset();
  maps.add(t);
  series.add(t);
  ASSERT_TRUE(series.maps.empty());
  runtime::ListenerFrame fm, fs;
  std::vector<float> gm(t.mode_count()), gs(t.mode_count());
  const runtime::GainMap& map = maps.maps.at(0);
  int checked = 0;
  for (std::size_t i = 0; i < t.mode_count(); ++i) {
    // Inside R every listener is heard as at R, where a map valid from R serves it.
    if (0.9 * map.valid_radius[i] <= t.radius) continue;
    ++checked;
    const Vec3 x = scale(direction(rng), 0.9 * map.valid_radius[i]);
    fm.update(maps, std::vector<Vec3>{x});
    fs.update(series, std::vector<Vec3>{x});
    EXPECT_GE(fm.series_order[0], int(t.modes[i].order));
    runtime::transfer_gains(maps, fm, gm);
    runtime::transfer_gains(series, fs, gs);
    EXPECT_EQ(gm[i], gs[i]) << "mode " << i;
  }
  EXPECT_GE(checked, 2);
  // Beyond every valid radius no harmonics are computed at all.
  fm.update(maps, std::vector<Vec3>{{0, 0, 2 * map.max_valid_radius}});
  EXPECT_EQ(fm.series_order[0], -1);
  fm.update(maps, std::vector<Vec3>{{0, 0, 2 * map.max_valid_radius}}, true);
  EXPECT_EQ(fm.series_order[0], int(maps.objects[0].max_order));
}

TEST(GainMap, InstancesShareCoefficientsAndMaps) {
  std::mt19937 rng(3);
  Transfer t;
  t.radius = 0.15;
  for (double kr : {1.0, 4.0, 12.0})
    add_sources(t, random_sources(rng, t.centre, t.radius, kr / 0.15));
  runtime::TransferTable table;
  table.add(t);
  const std::size_t coefficients = table.coefficients.size();
  const uint32_t second = table.add_instance(0);
  EXPECT_EQ(second, 1u);
  EXPECT_EQ(table.coefficients.size(), coefficients);
  EXPECT_EQ(table.maps.size(), 1u);
  EXPECT_EQ(table.mode_count(), 2 * t.mode_count());
  EXPECT_THROW(table.add_instance(7), std::out_of_range);
  // The same relative position gives the same gains, near (series) and far (maps).
  runtime::ListenerFrame frame;
  std::vector<float> g(table.mode_count());
  for (double r : {0.3, 5.0}) {
    const Vec3 x{0.6 * r, 0.0, 0.8 * r};
    frame.update(table, std::vector<Vec3>{x, x});
    runtime::transfer_gains(table, frame, g);
    for (std::size_t i = 0; i < t.mode_count(); ++i)
      EXPECT_EQ(g[i], g[i + t.mode_count()]) << "mode " << i << " at " << r;
  }
  auto ctx = test::gpu_context();
  if (!ctx) return;
  // The device reads the shared coefficients through each instance's records, also when they are
  // spread over several buffers.
  runtime::TransferTable series;
  series.map_options.reset();
  series.add(t);
  for (int n = 0; n < 4; ++n) series.add_instance(0);
  runtime::GpuTransferGains gpu(ctx, series), chunked(ctx, series, 4096);
  std::vector<Vec3> at;
  for (int n = 0; n < 5; ++n) at.push_back({0.3 + 0.1 * n, -0.2, 0.4});
  std::vector<float> cpu(series.mode_count()), dev(series.mode_count()), dev2(series.mode_count());
  frame.update(series, at);
  EXPECT_THROW(gpu.compute(frame, dev), std::invalid_argument);
  frame.update(series, at, true);
  runtime::transfer_gains(series, frame, cpu);
  gpu.compute(frame, dev);
  chunked.compute(frame, dev2);
  for (std::size_t i = 0; i < cpu.size(); ++i) {
    EXPECT_NEAR(dev[i], cpu[i], 1e-4 * cpu[i]) << "mode " << i;
    EXPECT_EQ(dev[i], dev2[i]) << "mode " << i;
  }
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

}  // namespace
}  // namespace chladni
