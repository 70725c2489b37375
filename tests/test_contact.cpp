// Continuous contact: the sliding and rolling laws of contact_excitation.hpp against their
// analytic spectra, the mode shapes at the contact point, fades, and scenes on both filterbanks.
#include <fftw3.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "chladni/core/analytic_bar.hpp"
#include "chladni/core/error.hpp"
#include "chladni/runtime/contact/contact_bank.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/scene/prepare_scene.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::runtime;

namespace {

constexpr double kContactFs = 48000;

// One-sided power spectral density (per Hz) by Welch's method: Hann-windowed segments of
// `n`, half overlapping.
std::vector<double> contact_psd(const std::vector<float>& x, int n) {
  std::vector<float> in(n);
  std::vector<fftwf_complex> out(n / 2 + 1);
  fftwf_plan plan = fftwf_plan_dft_r2c_1d(n, in.data(), out.data(), FFTW_ESTIMATE);
  std::vector<double> w(n), psd(n / 2 + 1, 0.0);
  double w2 = 0;
  for (int i = 0; i < n; ++i)
    w2 += (w[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * i / n)) * w[i];
  int segments = 0;
  for (std::size_t s = 0; s + n <= x.size(); s += n / 2, ++segments) {
    for (int i = 0; i < n; ++i) in[i] = float(x[s + i] * w[i]);
    fftwf_execute(plan);
    for (int k = 0; k <= n / 2; ++k)
      psd[k] += double(out[k][0]) * out[k][0] + double(out[k][1]) * out[k][1];
  }
  fftwf_destroy_plan(plan);
  for (int k = 0; k <= n / 2; ++k)
    psd[k] *= (k == 0 || k == n / 2 ? 1 : 2) / (segments * w2 * kContactFs);
  return psd;
}

// The mean of `psd` over the bins within a third of an octave of f.
double contact_band(const std::vector<double>& psd, int n, double f) {
  double sum = 0;
  int count = 0;
  for (std::size_t k = 0; k < psd.size(); ++k) {
    const double fk = double(k) * kContactFs / n;
    if (fk >= f * std::pow(2.0, -1.0 / 6) && fk <= f * std::pow(2.0, 1.0 / 6))
      sum += psd[k], ++count;
  }
  return sum / count;
}

// The same mean of an analytic density.
template <class F>
double contact_band_of(F density, double f) {
  double sum = 0;
  const int steps = 64;
  for (int i = 0; i < steps; ++i)
    sum += density(f * std::pow(2.0, -1.0 / 6 + (i + 0.5) / (3.0 * steps)));
  return sum / steps;
}

std::vector<float> contact_force(const SurfaceProfile& p, float force, float slip, float rolling,
                                 std::size_t samples) {
  ContactExcitation ex(p, kContactFs, 0.123);
  std::vector<float> f(samples), s(samples), r(samples), out(samples);
  std::fill(f.begin(), f.end(), force);
  std::fill(s.begin(), s.end(), slip);
  std::fill(r.begin(), r.end(), rolling);
  ex.process(f.data(), s.data(), r.data(), uint32_t(samples), out.data());
  return out;
}

double contact_db(double ratio) {
  return 10 * std::log10(ratio);
}

Roughness contact_surface() {
  Roughness r = roughness_preset("steel");
  r.beta = 2.5;  // away from 2, so the speed law's exponent beta - 1 is not 1
  return r;
}

}  // namespace

TEST(ContinuousContact, SlidingSpectrumIsTheProfileReadAtTheSlipSpeed) {
  const SurfaceProfile p(contact_surface(), 3);
  const Roughness& r = p.roughness();
  const int n = 8192;
  for (const float v : {0.2f, 0.8f}) {
    const float N = 3;
    const std::vector<double> psd = contact_psd(contact_force(p, N, v, 0, 1 << 18), n);
    const double gate = v * v / (v * v + kSlipGate * kSlipGate);
    // S(f) = level^2 N^2 g^2 P(f / v) / v.
    auto expected = [&](double f) {
      return r.level * r.level * N * N * gate * gate * p.psd(f / v) / v;
    };
    for (const double f : {4 * v / r.longest, 200.0 * v, 0.3 * v / r.shortest}) {
      SCOPED_TRACE("v " + std::to_string(v) + " f " + std::to_string(f));
      EXPECT_NEAR(contact_db(contact_band(psd, n, f) / contact_band_of(expected, f)), 0.0, 1.0);
    }
  }
}

