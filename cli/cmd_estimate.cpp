// chladni estimate RECORDING: the partials of a recorded strike, the damping curve through them
// and, with a soundbank, the material (specific modulus, amplitude scale, damping) that makes the
// object sound like the recording.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/material.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/estimate/damping_fit.hpp"
#include "chladni/estimate/features.hpp"
#include "chladni/estimate/material_fit.hpp"
#include "chladni/estimate/recording.hpp"
#include "chladni/estimate/struck_modes.hpp"
#include "chladni/precompute.hpp"
#include "commands.hpp"
#include "estimate_plot.hpp"

namespace chladni::cli {
namespace {

struct EstimateArgs {
  std::vector<std::string> recordings;
  std::string damping = "power", json_path, resynth, bank, mesh, listener, material, save_material,
              hit_point, plot;
  double start = 0, end = 0, explained = 0.9, min_freq = 20, max_freq = 0, rho = 0, nu = 0;
  std::size_t max_features = 64, hit_vertex = 0, starts = 4, mesh_modes = 60;
  bool quiet = false, hit_given = false;
};

nlohmann::json feature_json(const estimate::Feature& f) {
  return {{"frequency_hz", f.frequency},
          {"frequency_sigma_hz", f.frequency_sigma},
          {"decay_per_s", f.decay},
          {"decay_sigma_per_s", f.decay_sigma},
          {"damping_ratio", f.damping_ratio()},
          {"amplitude", f.amplitude},
          {"phase_rad", f.phase},
          {"energy_share", f.energy_share},
          {"window", f.window},
          {"frames", f.frames}};
}

void print_features(const estimate::FeatureSet& set) {
  std::printf("%4s %11s %9s %10s %9s %12s %10s %7s\n", "#", "freq (Hz)", "+-", "decay (1/s)", "+-",
              "damp. ratio", "amplitude", "energy");
  for (std::size_t i = 0; i < set.features.size(); ++i) {
    const auto& f = set.features[i];
    std::printf("%4zu %11.2f %9.3f %10.3f %9.3f %12.3e %10.3e %6.1f%%\n", i, f.frequency,
                f.frequency_sigma, f.decay, f.decay_sigma, f.damping_ratio(), f.amplitude,
                100 * f.energy_share);
  }
}

// The object whose modes explain the recording: a soundbank, or a mesh solved here in the
// material given (steel by default: only gamma's ratio to it matters).
struct StruckObject {
  ModalModel model;
  Material material;
  std::string origin;
};

StruckObject load_object(const EstimateArgs& a) {
  StruckObject o;
  if (!a.bank.empty()) {
    const Soundbank bank = read_soundbank(a.bank);
    o.model = to_modal_model(bank, "object");
    o.material = bank.material;
    o.origin = a.bank;
  } else {
    precompute::PrecomputeOptions po;
    if (!a.material.empty()) po.material = find_material(a.material);
    po.max_modes = a.mesh_modes;
    po.transfer = false;
    precompute::PrecomputeReport report;
    if (!a.quiet) std::printf("solving the modes of %s ...\n", a.mesh.c_str());
    const Soundbank bank = precompute::precompute_mesh(a.mesh, po, report);
    o.model = to_modal_model(bank, "object");
    o.material = bank.material;
    o.origin = a.mesh;
  }
  if (a.rho > 0) o.material.density = a.rho;
  if (a.nu > 0) o.material.poisson_ratio = a.nu;
  return o;
}

// The struck surface point: --hit-vertex, or the one nearest --hit-point.
std::size_t hit_of(const StruckObject& o, const EstimateArgs& a) {
  if (!a.hit_point.empty()) return o.model.nearest_point(parse_vec3(a.hit_point, "--hit-point"));
  return a.hit_vertex;
}

Vec3 listener_for(const StruckObject& o, std::size_t hit, const EstimateArgs& a) {
  if (!a.listener.empty()) return parse_vec3(a.listener, "--listener");
  // A metre out along the struck point's normal.
  const std::size_t p = std::min(hit, o.model.points.size() - 1);
  return add(o.model.points[p], o.model.normals[p]);
}

estimate::FeatureSet features_of(const estimate::Recording& rec, const EstimateArgs& a,
                                 double& seconds) {
  estimate::FeatureOptions fo;
  fo.explained = a.explained;
  fo.max_features = a.max_features;
  fo.min_frequency = a.min_freq;
  fo.max_frequency = a.max_freq;
  const auto t0 = std::chrono::steady_clock::now();
  estimate::FeatureSet set = estimate::extract_features(rec.samples, rec.sample_rate, fo);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (set.features.empty())
    throw InputError("recording " + rec.origin + ": no partial stands above the noise");
  return set;
}

nlohmann::json modes_json(const std::vector<estimate::Partial>& modes) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : modes)
    out.push_back(
        {{"frequency_hz", p.frequency}, {"decay_per_s", p.decay}, {"amplitude", p.amplitude}});
  return out;
}

