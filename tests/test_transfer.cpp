// Acoustic transfer: the special functions against the C++17 library's, the equivalent-source fit
// against the exact radiation of a pulsating/vibrating sphere, symmetry and reciprocity on a box,
// and the GPU kernels against the double-precision CPU reference.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "chladni/core/spherical.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

namespace chladni {
namespace {

using cd = std::complex<double>;
using precompute::AcousticOptions;
using precompute::RadiatingSurface;

TEST(Spherical, BesselAndNeumannMatchTheStandardLibrary) {
  constexpr int L = 30;
  double j[L + 1];
  cd h[L + 1];
  for (double x : {1e-3, 0.05, 0.7, 3.0, 12.5, 31.0, 80.0}) {
    sph_bessel_j(L, x, j);
    sph_hankel1(L, x, h);
    for (int l = 0; l <= L; ++l) {
      const double jr = std::sph_bessel(unsigned(l), x), yr = std::sph_neumann(unsigned(l), x);
      if (std::abs(jr) > 1e-290) {
        EXPECT_NEAR(j[l], jr, 1e-10 * std::abs(jr) + 1e-14) << l << " " << x;
      }
      EXPECT_NEAR(h[l].real(), jr, 1e-9 * std::abs(h[l]) + 1e-14) << l << " " << x;
      if (std::isfinite(yr)) {
        EXPECT_NEAR(h[l].imag(), yr, 1e-10 * std::abs(yr)) << l << " " << x;
      }
    }
  }
}

TEST(Spherical, HankelRatioAndDerivative) {
  cd r[21], a[21], b[21];
  sph_hankel1_ratio(20, 4.0, 0.3, r);
  sph_hankel1(20, 4.0, a);
  sph_hankel1(20, 0.3, b);
  for (int l = 0; l <= 20; ++l) EXPECT_LT(std::abs(r[l] - a[l] / b[l]), 1e-10 * std::abs(r[l]));
  // Tiny arguments: h_l(x0) alone overflows double for l = 150, the ratio does not.
  std::vector<cd> big(151);
  sph_hankel1_ratio(150, 2e-3, 1e-3, big.data());
  EXPECT_TRUE(std::isfinite(std::abs(big[150])));
  EXPECT_NEAR(std::abs(big[150]), std::pow(0.5, 151), 1e-3 * std::pow(0.5, 151));
  // h_l' from the recurrence against a central difference.
  for (int l = 0; l <= 5; ++l) {
    const double x = 1.7, e = 1e-6;
    cd hp[7], hm[7];
    sph_hankel1(6, x + e, hp);
    sph_hankel1(6, x - e, hm);
    EXPECT_LT(std::abs(sph_hankel1_derivative(l, x) - (hp[l] - hm[l]) / (2 * e)), 1e-7);
  }
}

TEST(Spherical, RealHarmonicsAreTheLibrarysAndObeyTheAdditionTheorem) {
  constexpr int L = 12;
  std::vector<double> ya(sh_count(L)), yb(sh_count(L));
  const Vec3 a{0.3, -0.8, 0.52}, b{-0.6, 0.1, -0.79};
  real_sh(L, a, ya.data());
  real_sh(L, b, yb.data());
  const double ra = std::sqrt(dot(a, a)), theta = std::acos(a[2] / ra),
               phi = std::atan2(a[1], a[0]);
  for (int l = 0; l <= L; ++l) {
    EXPECT_NEAR(ya[sh_index(l, 0)], std::sph_legendre(unsigned(l), 0, theta), 1e-12);
    for (int m = 1; m <= l; ++m) {
      // std::sph_legendre carries the Condon-Shortley phase (-1)^m; ours does not.
      const double s = (m % 2 ? -1.0 : 1.0) * std::numbers::sqrt2 *
                       std::sph_legendre(unsigned(l), unsigned(m), theta);
      EXPECT_NEAR(ya[sh_index(l, m)], s * std::cos(m * phi), 1e-12);
      EXPECT_NEAR(ya[sh_index(l, -m)], s * std::sin(m * phi), 1e-12);
    }
    double sum = 0;
    for (int m = -l; m <= l; ++m) sum += ya[sh_index(l, m)] * yb[sh_index(l, m)];
    const double c = dot(a, b) / (ra * std::sqrt(dot(b, b)));
    EXPECT_NEAR(sum, (2 * l + 1) / (4 * std::numbers::pi) * std::legendre(unsigned(l), c), 1e-12);
  }
}

// p = i rho0 c U h_l(kr) / h_l'(ka) P_l(cos t) for u_n = U P_l(cos t) on a sphere of radius a.
cd sphere_pressure(int l, double k, double a, double r, double cos_t, double rho0, double c) {
  std::vector<cd> h(static_cast<std::size_t>(l) + 1);
  sph_hankel1(l, k * r, h.data());
  return cd(0, rho0 * c) * h[l] / sph_hankel1_derivative(l, k * a) *
         std::legendre(unsigned(l), cos_t);
}

struct SphereCase {
  double ka;
  int level;
};

void check_sphere(precompute::TransferKernels& kernels, const Vec3& offset, const SphereCase& sc,
                  double* worst_mag, double* worst_phase) {
  const double a = 0.1;
  test::SurfaceMesh mesh = test::icosphere(a, sc.level);
  for (Vec3& v : mesh.vertices) v = {v[0] + offset[0], v[1] + offset[1], v[2] + offset[2]};
  AcousticOptions o;
  RadiatingSurface surf(mesh, o);
  const double k = sc.ka / a;
  for (int l = 0; l <= 3; ++l) {
    std::vector<cd> un(mesh.vertices.size());
    for (std::size_t v = 0; v < un.size(); ++v) {
      const Vec3 d = sub(mesh.vertices[v], offset);
      un[v] = std::legendre(unsigned(l), d[2] / std::sqrt(dot(d, d)));
    }
    const auto fit = precompute::fit_sources(surf, k, surf.from_vertex_values(un), o, kernels);
    std::vector<cd> coeff;
    const ModeTransfer mt = precompute::expand_sources(surf, fit, o, kernels, coeff);
    Transfer t;
    t.centre = surf.centre();
    t.radius = surf.radius();
    t.add_mode(mt, coeff);
    std::vector<Vec3> pts;
    std::vector<double> cosines, radii;
    for (double r : {2.0 * a, 3.0 * a, 6.0 * a}) {
      for (double ct : {0.95, 0.6, -0.3, -0.9, 0.1}) {
        const double st = std::sqrt(1 - ct * ct);
        for (double phi : {0.3, 2.5}) {
          pts.push_back({offset[0] + r * st * std::cos(phi), offset[1] + r * st * std::sin(phi),
                         offset[2] + r * ct});
          cosines.push_back(ct), radii.push_back(r);
        }
      }
    }
    const std::vector<cd> p = precompute::source_pressure(surf, fit, pts, kernels);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double pl = std::legendre(unsigned(l), cosines[i]);
      if (std::abs(pl) < 0.15) continue;  // near a nodal line the relative error means nothing
      const cd exact = sphere_pressure(l, k, a, radii[i], cosines[i], o.air_density, o.sound_speed);
      for (const cd got : {p[i], t.pressure(0, pts[i])}) {
        const double mag = std::abs(std::abs(got) / std::abs(exact) - 1.0);
        const double ph = std::abs(std::arg(got / exact));
        *worst_mag = std::max(*worst_mag, mag);
        *worst_phase = std::max(*worst_phase, ph);
        EXPECT_LT(mag, 0.02) << "ka " << sc.ka << " l " << l << " r/a " << radii[i] / a << " cos "
                             << cosines[i];
        EXPECT_LT(ph, 0.05) << "ka " << sc.ka << " l " << l << " r/a " << radii[i] / a;
      }
    }
    EXPECT_LT(mt.held_out_error, 0.05) << "ka " << sc.ka << " l " << l;
  }
}

// Every ka, centred and off-centre; prints the worst errors (docs/transfer.md quotes them).
void check_all_spheres(precompute::TransferKernels& kernels, const char* label) {
  const SphereCase cases[] = {{0.1, 4}, {0.5, 4}, {1.0, 4}, {3.0, 4}, {6.0, 4}, {10.0, 4}};
  for (const Vec3& offset : {Vec3{0, 0, 0}, Vec3{0.37, -1.2, 0.81}}) {
    for (const SphereCase& sc : cases) {
      double mag = 0, ph = 0;
      check_sphere(kernels, offset, sc, &mag, &ph);
      std::printf("%s ka %5.2f offset %d: worst |p| error %.4f, phase %.4f rad\n", label, sc.ka,
                  offset[0] != 0, mag, ph);
    }
  }
}

TEST(Transfer, SphereMatchesTheExactSolutionOnTheCpu) {
  check_all_spheres(*precompute::make_cpu_transfer_kernels(), "cpu");
}

TEST(Transfer, SphereMatchesTheExactSolutionOnTheGpu) {
  auto ctx = test::gpu_context();
  if (!ctx) GTEST_SKIP() << "no Vulkan device";
  check_all_spheres(*precompute::make_gpu_transfer_kernels(ctx), "gpu");
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

}  // namespace
}  // namespace chladni