TEST(ContinuousContact, SlidingLevelFollowsForceAndSpeedAndItsCentroidTheSpeed) {
  const SurfaceProfile p(contact_surface(), 4);
  const Roughness& r = p.roughness();
  const std::size_t len = 1 << 18;
  // Linear in the normal force, sample for sample.
  const std::vector<float> a = contact_force(p, 1, 0.5f, 0, 4096),
                           b = contact_force(p, 4, 0.5f, 0, 4096);
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_FLOAT_EQ(b[i], 4 * a[i]);
  // A mode at 1 kHz rings with power ~ v^(beta - 1): the density there, at two speeds.
  const int n = 8192;
  const double slow = contact_band(contact_psd(contact_force(p, 1, 0.25f, 0, len), n), n, 1000);
  const double fast = contact_band(contact_psd(contact_force(p, 1, 1.0f, 0, len), n), n, 1000);
  EXPECT_NEAR(contact_db(fast / slow), contact_db(std::pow(4.0, r.beta - 1)), 1.0);
  // The band moves with the speed: centroid = v * mean wavenumber of P.
  auto centroid = [&](float v) {
    const std::vector<double> psd = contact_psd(contact_force(p, 1, v, 0, len), n);
    double m0 = 0, m1 = 0;
    for (std::size_t k = 1; k < psd.size(); ++k)
      m0 += psd[k], m1 += psd[k] * double(k) * kContactFs / n;
    return m1 / m0;
  };
  double num = 0, den = 0;
  for (double k = 1 / r.longest; k <= 1 / r.shortest; k *= 1.001)
    num += k * p.psd(k) * k, den += p.psd(k) * k;  // d(log k) steps: weight k
  for (const float v : {0.1f, 0.4f}) EXPECT_NEAR(centroid(v) / (v * num / den), 1.0, 0.05) << v;
}

TEST(ContinuousContact, SilentWithoutSlipOrRolling) {
  const SurfaceProfile p(roughness_preset("wood"), 5);
  for (float x : contact_force(p, 10, 0, 0, 48000)) ASSERT_EQ(x, 0.0f);
}

TEST(ContinuousContact, RollingSpectrumFollowsSpeedAndThePatch) {
  const SurfaceProfile p(contact_surface(), 6);
  const Roughness& r = p.roughness();
  const int n = 8192;
  const float N = 2;
  for (const float v : {0.1f, 0.4f}) {
    const std::vector<double> psd = contact_psd(contact_force(p, N, 0, v, 1 << 18), n);
    // S(f) = (N h / g0)^2 (2 pi f)^4 P(f / v) H(f / v)^2 / v.
    auto expected = [&](double f) {
      const double m = N * r.height / kStandardGravity, k = f / v;
      return m * m * std::pow(2 * std::numbers::pi * f, 4) * p.psd(k) *
             std::pow(p.patch_response(k), 2) / v;
    };
    // Below the patch's cutoff, at it, and where it has taken 20 dB off.
    for (const double kk : {0.2 / r.patch, 0.5 / r.patch, 0.8 / r.patch}) {
      const double f = kk * v;
      SCOPED_TRACE("v " + std::to_string(v) + " f " + std::to_string(f));
      EXPECT_NEAR(contact_db(contact_band(psd, n, f) / contact_band_of(expected, f)), 0.0, 1.5);
    }
  }
}