nlohmann::json material_json(const estimate::MaterialFit& fit, const Material& m) {
  return {{"gamma_m2_s2", fit.gamma},
          {"frequency_scale", fit.frequency_scale},
          {"amplitude_scale", fit.amplitude_scale},
          {"contact_time_s", fit.contact_time},
          {"E_pa", m.youngs_modulus},
          {"nu", m.poisson_ratio},
          {"rho_kg_m3", m.density},
          {"damping", fit.damping.to_string()},
          {"search_damping", fit.search_damping.to_string()},
          {"matched_partials", fit.matched_partials},
          {"metric", {{"psycho", fit.psycho}, {"mrp", fit.mrp}, {"hybrid", fit.hybrid}}},
          {"evaluations", fit.evaluations},
          {"starts", fit.starts_tried},
          {"modes_in_band", fit.modes.size()},
          {"modes", modes_json(fit.modes)}};
}

void check_args(const EstimateArgs& a) {
  if (a.recordings.empty()) throw InputError("name a recording (WAV, FLAC, ...)");
  if (!a.bank.empty() && !a.mesh.empty()) throw InputError("give --bank or --mesh, not both");
  const bool object = !a.bank.empty() || !a.mesh.empty();
  if (object && a.hit_given == !a.hit_point.empty())
    throw InputError(
        "give the struck surface point, --hit-vertex or --hit-point (not both), with " +
        std::string(a.bank.empty() ? "--mesh" : "--bank"));
  if (!object && (a.hit_given || !a.hit_point.empty() || !a.listener.empty()))
    throw InputError("--hit-vertex, --hit-point and --listener need --bank or --mesh");
  if (!a.save_material.empty() && !object)
    throw InputError("--save-material needs an object (--bank or --mesh) to find E from");
  if (a.recordings.size() > 1 && (object || !a.resynth.empty()))
    throw InputError(
        "several recordings share one damping curve; --bank, --mesh and --resynth "
        "take one recording");
  if (!a.json_path.empty()) check_output_path(a.json_path, "--json");
  if (!a.resynth.empty()) check_output_path(a.resynth, "--resynth");
  if (!a.plot.empty()) check_output_path(a.plot, "--plot");
  if (!a.save_material.empty()) check_material_name(a.save_material);
}

// One recording read, checked and analysed.
struct Analysed {
  estimate::Recording rec;
  estimate::FeatureSet set;
  double seconds = 0;
};

Analysed analyse(const std::string& file, const EstimateArgs& a) {
  Analysed out;
  out.rec = estimate::read_recording(file, {a.start, a.end});
  estimate::check_recording(out.rec);
  if (out.rec.clipped > 0 && !a.quiet)
    std::fprintf(stderr, "warning: %s: %zu samples are clipped; analysis starts after the last\n",
                 file.c_str(), out.rec.clipped);
  out.set = features_of(out.rec, a, out.seconds);
  if (!a.quiet) {
    const auto& rec = out.rec;
    std::printf(
        "%s: %.3f s at %g Hz (%d channel%s), strike at %.3f s; %zu partials explain "
        "%.1f%% of the energy (%.3f s)\n",
        file.c_str(), double(rec.samples.size()) / rec.sample_rate, rec.sample_rate, rec.channels,
        rec.channels == 1 ? "" : "s, mixed to mono",
        double(out.set.origin) / rec.sample_rate + a.start, out.set.features.size(),
        100 * out.set.explained, out.seconds);
    print_features(out.set);
  }
  return out;
}

nlohmann::json recording_json(const Analysed& an, const EstimateArgs& a) {
  const auto& rec = an.rec;
  nlohmann::json features = nlohmann::json::array();
  for (const auto& f : an.set.features) features.push_back(feature_json(f));
  return {{"file", rec.origin},
          {"sample_rate_hz", rec.sample_rate},
          {"channels", rec.channels},
          {"clipped_samples", rec.clipped},
          {"start_s", a.start},
          {"strike_s", double(an.set.origin) / rec.sample_rate + a.start},
          {"analysed_s", an.set.duration},
          {"explained", an.set.explained},
          {"features_time_s", an.seconds},
          {"features", features}};
}

