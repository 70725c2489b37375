// Estimation speed (docs/PERFORMANCE.md, "Estimation"): feature extraction on each bundled
// recording and on a 3 s strike, and the full hybrid-model fit of an N-mode object (default
// 1,000 modes) to a strike synthesized from known parameters with noise at 30 dB SNR, with the
// recovered gamma and damping curve's error.
// Usage: chladni_estimate_bench [--modes N] [--recordings DIR] [--json OUT]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <string>

#include "chladni/estimate/damping_fit.hpp"
#include "chladni/estimate/features.hpp"
#include "chladni/estimate/material_fit.hpp"
#include "chladni/estimate/recording.hpp"

using namespace chladni;
using clock_type = std::chrono::steady_clock;

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

double since(clock_type::time_point t0) {
  return std::chrono::duration<double>(clock_type::now() - t0).count();
}

// Median wall time of `runs` calls.
template <class F>
double timed(int runs, F&& f) {
  std::vector<double> t;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = clock_type::now();
    f();
    t.push_back(since(t0));
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

// An object of n modes at the reference material: a plate-like density (f_i ~ 80 Hz (i+1)^0.9,
// jittered) and amplitudes that fall as 1/sqrt(f) with a random spread of +-10 dB.
estimate::StruckModes object(std::size_t n) {
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), spread(-1, 1);
  estimate::StruckModes m;
  m.gamma = 200e9 / 7850;
  for (std::size_t i = 0; i < n; ++i) {
    const double f = 80 * std::pow(double(i + 1) + jitter(gen), 0.9);
    m.omega.push_back(kTwoPi * f);
    m.amplitude.push_back(std::pow(10.0, 0.5 * spread(gen)) / std::sqrt(f));
  }
  return m;
}

void usage() {
  std::fprintf(stderr,
               "usage: chladni_estimate_bench [--modes N] [--recordings DIR] [--json OUT]\n");
}

// Feature extraction on the bundled recordings: a table row each, and out["features"].
void feature_rows(const std::string& dir, nlohmann::json& out) {
  std::printf("%-22s %8s %9s %10s %10s\n", "features of", "seconds", "partials", "explained",
              "time (s)");
  for (const char* name : {"glockenspiel_C6", "marimba_C4", "xylophone_C5", "woodblock_C4"}) {
    const double end = std::strcmp(name, "glockenspiel_C6") ? 0.0 : 0.798;
    const auto rec = estimate::read_recording(dir + "/" + name + ".wav", {0, end});
    estimate::FeatureSet set;
    const double t =
        timed(5, [&] { set = estimate::extract_features(rec.samples, rec.sample_rate, {}); });
    std::printf("%-22s %8.3f %9zu %9.1f%% %10.4f\n", name,
                double(rec.samples.size()) / rec.sample_rate, set.features.size(),
                100 * set.explained, t);
    out["features"][name] = {{"seconds", double(rec.samples.size()) / rec.sample_rate},
                             {"partials", set.features.size()},
                             {"time_s", t}};
  }
}

// A 3 s strike of the N-mode object in a known material (frequencies x s: gamma x s^2), damping
// `truth`, a 0.3 ms contact, noise 30 dB below the first second's rms.
std::vector<double> noisy_strike(const estimate::StruckModes& m, double s,
                                 const DampingModel& truth, double fs) {
  auto partials = estimate::model_partials(m, s, 1.0, 3e-4, truth, 0.45 * fs);
  std::vector<estimate::Feature> sines;
  for (const auto& p : partials)
    sines.push_back({p.frequency, p.decay, p.amplitude, -0.5 * std::numbers::pi});
  std::vector<double> x = estimate::synthesize(sines, fs, std::size_t(3 * fs));
  double rms = 0;
  for (std::size_t i = 0; i < std::size_t(fs); ++i) rms += x[i] * x[i];
  rms = std::sqrt(rms / fs);
  std::mt19937 gen(5);
  std::normal_distribution<double> noise(0.0, rms * std::pow(10.0, -1.5));
  for (double& v : x) v += noise(gen);
  return x;
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t modes = 1000;
  std::string dir = CHLADNI_SOURCE_DIR "/recordings", json_path;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--modes") && i + 1 < argc) {
      modes = std::stoul(argv[++i]);
    } else if (!std::strcmp(argv[i], "--recordings") && i + 1 < argc) {
      dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--json") && i + 1 < argc) {
      json_path = argv[++i];
    } else {
      usage();
      return 2;
    }
  }
  nlohmann::json out;
  feature_rows(dir, out);

  const double fs = 48000;
  const estimate::StruckModes m = object(modes);
  const DampingModel truth{DampingModel::Kind::Hybrid, {1.5, 1e-9, 1e-3, 0.4}};
  const double s_true = 0.8;
  const std::vector<double> x = noisy_strike(m, s_true, truth, fs);

  estimate::FeatureSet set;
  const double t_features = timed(3, [&] { set = estimate::extract_features(x, fs, {}); });
  std::printf("%-22s %8.3f %9zu %9.1f%% %10.4f\n", "3 s strike", 3.0, set.features.size(),
              100 * set.explained, t_features);
  const estimate::DampingFit curve =
      estimate::fit_damping(set.features, estimate::damping_kind("hybrid"));
  estimate::MaterialFitOptions o;
  o.shape = estimate::damping_kind("hybrid");
  estimate::MaterialFit fit;
  const auto t0 = clock_type::now();
  fit = estimate::fit_material(x, fs, set, m, curve, o);
  const double t_fit = since(t0);
  double worst = 0;
  for (double f = 100; f <= 10000; f *= 1.1)
    worst = std::max(
        worst, std::abs(fit.damping.coefficient(kTwoPi * f) / truth.coefficient(kTwoPi * f) - 1));
  const double gamma_error = fit.gamma / (m.gamma * s_true * s_true) - 1;
  std::printf(
      "hybrid fit of %zu modes: %.2f s (%zu evaluations, %zu starts); gamma %+.2f%%, "
      "damping curve within %.2f%% over 100 Hz-10 kHz; %s\n",
      modes, t_fit, fit.evaluations, fit.starts_tried, 100 * gamma_error, 100 * worst,
      fit.damping.to_string().c_str());
  out["fit"] = {{"modes", modes},
                {"time_s", t_fit},
                {"evaluations", fit.evaluations},
                {"starts", fit.starts_tried},
                {"gamma_error", gamma_error},
                {"curve_error", worst},
                {"features_time_s", t_features},
                {"partials", set.features.size()}};
  if (!json_path.empty()) std::ofstream(json_path) << out.dump(2) << "\n";
  return 0;
}