namespace chladni {
namespace {

// On a box (sharp edges, not a sphere): the surface velocity of interior point sources is data
// whose exterior field is known exactly, p = sum_j s_j G(x, y_j). A mirror pair of equal (opposite)
// sources must give a mirror-symmetric (antisymmetric) field, matching the exact one; and for two
// velocity patterns A and B, reciprocity holds on the surface: integral p_A u_B = integral p_B u_A.
TEST(Transfer, BoxSymmetryAndReciprocity) {
  const Vec3 size{0.2, 0.12, 0.08};
  const test::SurfaceMesh mesh = test::box_surface(size, {20, 12, 8});
  AcousticOptions o;
  const RadiatingSurface surf(mesh, o);
  auto kernels = precompute::make_cpu_transfer_kernels();
  const double k = 2 * std::numbers::pi * 1500.0 / o.sound_speed;
  const double cx = size[0] / 2;
  struct Source {
    Vec3 y;
    cd s;
  };
  auto green = [&](const Vec3& x, const Vec3& y) {
    const Vec3 d = sub(x, y);
    const double r = std::sqrt(dot(d, d));
    return std::polar(1.0 / (4 * std::numbers::pi * r), k * r);
  };
  auto velocity = [&](const std::vector<Source>& src) -> precompute::NormalVelocity {
    return [&, src](uint32_t t, const std::array<double, 3>& b) {
      const auto& tri = mesh.triangles[t];
      Vec3 x{0, 0, 0};
      for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a) x[a] += b[c] * mesh.vertices[tri[c]][a];
      cd dpdn = 0;
      for (const Source& j : src) {
        const Vec3 d = sub(x, j.y);
        const double r = std::sqrt(dot(d, d));
        dpdn += j.s * green(x, j.y) * cd(-1.0 / r, k) * (dot(d, surf.face_normal(t)) / r);
      }
      return dpdn / cd(0, k * o.sound_speed * o.air_density);  // dp/dn = i omega rho0 u_n
    };
  };
  std::vector<Vec3> pts, mirrored;
  for (const Vec3& d : {Vec3{0.35, 0.1, 0.2}, Vec3{0.5, -0.3, -0.1}, Vec3{0.25, 0.4, 0.6}}) {
    pts.push_back({cx + d[0], size[1] / 2 + d[1], size[2] / 2 + d[2]});
    mirrored.push_back({cx - d[0], size[1] / 2 + d[1], size[2] / 2 + d[2]});
  }
  const Vec3 y1{cx + 0.05, 0.07, 0.05}, y2{cx - 0.05, 0.07, 0.05};
  for (int parity : {+1, -1}) {
    const std::vector<Source> src{{y1, 1.0}, {y2, double(parity)}};
    const auto fit = precompute::fit_sources(surf, k, velocity(src), o, *kernels);
    EXPECT_LT(fit.held_out, 0.02);
    const auto p = precompute::source_pressure(surf, fit, pts, *kernels);
    const auto q = precompute::source_pressure(surf, fit, mirrored, *kernels);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const cd exact = green(pts[i], y1) + double(parity) * green(pts[i], y2);
      EXPECT_LT(std::abs(p[i] - exact), 0.02 * std::abs(exact)) << parity << " " << i;
      EXPECT_LT(std::abs(p[i] - double(parity) * q[i]), 0.01 * std::abs(p[i]))
          << parity << " " << i;
    }
  }
  // Reciprocity, with surface pressures and velocities at the triangle centroids.
  const std::vector<Source> A{{{0.06, 0.04, 0.03}, 1.0}}, B{{{0.15, 0.08, 0.05}, cd(0.3, 1.0)}};
  std::vector<Vec3> c(mesh.triangles.size());
  for (std::size_t t = 0; t < c.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (int a = 0; a < 3; ++a)
      c[t][a] =
          (mesh.vertices[tri[0]][a] + mesh.vertices[tri[1]][a] + mesh.vertices[tri[2]][a]) / 3;
  }
  auto integral = [&](const std::vector<Source>& pa, const std::vector<Source>& ub) {
    const auto fit = precompute::fit_sources(surf, k, velocity(pa), o, *kernels);
    const auto p = precompute::source_pressure(surf, fit, c, *kernels);
    const auto u = velocity(ub);
    cd s = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      const Vec3 n =
          triangle_normal(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]);
      s += p[t] * u(uint32_t(t), {1.0 / 3, 1.0 / 3, 1.0 / 3}) * (0.5 * std::sqrt(dot(n, n)));
    }
    return s;
  };
  const cd ab = integral(A, B), ba = integral(B, A);
  EXPECT_LT(std::abs(ab - ba), 0.01 * std::abs(ab)) << ab << " vs " << ba;
}