TEST(ContinuousContact, RibbedSurfaceSoundsAtTheSpeedOverTheSpacing) {
  Roughness r = contact_surface();
  r.ribs = 0.005;
  // Deep ribs: the fractal shares their wavenumbers' bins, with an amplitude 1-2 % of theirs.
  r.rib_depth = 10;
  const SurfaceProfile p(r, 8);
  const double k0 = p.rib_wavenumber();
  ASSERT_NEAR(1 / k0, r.ribs, 1e-3 * r.ribs);  // whole ribs in the loop: within 0.1 %
  const int n = 32768;                         // 1.5 Hz bins: each line clear of the next and of DC
  const double df = kContactFs / n;
  for (const float v : {0.25f, 0.5f}) {
    const std::vector<double> psd = contact_psd(contact_force(p, 1, v, 0, 1 << 18), n);
    // The fundamental at v k0: a line whose power, summed over its bins, is the sinusoid's
    // mean square (level N g A1)^2 / 2, far above the fractal beside it.
    const double f0 = v * k0;
    const std::size_t bin = std::size_t(std::llround(f0 / df));
    // A line's power: its 7 bins, less the fractal beside it (bins 8 to 16 away, either side).
    auto line_power = [&](std::size_t b) {
      double in = 0, beside = 0;
      for (std::size_t k = b - 3; k <= b + 3; ++k) in += psd[k];
      for (std::size_t d = 8; d <= 16; ++d) beside += psd[b - d] + psd[b + d];
      return (in - 7 * beside / 18) * df;
    };
    const double line = line_power(bin);
    const double gate = v * v / (v * v + kSlipGate * kSlipGate);
    const double a1 = r.level * gate * p.rib_amplitude(1);
    EXPECT_NEAR(contact_db(line / (a1 * a1 / 2)), 0.0, 0.5) << v;
    EXPECT_GT(psd[bin], 100 * psd[bin + 12]) << v;  // a line, not a band
    // The second harmonic, a quarter of the fundamental's amplitude.
    const double second = line_power(2 * bin);
    EXPECT_NEAR(contact_db(second / line), contact_db(1.0 / 16), 1.0) << v;
  }
}

namespace {

// Two modes on two surface points: mode 0 has a node at point 0, mode 1 moves at both.
ModalModel contact_two_points(double normal_sign) {
  ModalModel m;
  m.name = "two points";
  m.omega = {2 * std::numbers::pi * 440, 2 * std::numbers::pi * 1300};
  m.decay = {3, 5};
  m.radiation = {1, 1};
  m.points = {{0, 0, 0}, {0.1, 0, 0}};
  m.normals = {{0, 0, normal_sign}, {0, 0, normal_sign}};
  // shape(i, v) = shapes[i * points + v]
  m.shapes = {{0, 0, 0}, {0, 0, 1}, {0, 0, 0.5}, {0, 0, -0.7}};
  return m;
}

ContactPoint contact_point(uint64_t sample, float force, float slip, uint32_t v0, uint32_t v1 = 0) {
  ContactPoint p;
  p.sample = sample;
  p.force = force;
  p.slip = slip;
  p.vertex = {v0, v1};
  return p;
}

}  // namespace

TEST(ContactBank, AContactAtAModesNodeLeavesItStill) {
  const ModalModel model = contact_two_points(1);
  const ObjectModes modes = object_modes(model);
  CpuFilterbank fb({.capacity = 16, .channels = 1, .threads = 1, .max_frames = 256});
  ContactBank bank(fb, {.sample_rate = kContactFs, .max_contacts = 1});
  ContactSpec spec;
  spec.bodies[0] = &modes;
  spec.roughness = roughness_preset("steel");
  const int c = bank.add_contact(spec);
  ASSERT_TRUE(bank.push(c, contact_point(0, 2, 0.5f, 0)));
  ASSERT_TRUE(bank.push(c, contact_point(4800, 2, 0.5f, 0)));
  std::vector<float> rows(256), out(256);
  for (uint64_t t = 0; t < 4096; t += 256) {
    bank.render(t, 256, rows.data());
    fb.process({}, 256, out.data(), {rows.data(), bank.streams()});
  }
  EXPECT_EQ(std::abs(fb.state(0)), 0.0f);  // mode 0 at its node
  EXPECT_GT(std::abs(fb.state(1)), 0.0f);
  // The contact moves to point 1, where mode 0 moves too.
  ASSERT_TRUE(bank.push(c, contact_point(4864, 2, 0.5f, 1)));
  ASSERT_TRUE(bank.push(c, contact_point(9600, 2, 0.5f, 1)));
  for (uint64_t t = 4096; t < 8192; t += 256) {
    bank.render(t, 256, rows.data());
    fb.process({}, 256, out.data(), {rows.data(), bank.streams()});
  }
  EXPECT_GT(std::abs(fb.state(0)), 0.0f);
}

