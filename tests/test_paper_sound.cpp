// Paper sound, synthesis half: the sheet model, inverse-FFT noise and spectra, the
// sound databases on disk, the dipole and image-source spatialization (Schreck et al. 2016,
// Eq. 3-6), database and modal synthesis (CPU and GPU) and onsets at the events' frames.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/plot/sound_figure.hpp"
#include "chladni/runtime/filterbank/cpu_filterbank.hpp"
#include "chladni/runtime/filterbank/gpu_filterbank.hpp"
#include "chladni/runtime/paper/paper_database.hpp"
#include "chladni/runtime/paper/paper_sheet.hpp"
#include "chladni/runtime/paper/paper_spatial.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"
#include "chladni/runtime/paper/spectral_noise.hpp"
#include "chladni/runtime/phisem/phisem.hpp"
#include "chladni/tools/paper_db_generate.hpp"
#include "paper_fixtures.hpp"
#include "test_support.hpp"

namespace {

using namespace chladni;
using namespace chladni::runtime;
using namespace chladni::tools;
using std::numbers::pi;

TEST(PaperSheet, FlatPanelIsTheKirchhoffPlateAndCurvatureStiffensLowOrders) {
  PaperMaterial mat;
  mat.loss_factor = 0;
  mat.air_decay = 0;
  const double a = 0.2, b = 0.1;
  const auto flat = sheet_modes(a, b, 0, mat, 1, 20000);
  const double D = mat.young * std::pow(mat.thickness, 3) / (12 * (1 - 0.09));
  // Simply supported plate: omega_mn = (pi^2) sqrt(D / rho h) ((m/a)^2 + (n/b)^2) (Leissa).
  for (const SheetMode& m : {flat[0], flat[5], flat[40]}) {
    const double expect = pi * pi * std::sqrt(D / mat.surface_density) *
                          (std::pow(m.m / a, 2) + std::pow(m.n / b, 2));
    EXPECT_NEAR(m.omega, expect, 1e-9 * expect) << m.m << "," << m.n;
  }
  // (1,1) of a 20 x 10 cm office sheet: sqrt(D / rho h) = 0.0677 m^2/s, pi^2 * 0.0677 * 125 / 2pi.
  EXPECT_NEAR(flat[0].omega / (2 * pi), 13.29, 0.01);
  // Bent: the membrane term raises modes with few half-waves across the bend the most.
  const auto bent = sheet_modes(a, b, sheet_radius(b, mat), mat, 1, 20000);
  ASSERT_GT(bent.size(), 10u);
  for (const SheetMode& m : bent) EXPECT_GE(m.omega, 0.999 * flat[0].omega);
  EXPECT_GT(bent[0].omega, 3 * flat[0].omega);
  EXPECT_LT(bent.size(), flat.size());
  // Damping: decay = loss * omega / 2 + air, and thinning keeps the summed energy.
  mat.loss_factor = 0.04;
  mat.air_decay = 30;
  const auto damped = sheet_modes(a, b, 0, mat, 1, 20000);
  EXPECT_NEAR(damped[10].decay, 0.02 * std::hypot(damped[10].omega, damped[10].decay) + 30,
              1e-6 * damped[10].decay);
  const auto thin = thin_modes(damped, 48);
  EXPECT_LE(thin.size(), 48u);
  double e_all = 0, e_thin = 0;
  for (const auto& m : damped) e_all += double(m.weight) * m.weight;
  for (const auto& m : thin) e_thin += double(m.weight) * m.weight;
  EXPECT_NEAR(e_thin, e_all, 1e-6 * e_all);
  EXPECT_NEAR(sheet_radius(0.1, mat), 0.1 / 2.8, 0.002);  // chord 0.7 of the arc
}

TEST(PaperSheet, CrumpleBurstsAreDeterministicAndDecay) {
  Rng r1(5), r2(5), r3(6);
  const auto b1 = crumple_burst(r1), b2 = crumple_burst(r2), b3 = crumple_burst(r3);
  ASSERT_EQ(b1.size(), b2.size());
  for (std::size_t i = 0; i < b1.size(); ++i) EXPECT_EQ(b1[i].time, b2[i].time);
  EXPECT_NE(b1.size() == b3.size() && b1.back().time == b3.back().time, true);
  // One shake of the PhISEM "paper" instrument: clicks with probability N/1024 per reference
  // sample while the energy d^n stays above 0.001, each as strong as the energy then.
  const PhisemParams p = phisem_params(phisem_preset("paper"), kPhisemReferenceRate);
  const double active = std::floor(std::log(kPhisemMinEnergy) / std::log(p.system_decay)) + 1;
  const double tau = -1.0 / (std::log(p.system_decay) * kPhisemReferenceRate);  // s
  Rng r(9);
  double clicks = 0, first = 0, second = 0, n_first = 0, n_second = 0;
  for (int k = 0; k < 400; ++k) {
    const auto burst = crumple_burst(r);
    clicks += burst.size();
    for (std::size_t i = 1; i < burst.size(); ++i) {  // the snap aside
      const double t = burst[i].time, s = std::abs(burst[i].strength);
      if (t < tau) first += s, n_first += 1;
      if (t >= tau && t < 2 * tau) second += s, n_second += 1;
    }
  }
  EXPECT_NEAR(clicks / 400, active * p.collision_probability,
              0.05 * active * p.collision_probability);
  // Strength falls by e over one time constant.
  EXPECT_NEAR((second / n_second) / (first / n_first), std::exp(-1.0), 0.05);
}

TEST(SpectralNoise, ReproducesTheSpectrumItIsGiven) {
  // A two-level spectrum: 0.02 below 5 kHz, 0.005 above; variance = mean of M^2.
  std::vector<float> spectrum(kFrictionBins);
  for (std::size_t k = 0; k < kFrictionBins; ++k)
    spectrum[k] = k * 44100.0 / 4096 < 5000 ? 0.02f : 0.005f;
  std::vector<float> bins(SpectralNoise::kBins);
  spectrum_to_hop_bins(spectrum, bins.data());
  SpectralNoise noise(1, 3);
  std::vector<float> signal(400 * SpectralNoise::kHop);
  for (std::size_t h = 0; h < 400; ++h) noise.hop(bins, signal.data() + h * SpectralNoise::kHop);
  signal.erase(signal.begin(), signal.begin() + SpectralNoise::kHop);  // skip the fade-in
  double var = 0, expect = 0;
  for (float x : signal) var += double(x) * x;
  for (std::size_t k = 0; k + 1 < SpectralNoise::kBins; ++k) expect += double(bins[k]) * bins[k];
  EXPECT_NEAR(var / signal.size(), expect / (SpectralNoise::kBins - 1), 0.03 * expect / 1024);
  const auto measured = friction_spectrum(signal);
  auto band = [&](double f0, double f1) {
    double s = 0;
    int n = 0;
    for (std::size_t k = 0; k < kFrictionBins; ++k)
      if (k * 44100.0 / 4096 >= f0 && k * 44100.0 / 4096 < f1) s += measured[k], ++n;
    return s / n;
  };
  EXPECT_NEAR(band(500, 4500), 0.02, 0.001);
  EXPECT_NEAR(band(6000, 20000), 0.005, 0.00025);
  EXPECT_THROW(friction_spectrum(std::vector<float>(4095)), InputError);
}

PaperDbOptions small_db() {
  PaperDbOptions o;
  o.variants = 1;
  o.clip_seconds = 0.1;
  o.clip_modes = 64;
  o.spectrum_modes = 128;
  return o;
}

TEST(PaperDatabase, GeneratedIsDeterministicAndSizeOrdered) {
  const PaperSoundDb a = generate_paper_database(small_db());
  const PaperSoundDb b = generate_paper_database(small_db());
  ASSERT_EQ(a.entries.size(), 82u);  // 9 x 9 grid + (0, 0)
  EXPECT_TRUE(a.entries[0].constrained);
  EXPECT_EQ(a.entries[5].crumple[0], b.entries[5].crumple[0]);
  // Bigger sheets ring lower: spectral centroid of the friction spectra falls with l_r.
  auto centroid = [](const std::vector<float>& s) {
    double num = 0, den = 0;
    for (std::size_t k = 0; k < s.size(); ++k)
      num += k * double(s[k]) * s[k], den += double(s[k]) * s[k];
    return num / den;
  };
  const auto& small = a.nearest_friction("wood", 0.025, 0.05, false);
  const auto& large = a.nearest_friction("wood", 0.30, 0.30, false);
  EXPECT_DOUBLE_EQ(small.l_r, 0.025);
  EXPECT_DOUBLE_EQ(large.l_c, 0.30);
  EXPECT_TRUE(a.nearest_crumple(0.1, 0.1, true).constrained);
  EXPECT_DOUBLE_EQ(a.nearest_crumple(0.11, 0.21, false).l_r, 0.10);
  EXPECT_DOUBLE_EQ(a.nearest_crumple(0.11, 0.21, false).l_c, 0.20);
  // The curved sheet's lowest modes (membrane-stiffened) sit lower for the big sheet.
  EXPECT_GT(centroid(small.friction.at("wood")[0]), centroid(large.friction.at("wood")[0]));
}

TEST(PaperDatabase, RoundTripsThroughRecordingsAndNamesBadFiles) {
  const std::string dir = test::temp_path("paper_db_rt");
  std::filesystem::remove_all(dir);
  const PaperSoundDb db = generate_paper_database(small_db());
  write_paper_database(dir, db, 3.0, 7);
  const PaperSoundDb back = load_paper_database(dir);
  ASSERT_EQ(back.entries.size(), db.entries.size());
  for (std::size_t i : {0, 17, 81}) {
    const auto& c0 = db.entries[i].crumple[0];
    const auto& c1 = back.entries[i].crumple[0];
    ASSERT_EQ(c0.size(), c1.size());
    EXPECT_LT(test::max_diff(c0, c1), 1.0 / 32768 + 1e-6);  // 16-bit PCM
    // The spectrum measured from the noise recording matches the one it was made from, band
    // by band (1 kHz bands: Welch noise averages out).
    const auto& s0 = db.entries[i].friction.at("wood")[0];
    const auto& s1 = back.entries[i].friction.at("wood")[0];
    for (std::size_t k0 = 100; k0 + 100 < kFrictionBins; k0 += 93) {
      double p0 = 0, p1 = 0;
      for (std::size_t k = k0; k < k0 + 93; ++k)
        p0 += double(s0[k]) * s0[k], p1 += double(s1[k]) * s1[k];
      EXPECT_NEAR(std::sqrt(p1 / p0), 1.0, 0.1) << "entry " << i << " bin " << k0;
    }
  }
  // A user's recording: stereo, replacing one clip; mixed to mono on load.
  AudioBuffer rec;
  rec.sample_rate = 44100;
  rec.channels = 2;
  rec.samples = {0.5f, 0.1f, -0.2f, -0.2f, 0.0f, 0.4f};
  write_wav(dir + "/crumple/mine.wav", rec);
  nlohmann::json index;
  std::ifstream(dir + "/paper_db.json") >> index;
  index["entries"][3]["crumple"][0] = "crumple/mine.wav";
  std::ofstream(dir + "/paper_db.json") << index.dump();
  const PaperSoundDb mine = load_paper_database(dir);
  EXPECT_EQ(mine.entries[3].crumple[0], (std::vector<float>{0.3f, -0.2f, 0.2f}));

  auto error_of = [&](nlohmann::json j) {
    std::ofstream(dir + "/paper_db.json") << j.dump();
    try {
      load_paper_database(dir);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto j = index;
  j["entries"][2]["crumple"][0] = "crumple/missing.wav";
  EXPECT_NE(error_of(j).find("entries[2].crumple[0]: file"), std::string::npos) << error_of(j);
  AudioBuffer slow = rec;
  slow.sample_rate = 22050;
  write_wav(dir + "/friction/slow.wav", slow);
  j = index;
  j["entries"][4]["friction"]["wood"][0] = "friction/slow.wav";
  EXPECT_NE(error_of(j).find("22050 Hz"), std::string::npos) << error_of(j);
  write_wav(dir + "/friction/short.wav", rec);
  j["entries"][4]["friction"]["wood"][0] = "friction/short.wav";
  EXPECT_NE(error_of(j).find("entries[4].friction.wood[0]: a friction recording needs"),
            std::string::npos)
      << error_of(j);
  j = index;
  j["entries"][1]["l_r_cm"] = -2;
  EXPECT_NE(error_of(j).find("entries[1].l_r_cm: must be > 0"), std::string::npos) << error_of(j);
  j = index;
  j["entries"][1]["colour"] = "red";
  EXPECT_NE(error_of(j).find("unknown field 'colour'"), std::string::npos) << error_of(j);
  std::filesystem::remove(dir + "/paper_db.json");
  EXPECT_THROW(load_paper_database(dir), InputError);
}

TEST(PaperSpatial, DipoleAndImageFollowEquations3To5) {
  const Vec3 y{0, 0, 0.1}, n{0, 0, 1}, x{0.3, 0, 0.5};
  PaperObstacle table;  // z = 0, normal +z
  PaperSpatialOptions o;
  std::vector<SoundPath> p;
  dipole_paths(y, n, 0.05, 0.05, x, std::span(&table, 1), o, p);
  ASSERT_EQ(p.size(), 2u);
  const double R = std::hypot(0.3, 0.4), Ri = std::hypot(0.3, 0.6);
  EXPECT_NEAR(p[0].gain, (0.4 / R) / R, 1e-12);     // cos(theta) / R, a = reference
  EXPECT_NEAR(p[1].gain, -(0.6 / Ri) / Ri, 1e-12);  // mirrored normal points down
  EXPECT_NEAR(p[1].delay - p[0].delay, (Ri - R) / 343, 1e-12);
  // Size: (a / a_ref)^3.
  p.clear();
  dipole_paths(y, n, 0.1, 0.05, x, {}, o, p);
  EXPECT_NEAR(p[0].gain, 8 * (0.4 / R) / R, 1e-12);
  // Eq. 6 magnitude: |g0 + g1 e^{i w dt}|.
  const std::vector<SoundPath> two{{1.0, 0.0}, {0.5, 1e-3}};
  EXPECT_NEAR(path_magnitude(two, 2 * pi * 500), 0.5, 1e-12);   // half a period: 1 - 0.5
  EXPECT_NEAR(path_magnitude(two, 2 * pi * 1000), 1.5, 1e-12);  // in phase
  // A source lying on the plane: the image fades (weight h / a) instead of cancelling it.
  p.clear();
  dipole_paths({0, 0, 0.0}, n, 0.05, 0.05, x, std::span(&table, 1), o, p);
  EXPECT_NEAR(p[1].gain, 0, 1e-12);
  // Ears: the listener's right is forward x up.
  PaperListener l;
  l.position = {0, 0, 0};
  l.forward = {0, 1, 0};
  l.up = {0, 0, 1};
  const auto ears = ear_positions(l);
  EXPECT_NEAR(ears[0][0], -0.09, 1e-12);
  EXPECT_NEAR(ears[1][0], 0.09, 1e-12);
}

// A database with one impulse clip and flat friction spectra, so outputs show the paths.
PaperSoundDb impulse_db() {
  PaperSoundDb db;
  for (bool constrained : {true, false}) {
    PaperDbEntry e;
    e.constrained = constrained;
    e.l_r = e.l_c = constrained ? 0 : 0.1;
    e.crumple.push_back(std::vector<float>(64, 0.0f));
    e.crumple.back()[0] = 1;
    e.friction["wood"].push_back(std::vector<float>(kFrictionBins, 0.01f));
    db.entries.push_back(e);
  }
  return db;
}

TEST(PaperSynth, CrumpleGivesTheDirectAndTheReflectedCopyAtTheirDelayAndGain) {
  // A 10 x 10 cm sheet 15 cm above a table flips its bend between frames 0 and 1.
  const double W = 0.1, r = 0.2, z0 = 0.15;
  auto bent = [&](double sign) {
    return [=](double u, double v) {
      const Vec3 c = test::cylinder(u, v, sign * r);
      return Vec3{c[0], c[1], z0 + c[2]};
    };
  };
  PaperAnimation a = test::two_frames(11, 11, W, W, bent(1), bent(-1));
  a.obstacles.push_back({"table", {0, 0, 0}, {0, 0, 1}, "wood"});
  a.listener.position = {0.05, -0.1, 0.6};
  validate(a, "test");
  PaperAnalyzer an(a);
  an.analyze(0);
  const auto fa = an.analyze(1);
  ASSERT_EQ(fa.events.size(), 1u);
  ASSERT_EQ(fa.events[0].resonators.size(), 1u);
  const PaperResonator& res = fa.events[0].resonators[0];

  const PaperSoundDb db = impulse_db();
  PaperSynthOptions o;
  const AudioBuffer out = render_paper(a, &db, nullptr, o);
  const double scale = std::min(fa.events[0].amplitude / o.crumple_reference, o.crumple_max_scale);
  const auto ears = ear_positions(a.listener);
  const std::int64_t at = std::llround(44100.0 / 60);  // frame 1
  const double a_disk = std::sqrt(res.area / pi), a_ref = std::sqrt(0.1 * 0.05 / pi);
  for (int ear = 0; ear < 2; ++ear) {
    // Independent geometry: the image of the centroid below the table.
    const Vec3 img{res.centroid[0], res.centroid[1], -res.centroid[2]};
    const double R = norm(sub(ears[ear], res.centroid)), Ri = norm(sub(ears[ear], img));
    const double cos_d = dot(sub(ears[ear], res.centroid), res.normal) / R;
    const Vec3 n_img{res.normal[0], res.normal[1], -res.normal[2]};
    const double cos_i = dot(sub(ears[ear], img), n_img) / Ri;
    const double size = std::pow(a_disk / a_ref, 3);
    const std::int64_t t0 = at + std::llround(R / 343 * 44100);
    const std::int64_t t1 = at + std::llround(Ri / 343 * 44100);
    ASSERT_GT(t1, t0 + 5);
    std::vector<std::pair<std::int64_t, float>> nonzero;
    for (std::size_t t = 0; t < out.frames(); ++t)
      if (out.samples[2 * t + ear] != 0)
        nonzero.push_back({std::int64_t(t), out.samples[2 * t + ear]});
    ASSERT_EQ(nonzero.size(), 2u) << "ear " << ear;
    EXPECT_EQ(nonzero[0].first, t0);
    EXPECT_EQ(nonzero[1].first, t1);
    EXPECT_NEAR(nonzero[0].second, scale * size * cos_d / R, 1e-5 * std::abs(nonzero[0].second));
    EXPECT_NEAR(nonzero[1].second, scale * size * cos_i / Ri, 1e-5 * std::abs(nonzero[1].second));
  }
}

TEST(PaperSynth, FrictionNearAWallShowsTheImageSourceNotches) {
  // A flat sheet slides slowly along a wall on a table; its friction noise heard with and
  // without the wall: the ratio of the spectra is Eq. 6's factor, with notches where the
  // image's extra path is an odd number of half wavelengths (same-sign image: the sheet's
  // normal lies in the wall's plane).
  const double W = 0.06, d = 0.05, speed = 0.02;
  const std::uint32_t frames = 240;
  const std::uint32_t nx = 7;
  PaperAnimation a = test::grid_sheet(nx, nx);
  a.frame_rate = 60;
  for (std::uint32_t f = 0; f < frames; ++f)
    for (std::uint32_t j = 0; j < nx; ++j)
      for (std::uint32_t i = 0; i < nx; ++i) {
        a.positions.push_back(float(d - W / 2 + W * i / (nx - 1)));
        a.positions.push_back(float(-0.04 + W * j / (nx - 1) + speed * f / 60));
        a.positions.push_back(0.001f);
      }
  a.obstacles.push_back({"table", {0, 0, 0}, {0, 0, 1}, "wood"});
  a.listener.position = {0.6, 0, 0.3};
  a.listener.forward = {-1, 0, 0};
  validate(a, "test");
  const PaperSoundDb db = impulse_db();
  PaperSynthOptions o;
  o.tail_seconds = 0;
  const AudioBuffer open = render_paper(a, &db, nullptr, o);
  a.obstacles.push_back({"wall", {0, 0, 0}, {1, 0, 0}, "wood"});
  const AudioBuffer walled = render_paper(a, &db, nullptr, o);
  const auto ears = ear_positions(a.listener);
  for (int ear = 0; ear < 2; ++ear) {
    std::vector<float> x0, x1;
    for (std::size_t t = 4096; t < open.frames(); ++t) {
      x0.push_back(open.samples[2 * t + ear]);
      x1.push_back(walled.samples[2 * t + ear]);
    }
    const auto s0 = friction_spectrum(x0), s1 = friction_spectrum(x1);
    // The sheet's centre at mid-animation; its image behind the wall at x = -d.
    const Vec3 y{d, -0.04 + W / 2 + speed * frames / 120, 0.001}, yi{-d, y[1], y[2]};
    const double delta = norm(sub(ears[ear], yi)) - norm(sub(ears[ear], y));
    auto ratio_at = [&](double f) {
      const std::size_t k = std::size_t(std::lround(f / (44100.0 / 4096)));
      return s1[k] / s0[k];
    };
    for (int k = 0; k < 3; ++k) {
      const double notch = (k + 0.5) * 343 / delta, peak = (k + 1) * 343 / delta;
      // The deepest point within +-15% of the prediction lies within 3% of it.
      double best = 1e9, best_f = 0;
      for (double f = 0.85 * notch; f <= 1.15 * notch; f += 44100.0 / 4096)
        if (ratio_at(f) < best) best = ratio_at(f), best_f = f;
      EXPECT_NEAR(best_f, notch, 0.03 * notch) << "ear " << ear << " notch " << k;
      EXPECT_LT(best, 0.35 * ratio_at(peak)) << "ear " << ear << " notch " << k;
    }
  }
}

// Onsets: 128-sample windows whose energy jumps 10x over the previous 16 windows' mean
// (silence before the start).
std::vector<double> onsets(const AudioBuffer& a) {
  const std::size_t w = 128, n = a.frames() / w;
  std::vector<double> e(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t t = i * w; t < (i + 1) * w; ++t)
      for (int c = 0; c < a.channels; ++c)
        e[i] += double(a.samples[t * a.channels + c]) * a.samples[t * a.channels + c];
  const double floor = 1e-6 * *std::max_element(e.begin(), e.end());
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) {
    double mean = 0;
    for (std::size_t k = i < 16 ? 0 : i - 16; k < i; ++k) mean += e[k] / 16;
    if (e[i] > floor && e[i] > 10 * std::max(mean, floor)) {
      out.push_back(double(i * w) / a.sample_rate);
      i += 16;  // refractory
    }
  }
  return out;
}

class ShippedExamples : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedExamples, SoundsStartAtTheEventFrames) {
  const std::string mode = GetParam();
  static const PaperSoundDb db = generate_paper_database(small_db());
  CpuFilterbankOptions fo;
  fo.channels = 2;
  fo.capacity = 1 << 16;
  fo.threads = 1;
  CpuFilterbank fb(fo);
  for (const std::string n : {"slide", "shake", "flap", "crumple"}) {
    const PaperAnimation a =
        load_paper_animation(CHLADNI_SOURCE_DIR "/meshes/paper/" + n + ".json");
    PaperSynthOptions o;
    o.mode = parse_paper_mode(mode);
    PaperRenderReport rep;
    const AudioBuffer out = render_paper(a, &db, &fb, o, &rep);
    EXPECT_EQ(rep.frames, a.frame_count());
    const std::vector<double> got = onsets(out);
    const double frame = 1 / a.frame_rate;
    auto onset_near = [&](double t, double early, double late) {
      for (double g : got)
        if (g >= t - early && g <= t + late) return true;
      return false;
    };
    if (n == "slide") {
      // Rubbing from frame 1 to the end: one onset at the start (one 2048-sample buffer of
      // latency at most), the sound lasting until the last frame.
      ASSERT_FALSE(got.empty()) << n;
      EXPECT_NEAR(got.front(), a.event_frames.front() * frame, 2048.0 / 44100 + frame) << n;
      const std::size_t last = std::size_t(a.event_frames.back() * frame * 44100);
      double level = 0;
      for (std::size_t t = last - 4410; t < last; ++t) level += std::abs(out.samples[2 * t]);
      EXPECT_GT(level / 4410, 1e-3) << n;
      continue;
    }
    PaperAnalyzer an(a);
    std::vector<double> crumples;
    for (std::uint32_t f = 0; f < a.frame_count(); ++f)
      if (!an.analyze(f).events.empty()) crumples.push_back(f * frame);
    ASSERT_FALSE(crumples.empty()) << n;
    // Each crumple with no other in the 0.2 s before (most of a burst's length: later clicks of a
    // burst are onsets of their own) is heard within a frame, plus the flight time.
    int isolated = 0;
    for (std::size_t i = 0; i < crumples.size(); ++i) {
      if (i > 0 && crumples[i] - crumples[i - 1] < 0.2) continue;
      ++isolated;
      EXPECT_TRUE(onset_near(crumples[i], 0.003, frame + 0.005))
          << n << " " << mode << ": nothing heard at " << crumples[i] << " s";
    }
    EXPECT_GE(isolated, n == "crumple" ? 3 : 4) << n;
    // Every onset heard belongs to a crumpling event: it follows one by at most a burst.
    for (double t : got) {
      bool ok = false;
      for (double c : crumples) ok |= t >= c - 0.003 && t <= c + frame + 0.255;
      EXPECT_TRUE(ok) << n << " " << mode << ": onset at " << t << " s without an event";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Modes, ShippedExamples, ::testing::Values("database", "modal"));

TEST(PaperSynth, ModalVoicesAgreeOnCpuAndGpuAndAreDeterministic) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  const PaperAnimation a = load_paper_animation(CHLADNI_SOURCE_DIR "/meshes/paper/crumple.json");
  PaperSynthOptions o;
  o.mode = PaperSynthMode::Modal;
  CpuFilterbankOptions co;
  co.channels = 2;
  co.capacity = 1 << 16;
  CpuFilterbank cpu(co);
  GpuFilterbankOptions go;
  go.channels = 2;
  go.capacity = 1 << 16;
  go.max_frames = 1024;
  GpuFilterbank gpu(ctx, go);
  const AudioBuffer c = render_paper(a, nullptr, &cpu, o);
  const AudioBuffer g = render_paper(a, nullptr, &gpu, o);
  const double peak = test::max_abs(c.samples);
  ASSERT_GT(peak, 0);
  EXPECT_LT(test::max_diff(c.samples, g.samples), 1e-4 * peak);
  CpuFilterbank cpu2(co);
  EXPECT_EQ(render_paper(a, nullptr, &cpu2, o).samples, c.samples);
  o.seed = 2;
  CpuFilterbank cpu3(co);
  EXPECT_GT(test::max_diff(render_paper(a, nullptr, &cpu3, o).samples, c.samples), 0.01 * peak);
}

TEST(PaperSynth, RejectsWhatItCannotPlay) {
  const PaperAnimation a = load_paper_animation(CHLADNI_SOURCE_DIR "/meshes/paper/slide.json");
  PaperSoundDb db = impulse_db();
  db.entries[0].friction.clear();
  db.entries[1].friction = {{"glass", {std::vector<float>(kFrictionBins, 0.01f)}}};
  try {
    render_paper(a, &db, nullptr, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("surface 'wood'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("it has: glass"), std::string::npos) << e.what();
  }
  EXPECT_THROW(render_paper(a, nullptr, nullptr, {}), InputError);
  PaperSynthOptions o;
  o.mode = PaperSynthMode::Modal;
  EXPECT_THROW(render_paper(a, nullptr, nullptr, o), InputError);
  EXPECT_THROW(parse_paper_mode("granular"), InputError);
  o = {};
  o.crumple_reference = std::nan("");
  EXPECT_THROW(render_paper(a, &db, nullptr, o), InputError);
}

TEST(PaperCli, RendersWavAndSpectrogram) {
  const std::string dir = test::temp_path("paper_cli_sound");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string exe = CHLADNI_EXE;
  const std::string db = dir + "/db";
  ASSERT_EQ(std::system((exe + " paper-db generate -o " + db +
                         " --variants 1 --clip-seconds 0.1 --friction-seconds 0.2 > /dev/null")
                            .c_str()),
            0);
  const std::string wav = dir + "/flap.wav", png = dir + "/flap.png";
  ASSERT_EQ(std::system((exe + " paper " CHLADNI_SOURCE_DIR "/meshes/paper/flap.json -o " + wav +
                         " --db " + db + " --paper-mode both --spectrogram " + png +
                         " --listener 0,-0.4,0.3 > /dev/null")
                            .c_str()),
            0);
  const AudioBuffer audio = read_audio(wav);
  EXPECT_EQ(audio.channels, 2);
  EXPECT_EQ(audio.sample_rate, 44100);
  EXPECT_GT(test::max_abs(audio.samples), 1e-3);
  std::ifstream f(png, std::ios::binary);
  std::string head(24, '\0');
  f.read(head.data(), 24);
  EXPECT_EQ(head.substr(1, 3), "PNG");
  const auto be32 = [&](int o) {
    return (unsigned(std::uint8_t(head[o])) << 24) | (unsigned(std::uint8_t(head[o + 1])) << 16) |
           (unsigned(std::uint8_t(head[o + 2])) << 8) | unsigned(std::uint8_t(head[o + 3]));
  };
  EXPECT_EQ(be32(16),
            unsigned(chladni::plot::kSoundFigureWidth));  // the labelled figure (test_plot)
  EXPECT_EQ(be32(20), unsigned(chladni::plot::kSoundFigureHeight));
  // Bad input: named, exit code 2.
  for (const std::string& bad : {std::string(" --paper-mode granular"), " --db " + dir + "/nodb",
                                 std::string(" --listener 0,nan,0")}) {
    const int status =
        std::system((exe + " paper " CHLADNI_SOURCE_DIR "/meshes/paper/flap.json -o " + wav + bad +
                     " > /dev/null 2>&1")
                        .c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2) << bad;
  }
}

}  // namespace