// The Vulkan kernels (float) against the double-precision reference.
TEST(Transfer, GpuKernelsMatchTheCpuReference) {
  auto ctx = test::gpu_context();
  if (!ctx) GTEST_SKIP() << "no Vulkan device";
  auto gpu = precompute::make_gpu_transfer_kernels(ctx);
  auto cpu = precompute::make_cpu_transfer_kernels();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> x(300), n(300), y(130);
  for (auto& p : x) {
    p = {u(rng), u(rng), u(rng)};
    const double r = std::sqrt(dot(p, p));
    n[&p - x.data()] = {p[0] / r, p[1] / r, p[2] / r};
    p = {0.15 * p[0] / r, 0.15 * p[1] / r, 0.15 * p[2] / r};  // on a sphere of 15 cm
  }
  for (auto& s : y) s = {0.08 * u(rng), 0.08 * u(rng), 0.08 * u(rng)};
  std::vector<cd> q(y.size());
  for (auto& z : q) z = {u(rng), u(rng)};
  for (double k : {0.5, 20.0, 400.0}) {  // up to kr ~ 90
    for (bool neumann : {false, true}) {
      std::vector<cd> a(x.size() * y.size()), b(a.size());
      cpu->matrix(x, neumann ? std::span<const Vec3>(n) : std::span<const Vec3>(), y, k, a.data());
      gpu->matrix(x, neumann ? std::span<const Vec3>(n) : std::span<const Vec3>(), y, k, b.data());
      double num = 0, den = 0, worst = 0, top = 0;
      for (std::size_t i = 0; i < a.size(); ++i) {
        num += std::norm(a[i] - b[i]), den += std::norm(a[i]);
        worst = std::max(worst, std::abs(a[i] - b[i])), top = std::max(top, std::abs(a[i]));
      }
      EXPECT_LT(std::sqrt(num / den), 1e-4) << "k " << k << " neumann " << neumann;
      EXPECT_LT(worst / top, 1e-4) << "k " << k << " neumann " << neumann;
    }
    std::vector<cd> pa(x.size()), pb(x.size());
    cpu->field(x, y, q, k, pa.data());
    gpu->field(x, y, q, k, pb.data());
    for (std::size_t j = 0; j < x.size(); ++j)
      EXPECT_LT(std::abs(pa[j] - pb[j]), 1e-4 * std::abs(pa[j]) + 1e-6)
          << "k " << k << " point " << j;
  }
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

}  // namespace
}  // namespace chladni