TEST(ContactBank, TwoBodiesFeelEqualAndOppositeForces) {
  // The second body's normal there points the other way (it lies on the other side of the
  // contact): its modes are driven by the same force with the opposite sign.
  const ModalModel a = contact_two_points(1), b = contact_two_points(-1);
  const ObjectModes ma = object_modes(a), mb = object_modes(b);
  CpuFilterbank fb({.capacity = 16, .channels = 1, .threads = 1, .max_frames = 256});
  ContactBank bank(fb, {.sample_rate = kContactFs, .max_contacts = 1});
  ContactSpec spec;
  spec.bodies = {&ma, &mb};
  spec.roughness = roughness_preset("glass");
  const int c = bank.add_contact(spec);
  ASSERT_TRUE(bank.push(c, contact_point(0, 1, 0.3f, 1, 1)));
  ASSERT_TRUE(bank.push(c, contact_point(2400, 1, 0.3f, 1, 1)));
  std::vector<float> rows(256), out(256);
  for (uint64_t t = 0; t < 2048; t += 256) {
    bank.render(t, 256, rows.data());
    fb.process({}, 256, out.data(), {rows.data(), bank.streams()});
  }
  for (uint32_t i = 0; i < 2; ++i) {
    ASSERT_GT(std::abs(fb.state(i)), 0.0f);
    EXPECT_EQ(fb.state(2 + i), -fb.state(i)) << "mode " << i;
  }
}

TEST(ContactBank, FadesInAndOutOverTheRampAndRefusesBadPoints) {
  const ModalModel model = contact_two_points(1);
  const ObjectModes modes = object_modes(model);
  // The same contact with the ramp and with none (and no end): the first must be the second
  // times the fade, sample for sample.
  std::vector<float> force[2];
  for (int run = 0; run < 2; ++run) {
    CpuFilterbank fb({.capacity = 16, .channels = 1, .threads = 1, .max_frames = 512});
    ContactBank bank(fb,
                     {.sample_rate = kContactFs, .max_contacts = 1, .ramp = run == 0 ? 256u : 1u});
    ContactSpec spec;
    spec.bodies[0] = &modes;
    spec.roughness = roughness_preset("stone");
    const int c = bank.add_contact(spec);
    if (run == 0) {  // refused: non-finite or negative values, a vertex past the surface
      EXPECT_FALSE(bank.push(c, contact_point(0, NAN, 0.5f, 1)));
      EXPECT_FALSE(bank.push(c, contact_point(0, 1, INFINITY, 1)));
      EXPECT_FALSE(bank.push(c, contact_point(0, -1, 0.5f, 1)));
      EXPECT_FALSE(bank.push(c, contact_point(0, 1, 0.5f, 2)));
      EXPECT_FALSE(bank.push(7, contact_point(0, 1, 0.5f, 1)));
    }
    ASSERT_TRUE(bank.push(c, contact_point(100, 1, 0.5f, 1)));
    EXPECT_FALSE(bank.push(c, contact_point(50, 1, 0.5f, 1)));  // out of order
    ASSERT_TRUE(bank.push(c, contact_point(1000, 1, 0.5f, 1)));
    if (run == 0) {
      bank.end(c, 1000);
      EXPECT_EQ(bank.silent_from(), 1256u);
      EXPECT_FALSE(bank.push(c, contact_point(2000, 1, 0.5f, 1)));  // ended
    }
    std::vector<float> rows(512), out(512);
    for (uint64_t t = 0; t < 1536; t += 512) {
      bank.render(t, 512, rows.data());
      const std::span<const float> f = bank.force(c);
      force[run].insert(force[run].end(), f.begin(), f.begin() + 512);
      fb.process({}, 512, out.data(), {rows.data(), bank.streams()});
    }
  }
  const double peak = test::max_abs(force[1]);
  ASSERT_GT(peak, 0);
  for (std::size_t i = 0; i < force[0].size(); ++i) {
    double env = std::clamp((double(i) - 100) / 256, 0.0, 1.0);
    env *= std::clamp(1 - (double(i) - 1000) / 256, 0.0, 1.0);
    ASSERT_NEAR(force[0][i], env * force[1][i], 1e-6 * peak) << i;
    if (i <= 100 || i >= 1256) ASSERT_EQ(force[0][i], 0.0f) << i;
  }
}