// The material of the struck object; fills j["object"], j["material"] and the resynthesis.
DampingModel fit_object(const EstimateArgs& a, const DampingModel& shape,
                        const estimate::Recording& rec, const estimate::FeatureSet& set,
                        const estimate::DampingFit& curve, nlohmann::json& j,
                        std::vector<estimate::Feature>& sound) {
  const StruckObject obj = load_object(a);
  const std::size_t hit = hit_of(obj, a);
  const estimate::StruckModes modes =
      estimate::struck_modes(obj.model, hit, listener_for(obj, hit, a),
                             obj.material.youngs_modulus / obj.material.density);
  estimate::MaterialFitOptions mo;
  mo.shape = shape;
  mo.starts = a.starts;
  mo.max_frequency = a.max_freq;
  const auto t0 = std::chrono::steady_clock::now();
  const estimate::MaterialFit fit =
      estimate::fit_material(rec.samples, rec.sample_rate, set, modes, curve, mo);
  const double t_fit = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Material m = obj.material;
  m.name = a.save_material.empty() ? "estimated" : a.save_material;
  m.youngs_modulus = fit.gamma * m.density;
  m.damping = fit.damping;
  m.source = "estimated by chladni estimate from " + rec.origin + " struck on " + obj.origin +
             " (vertex " + std::to_string(hit) + "); nu and rho assumed";
  if (!a.quiet)
    std::printf(
        "material: gamma = E/rho %.4g m^2/s^2 (frequencies x %.4f of %s's), E %.4g Pa at "
        "rho %g; contact %.3g ms; damping %s (%zu partials); metric %.4g (psycho %.4g, "
        "MRP %.3f); %zu evaluations from %zu starts in %.2f s\n",
        fit.gamma, fit.frequency_scale, obj.material.name.c_str(), m.youngs_modulus, m.density,
        1e3 * fit.contact_time, fit.damping.to_string().c_str(), fit.matched_partials, fit.hybrid,
        fit.psycho, fit.mrp, fit.evaluations, fit.starts_tried, t_fit);
  j["object"] = {{"file", obj.origin},
                 {"hit_vertex", hit},
                 {"modes", modes.omega.size()},
                 {"reference_material", obj.material.name}};
  j["material"] = material_json(fit, m);
  j["timing_s"]["fit"] = t_fit;
  sound.clear();
  for (const auto& p : fit.modes)  // struck: each mode starts as a sine
    sound.push_back({p.frequency, p.decay, p.amplitude, -0.5 * std::numbers::pi});
  if (!a.save_material.empty()) {
    save_user_material(m);
    if (!a.quiet)
      std::printf("saved material '%s' to %s\n", m.name.c_str(), user_materials_path().c_str());
  }
  return fit.damping;
}

void run_estimate(const EstimateArgs& a) {
  check_args(a);
  const DampingModel shape = estimate::damping_kind(a.damping);
  std::vector<Analysed> all;
  std::vector<estimate::Feature> pooled;
  for (const std::string& file : a.recordings) {
    all.push_back(analyse(file, a));
    pooled.insert(pooled.end(), all.back().set.features.begin(), all.back().set.features.end());
  }
  const estimate::DampingFit curve = estimate::fit_damping(pooled, shape);
  if (!a.quiet)
    std::printf("damping through the partials%s: %s (%zu partials, weighted rms error %.1f%%)\n",
                all.size() > 1 ? " of every recording" : "", curve.model.to_string().c_str(),
                curve.partials, 100 * curve.rms_relative_error);
  for (const auto& w : curve.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  nlohmann::json j;
  const Analysed& first = all.front();
  std::vector<estimate::Feature> sound = first.set.features;
  std::optional<DampingModel> material;
  if (!a.bank.empty() || !a.mesh.empty())
    material = fit_object(a, shape, first.rec, first.set, curve, j, sound);
  std::vector<double> resynthesized;
  if (!a.resynth.empty() || !a.plot.empty())
    resynthesized = estimate::synthesize(sound, first.rec.sample_rate, first.set.residual.size());
  if (!a.resynth.empty()) {
    AudioBuffer out;
    out.sample_rate = int(std::lround(first.rec.sample_rate));
    out.samples.assign(resynthesized.begin(), resynthesized.end());
    write_wav(a.resynth, out);
    if (!a.quiet) std::printf("wrote %s\n", a.resynth.c_str());
  }
  if (!a.plot.empty()) {
    EstimatePlot p;
    p.path = a.plot;
    p.title = first.rec.origin + (all.size() > 1 ? " and others" : "") + ": " +
              std::to_string(pooled.size()) + " partials, " + a.damping + " damping" +
              (material ? ", fitted on " + (a.bank.empty() ? a.mesh : a.bank) : "");
    p.recording = &first.rec;
    p.features = &first.set;
    p.resynthesized = std::move(resynthesized);
    for (const Analysed& an : all) p.pooled.push_back(&an.set);
    p.curve = curve.model;
    p.material = material ? &*material : nullptr;
    write_estimate_plot(p);
    if (!a.quiet) std::printf("wrote %s\n", a.plot.c_str());
  }
  if (!a.json_path.empty()) {
    for (const Analysed& an : all) j["recordings"].push_back(recording_json(an, a));
    j["damping_curve"] = {{"model", curve.model.to_string()},
                          {"partials", curve.partials},
                          {"rms_relative_error", curve.rms_relative_error},
                          {"scatter", curve.spread},
                          {"warnings", curve.warnings}};
    write_file_atomic(a.json_path, j.dump(2) + "\n", "--json");
    if (!a.quiet) std::printf("wrote %s\n", a.json_path.c_str());
  }
}

}  // namespace