#include "chladni/runtime/modal/transfer_gains.hpp"
#include "chladni/runtime/thread_pool.hpp"

namespace chladni {
namespace {

// Two objects with random expansions (orders 0-30, kR from 0.005 to 40): the float CPU path and
// the GPU kernel against the double-precision Transfer::pressure, for listeners inside the
// reference sphere (clamped), near it and far away, after moving and turning.
Transfer random_transfer(std::mt19937& rng, const Vec3& centre, double radius, int modes) {
  std::uniform_real_distribution<double> u(-1, 1);
  Transfer t;
  t.centre = centre;
  t.radius = radius;
  for (int i = 0; i < modes; ++i) {
    ModeTransfer m;
    m.order = uint32_t(i % 31);
    m.wavenumber = std::exp(std::log(0.005 / radius) +
                            (std::log(40.0 / radius) - std::log(0.005 / radius)) * (i % 17) / 16.0);
    std::vector<cd> a(sh_count(int(m.order)));
    for (int l = 0; l <= int(m.order); ++l)
      for (int mm = -l; mm <= l; ++mm) a[sh_index(l, mm)] = cd(u(rng), u(rng)) / double(1 + l);
    t.add_mode(m, a);
  }
  return t;
}

TEST(TransferGains, CpuAndGpuMatchTheDoubleReference) {
  std::mt19937 rng(11);
  const Transfer a = random_transfer(rng, {0.1, 0.2, 0.0}, 0.12, 200);
  const Transfer b = random_transfer(rng, {-2.0, 0.5, 1.0}, 0.4, 150);
  runtime::TransferTable table;
  table.map_options.reset();  // the series itself (gain maps: test_gain_map.cpp)
  table.add(a);
  table.add(b);
  ASSERT_EQ(table.mode_count(), 350u);
  runtime::ThreadPool pool(2);
  auto ctx = test::gpu_context();
  std::unique_ptr<runtime::GpuTransferGains> gpu, chunked;
  if (ctx) {
    gpu = std::make_unique<runtime::GpuTransferGains>(ctx, table);
    // Coefficients split over many buffers, as a device with a small binding range needs.
    chunked = std::make_unique<runtime::GpuTransferGains>(ctx, table, 8192);
  }
  std::vector<float> dev2(table.mode_count());
  runtime::ListenerFrame frame;
  std::vector<float> cpu(table.mode_count()), dev(table.mode_count());
  for (const Vec3& la : {Vec3{0.12, 0.21, 0.05}, Vec3{0.1, 0.2, 0.3}, Vec3{3.0, -4.0, 1.5}}) {
    const Vec3 lb{la[1] - 2.0, -la[0] + 0.5, la[2] + 1.0};
    const std::vector<Vec3> listener{la, lb};
    frame.update(table, listener, true);
    runtime::transfer_gains(table, frame, cpu, &pool);
    if (gpu) {
      gpu->compute(frame, dev);
      chunked->compute(frame, dev2);
      EXPECT_EQ(dev, dev2);
    }
    for (std::size_t i = 0; i < table.mode_count(); ++i) {
      const bool first = i < a.mode_count();
      const double ref =
          first ? std::abs(a.pressure(i, la)) : std::abs(b.pressure(i - a.mode_count(), lb));
      ASSERT_TRUE(std::isfinite(ref));
      EXPECT_NEAR(cpu[i], ref, 1e-4 * ref + 1e-30) << "mode " << i;
      if (gpu) {
        EXPECT_NEAR(dev[i], ref, 1e-4 * ref + 1e-30) << "gpu mode " << i;
      }
    }
  }
  if (ctx) {
    EXPECT_EQ(ctx->validation_errors(), 0u);
  }
}

// Physics of the gains: a monopole falls off as 1/r and is the same in every direction; a dipole
// (l = 1, m = 0) is silent broadside and loudest on its axis.
TEST(TransferGains, DistanceAndDirectionShapeTheGain) {
  Transfer t;
  t.radius = 0.1;
  ModeTransfer m;
  m.wavenumber = 2 * std::numbers::pi * 2000 / 343.0;
  m.order = 1;
  t.add_mode(m, {cd(1, 0), 0, 0, 0});
  t.add_mode(m, {0, 0, cd(0, 1), 0});
  runtime::TransferTable table;
  table.map_options.reset();
  table.add(t);
  runtime::ListenerFrame frame;
  std::vector<float> g(2);
  auto at = [&](const Vec3& x) {
    frame.update(table, std::vector<Vec3>{x});
    runtime::transfer_gains(table, frame, g);
    return g;
  };
  const auto near = at({0, 0, 1}), far = at({0, 0, 4});
  EXPECT_NEAR(far[0] / near[0], 0.25, 1e-5);
  EXPECT_NEAR(at({1, 0, 0})[0], near[0], 1e-6 * near[0]);
  EXPECT_LT(at({1, 0, 0})[1], 1e-6 * near[1]);
  EXPECT_NEAR(at({0.6, 0, 0.8})[1], 0.8 * near[1], 1e-4 * near[1]);
}

}  // namespace
}  // namespace chladni