namespace {

// A rod dragged across a plate-like bar while gravel is shaken onto the plate: a contact between
// two bodies with a moving point, one on a single body rolling, impacts and shakes besides.
Scene contact_scene(const std::string& extra = "") {
  return parse_scene(nlohmann::json::parse(R"({
    "sample_rate": 48000, "channels": 2, "duration": 1.2,
    "listener": {"position": [0, 1.0, 0.3]},
    "objects": [
      {"name": "rod", "position": [0.2, 1, 0], "bar": {"length": 0.25}},
      {"name": "plate", "position": [-0.3, 1, 0], "bar": {"length": 0.4, "width": 0.1}}
    ],
    "events": [
      {"time": 0.05, "type": "contact", "object": "plate", "other": "rod", "rate": 50,
       "force": [0, 2, 3, 3, 2, 1, 0], "slip": [0.2, 0.4, 0.6, 0.6, 0.5, 0.3, 0.1],
       "point": [[0.05, 0.05, 0.005], [0.1, 0.05, 0.005], [0.15, 0.05, 0.005],
                 [0.2, 0.05, 0.005], [0.25, 0.05, 0.005], [0.3, 0.05, 0.005],
                 [0.35, 0.05, 0.005]],
       "other_point": [0.12, 0.015, 0.005], "roughness": {"surface": "steel", "level": 0.08}},
      {"time": 0.4, "type": "contact", "object": "rod", "duration": 0.5, "force": 1,
       "rolling": 0.3, "point": [0.1, 0.015, 0.005],
       "roughness": {"surface": "glass", "ribs": 0.004, "rib_depth": 1}},
      {"time": 0.0, "type": "shake", "object": "plate", "instrument": "gravel", "energy": 0.3},
      {"time": 0.7, "type": "impact", "object": "rod", "impulse": 0.002})" +
                                           extra + "]}"),
                     ".");
}

}  // namespace