void add_estimate(CLI::App& app) {
  auto a = std::make_shared<EstimateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "estimate", "Partials, damping and material from recordings of single strikes");
  cmd->add_option("recordings", a->recordings,
                  "WAV, FLAC, ... (channels are mixed to mono); several recordings of one "
                  "material share one damping curve");
  cmd->add_option("--damping", a->damping, "Model: rayleigh, caughey:K, power or hybrid")
      ->capture_default_str();
  cmd->add_option("--start", a->start, "Seconds into the file where analysis may begin")
      ->check(finite_in(0, 3600));
  cmd->add_option("--end", a->end, "Seconds into the file where analysis stops (0: the end)")
      ->check(finite_in(0, 3600));
  cmd->add_option("--explained", a->explained, "Share of the energy the partials must explain")
      ->check(finite_above(0, 1))
      ->capture_default_str();
  cmd->add_option("--max-partials", a->max_features, "At most this many partials")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--min-freq", a->min_freq, "Lowest partial (Hz)")
      ->check(finite_in(0, 1e5))
      ->capture_default_str();
  cmd->add_option("--max-freq", a->max_freq, "Highest partial (Hz; 0: 0.45 x the sample rate)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--bank", a->bank, "The struck object's soundbank");
  cmd->add_option("--mesh", a->mesh, "The struck object's mesh (its modes are solved here)");
  cmd->add_option("--hit-vertex", a->hit_vertex, "Surface point that was struck (bank or mesh)")
      ->check(CLI::Range(std::size_t(0), std::size_t(1) << 40))
      ->each([a](const std::string&) { a->hit_given = true; });
  cmd->add_option("--hit-point", a->hit_point, "... or the surface point nearest X,Y,Z (m)");
  cmd->add_option("--listener", a->listener,
                  "Microphone X,Y,Z (m, object frame; default 1 m along the hit normal)");
  cmd->add_option("--material", a->material, "--mesh: the reference material (default steel)");
  cmd->add_option("--mesh-modes", a->mesh_modes, "--mesh: modes to solve")
      ->check(CLI::Range(1, 2000))
      ->capture_default_str();
  cmd->add_option("--rho", a->rho, "Density for E = gamma rho (default: the object's)")
      ->check(finite_above(0, 1e5));
  cmd->add_option("--nu", a->nu, "Poisson's ratio to record (default: the object's)")
      ->check(finite_above(0, 0.499));
  cmd->add_option("--starts", a->starts, "Local searches from the best starting points")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--save-material", a->save_material,
                  "Save the fitted material under this name (chladni precompute --material NAME)");
  cmd->add_option("--json", a->json_path, "Write the partials and the fit as JSON");
  cmd->add_option("--resynth", a->resynth, "Write the resynthesized strike as WAV");
  cmd->add_option("--plot", a->plot,
                  "Write the recorded and resynthesized spectrograms and the damping curves as "
                  "PNG");
  cmd->add_flag("-q,--quiet", a->quiet, "Print nothing but errors");
  cmd->callback([a] { run_estimate(*a); });
}

}  // namespace chladni::cli