#include "chladni/core/scene.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/scene/render.hpp"

namespace chladni {
namespace {

// Amplitude of the component at `hz` in samples [from, to) of channel 0 (Goertzel, Hann window).
double tone(const AudioBuffer& a, double hz, std::size_t from, std::size_t to) {
  std::complex<double> acc = 0;
  double wsum = 0;
  for (std::size_t n = from; n < to; ++n) {
    const double w =
        0.5 - 0.5 * std::cos(2 * std::numbers::pi * double(n - from) / double(to - from));
    acc += w * double(a.samples[n * a.channels]) *
           std::polar(1.0, -2 * std::numbers::pi * hz * double(n) / a.sample_rate);
    wsum += w;
  }
  return 2 * std::abs(acc) / wsum;
}

// The probe: mode A (500 Hz) radiates as a monopole, mode B (900 Hz) as a z-dipole.
ModalModel probe_model() {
  ModalModel model;
  model.name = "probe";
  model.omega = {2 * std::numbers::pi * 500, 2 * std::numbers::pi * 900};
  model.decay = {1.0, 1.0};
  model.radiation = {1.0, 1.0};
  Transfer t;
  t.radius = 0.1;
  ModeTransfer m;
  m.order = 1;
  m.wavenumber = model.omega[0] / 343.0;
  t.add_mode(m, {cd(1, 0), 0, 0, 0});
  m.wavenumber = model.omega[1] / 343.0;
  t.add_mode(m, {0, 0, cd(1, 0), 0});
  model.transfer = t;
  return model;
}

// One strike of the probe at the origin, 1 s, the listener at `at`.
Scene probe_scene(const Vec3& at) {
  Scene s;
  s.channels = 1;
  s.duration = 1.0;
  SceneObject so;
  so.name = "probe";
  s.objects = {so};
  ImpactEvent ev;
  ev.impulse = 1.0;
  s.events = {ev};
  s.listener.position = at;
  return s;
}

AudioBuffer render_probe(const Scene& scene, const runtime::ObjectModes& obj,
                         std::size_t map_modes = 4096) {
  runtime::CpuFilterbankOptions fo;
  fo.channels = 1;
  fo.capacity = 1024;
  fo.threads = 1;
  runtime::CpuFilterbank fb(fo);
  runtime::RenderOptions ro;
  ro.map_gain_modes = map_modes;
  return runtime::render_scene(scene, {obj}, fb, ro);
}

constexpr std::size_t kHalf = 24000;  // samples in half the render

// On the object's z axis both modes sound; broadside the dipole falls silent, exactly and through
// far-field maps; distance scales the monopole as 1/r.
TEST(TransferRender, ListenerDirectionAndDistanceShapeTheSound) {
  const ModalModel model = probe_model();  // object_modes points into it
  const runtime::ObjectModes obj = runtime::object_modes(model);
  ASSERT_NE(obj.transfer, nullptr);
  const AudioBuffer axis = render_probe(probe_scene({0, 0, 1}), obj);
  const AudioBuffer side = render_probe(probe_scene({1, 0, 0}), obj);
  EXPECT_NEAR(tone(side, 500, 0, kHalf) / tone(axis, 500, 0, kHalf), 1.0, 1e-3);
  EXPECT_LT(tone(side, 900, 0, kHalf), 1e-3 * tone(axis, 900, 0, kHalf));
  EXPECT_GT(tone(axis, 900, 0, kHalf), 0.1 * tone(axis, 500, 0, kHalf));
  // The same through far-field maps (10 R away): the levels and the dipole's null hold.
  const AudioBuffer axis_map = render_probe(probe_scene({0, 0, 1}), obj, 0);
  EXPECT_NEAR(tone(axis_map, 500, 0, kHalf) / tone(axis, 500, 0, kHalf), 1.0, 5e-3);
  EXPECT_NEAR(tone(axis_map, 900, 0, kHalf) / tone(axis, 900, 0, kHalf), 1.0, 5e-3);
  const AudioBuffer side_map = render_probe(probe_scene({1, 0, 0}), obj, 0);
  EXPECT_LT(tone(side_map, 900, 0, kHalf), 1e-3 * tone(axis, 900, 0, kHalf));
  // Twice as far on the axis: the monopole at half the level.
  const AudioBuffer far = render_probe(probe_scene({0, 0, 2}), obj);
  EXPECT_NEAR(tone(far, 500, 0, kHalf) / tone(axis, 500, 0, kHalf), 0.5, 5e-3);
}

// A turned object turns its dipole; a listener move mid-render changes the balance from then on.
TEST(TransferRender, TurnedObjectAndMovingListenerShapeTheSound) {
  const ModalModel model = probe_model();  // object_modes points into it
  const runtime::ObjectModes obj = runtime::object_modes(model);
  const AudioBuffer axis = render_probe(probe_scene({0, 0, 1}), obj);
  // The object turned 90 degrees about y: its dipole axis now points along world x.
  Scene s = probe_scene({1, 0, 0});
  s.objects[0].orientation = {std::cos(std::numbers::pi / 4), 0, std::sin(std::numbers::pi / 4), 0};
  const AudioBuffer turned = render_probe(s, obj);
  EXPECT_NEAR(tone(turned, 900, 0, kHalf) / tone(axis, 900, 0, kHalf), 1.0, 1e-3);

  // A listener move at 0.5 s from the axis to broadside silences the dipole from there on.
  s = probe_scene({0, 0, 1});
  MoveEvent mv;
  mv.time = 0.5;
  mv.position = Vec3{1, 0, 0};
  s.moves = {mv};
  const AudioBuffer moved = render_probe(s, obj);
  EXPECT_GT(tone(moved, 900, 0, kHalf), 0.5 * tone(axis, 900, 0, kHalf));
  EXPECT_LT(tone(moved, 900, kHalf, 2 * kHalf), 1e-3 * tone(axis, 900, kHalf, 2 * kHalf));
}

// A fit that misses the surface data (held-out error > 1) is not used: that mode falls back to
// its compact-source gain over distance, the same in every direction.
TEST(TransferRender, PoorFitFallsBackToTheCompactSource) {
  ModalModel model = probe_model();
  model.transfer->modes[1].held_out_error = 2.0f;
  const runtime::ObjectModes fallback = runtime::object_modes(model);
  const AudioBuffer side = render_probe(probe_scene({1, 0, 0}), fallback);
  const AudioBuffer axis = render_probe(probe_scene({0, 0, 1}), fallback);
  EXPECT_GT(tone(side, 900, 0, kHalf), 0.0);
  EXPECT_NEAR(tone(side, 900, 0, kHalf) / tone(axis, 900, 0, kHalf), 1.0, 1e-3);
}

}  // namespace
}  // namespace chladni