TEST(ContactScene, ParsesTrajectoriesAndNamesEachProblem) {
  const Scene s = contact_scene();
  ASSERT_EQ(s.contacts.size(), 2u);
  const ContactEvent& a = s.contacts[0];
  EXPECT_EQ(a.samples, 7u);
  EXPECT_DOUBLE_EQ(a.end_time(), 0.05 + 6 / 50.0);
  ASSERT_TRUE(a.other.has_value());
  EXPECT_EQ(*a.other, 0u);
  EXPECT_EQ(a.roughness.surface, "steel");
  EXPECT_EQ(*a.roughness.level, 0.08);
  EXPECT_EQ(s.contacts[1].samples, 51u);  // 0.5 s at 100 per second, both ends
  EXPECT_EQ(*s.contacts[1].roughness.ribs, 0.004);
  EXPECT_EQ(*s.contacts[1].roughness.rib_depth, 1.0);
  auto error = [](const std::string& event) {
    try {
      contact_scene("," + event);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head = R"({"time": 0, "type": "contact", "object": "rod", )";
  EXPECT_EQ(error(R"({"time": 0, "type": "contact", "object": "pot", "force": [1, 1]})"),
            "$.events[4].object: unknown object 'pot'");
  EXPECT_EQ(error(head + R"("other": "rod", "force": [1, 1]})"),
            "$.events[4].other: must name another object");
  EXPECT_EQ(error(head + R"("force": [1, -1]})"),
            "$.events[4].force[1]: must lie in [0, 1000000.0]");
  EXPECT_EQ(error(head + R"("force": [1, 1], "slip": [1, 1, 1]})"),
            "$.events[4].slip: has 3 values where the others have 2");
  EXPECT_EQ(error(head + R"("force": 1})"),
            "$.events[4]: a contact needs a 'duration' or per-sample arrays of 2 values or more");
  EXPECT_EQ(error(head + R"("duration": 1})"), "$.events[4]: missing required field 'force'");
  EXPECT_EQ(error(head + R"("force": [1, 1], "rolling": [1, "x"]})"),
            "$.events[4].rolling[1]: expected a number, got string");
  EXPECT_EQ(error(head + R"("force": [1, 1], "roughness": {"surface": "steel", "bumps": 1}})"),
            "$.events[4].roughness: unknown field 'bumps'");
  EXPECT_EQ(error(head + R"("force": [1, 1], "other_point": [0, 0, 0]})"),
            "$.events[4].other_point: needs 'other'");
}

TEST(ContactScene, RefusesPointsOffTheSurfaceAndUnknownSurfaces) {
  auto error = [](const std::string& event) {
    try {
      prepare_scene(contact_scene("," + event));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head = R"({"time": 0, "type": "contact", "object": "rod", "force": [1, 1], )";
  EXPECT_NE(error(head + R"("point": [[0.1, 0.015, 0.005], [0.1, 0.015, 5]]})")
                .find("$.events[4].point[1]: lies 4.99"),
            std::string::npos);
  EXPECT_EQ(error(head + R"("roughness": {"surface": "velvet"}})"),
            "$.events[4].roughness: unknown surface 'velvet' (known: steel, aluminium, glass, "
            "ceramic, wood, stone, plastic)");
  EXPECT_EQ(error(head + R"("roughness": {"longest": 2}})"),
            "$.events[4].roughness: roughness: longest must lie in (shortest, 1] m");
  EXPECT_EQ(error(head + R"("roughness": {"ribs": 0.5, "rib_depth": 1}})"),
            "$.events[4].roughness: roughness: ribs must be 0 or lie in [2 shortest, 0.1] m");
}

TEST(ContactScene, CpuAndGpuFilterbanksAgree) {
  const Scene scene = contact_scene();
  SceneSettings cpu_settings;
  cpu_settings.filterbank.threads = 1;
  PreparedScene c = prepare_scene(scene, cpu_settings);
  const AudioBuffer a = render_scene(scene, c);
  const double peak = test::max_abs(a.samples);
  ASSERT_GT(peak, 1e-4);
  // The contacts sound: without them the first contact's 120 ms differ by far more than noise.
  Scene quiet = scene;
  quiet.contacts.clear();
  PreparedScene q = prepare_scene(quiet, cpu_settings);
  const AudioBuffer without = render_scene(quiet, q);
  double diff = 0;
  for (std::size_t i = 2 * 2400; i < 2 * 9600; ++i)
    diff = std::max(diff, double(std::abs(a.samples[i] - without.samples[i])));
  EXPECT_GT(diff, 0.003 * peak);
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  SceneSettings gpu_settings;
  gpu_settings.filterbank.backend = gpu::DeviceChoice::Gpu;
  gpu_settings.filterbank.gpu_falls_back = false;
  PreparedScene g = prepare_scene(scene, gpu_settings);
  ASSERT_TRUE(g.filterbank->name().starts_with("gpu")) << g.filterbank->name();
  const AudioBuffer b = render_scene(scene, g);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  EXPECT_LT(test::max_diff(a.samples, b.samples), 1e-4 * peak);
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

TEST(ContactBank, ARemovedContactRingsDownThenGivesItsSlotsBack) {
  const ModalModel model = contact_two_points(1);
  const ObjectModes modes = object_modes(model);
  // Slots for one contact on the two-mode body: a second waits for the first to be freed.
  CpuFilterbank fb({.capacity = 2, .channels = 1, .threads = 1, .max_frames = 256});
  ContactBank bank(fb, {.sample_rate = kContactFs, .slots = 2, .max_contacts = 2});
  ContactSpec spec;
  spec.bodies[0] = &modes;
  spec.roughness = roughness_preset("wood");
  auto first = bank.prepare(spec), second = bank.prepare(spec);
  ASSERT_TRUE(bank.install(*first, 0));
  EXPECT_FALSE(bank.install(*second, 1));  // no slots left
  ASSERT_TRUE(bank.push(0, contact_point(0, 1, 0.4f, 1)));
  ASSERT_TRUE(bank.push(0, contact_point(2400, 1, 0.4f, 1)));
  std::vector<float> rows(2 * 256), out(256);
  uint64_t t = 0;
  auto block = [&] {
    bank.render(t, 256, rows.data());
    fb.process({}, 256, out.data(), {rows.data(), bank.streams()});
    t += 256;
  };
  while (t < 4096) block();
  bank.remove(0, t);
  EXPECT_FALSE(bank.push(0, contact_point(t + 10, 1, 0.4f, 1)));
  // Mode 0 decays at 3/s: it rings for ln(1000)/3 = 2.3 s before the slots are let go.
  const uint64_t removed = t;
  while (bank.retired().empty() && t < removed + 4 * 48000) {
    block();
    if (t < removed + 2 * 48000) ASSERT_GT(std::abs(fb.state(0)), 0.0f) << t;
  }
  ASSERT_EQ(bank.retired().size(), 1u);
  EXPECT_EQ(bank.retired()[0], 0u);
  EXPECT_GT(t, removed + std::log(1e3) / 3 * 48000);
  EXPECT_EQ(std::abs(fb.state(0)), 0.0f);
  EXPECT_FALSE(bank.live(0));
  bank.clear_retired();
  EXPECT_TRUE(bank.install(*second, 1));  // the freed slots
}
