// chladni precompute MESH -o BANK: the precompute pipeline from a closed mesh to a soundbank.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/precompute.hpp"
#include "chladni/precompute/blas_kernels.hpp"
#include "commands.hpp"
#include "parse_choices.hpp"
#include "progress.hpp"

namespace chladni::cli {
namespace {

// What the command line fills: the library's options directly where a flag is one of them, and
// the text and unit choices that become options in precompute_options.
struct PrecomputeArgs {
  precompute::PrecomputeOptions o;
  std::string mesh, output, unit = "m", material = "steel", damping, mass = "consistent", json_path;
  double scale = 1, E = NAN, nu = NAN, rho = NAN;
  std::string refinement = "local";
  double max_memory_gb = -1;  // negative: 80 % of the memory available
  std::string eigensolver = "block", transfer_backend = "auto", transfer_method = "auto";
  bool quiet = false, no_transfer = false;
};

// What --repair did, as recorded in the soundbank's META.
nlohmann::json repair_meta(const Soundbank& bank) {
  const auto meta = nlohmann::json::parse(bank.metadata_json, nullptr, false);
  return meta.is_object() && meta.contains("repair") ? meta["repair"] : nlohmann::json();
}

nlohmann::json summary_json(const PrecomputeArgs& a, const precompute::PrecomputeReport& r,
                            const Soundbank& bank) {
  nlohmann::json j;
  j["mesh"] = a.mesh;
  j["output"] = a.output;
  j["material"] = {{"name", bank.material.name},
                   {"E", bank.material.youngs_modulus},
                   {"nu", bank.material.poisson_ratio},
                   {"rho", bank.material.density},
                   {"damping", bank.material.damping.to_string()}};
  j["surface"] = {
      {"vertices", r.mesh.vertices},          {"triangles", r.mesh.triangles},
      {"volume_m3", r.mesh.volume},           {"cavities", r.mesh.cavities},
      {"simplified_from", r.simplified_from}, {"simplify_envelope_m", r.simplify_envelope}};
  j["repairs"] = r.repair.log;
  if (a.o.repair) j["repair"] = repair_meta(bank);
  j["volume_mesh"] = {{"tetrahedra", r.tets},
                      {"nodes", r.nodes},
                      {"dofs", r.dofs},
                      {"nonzeros", r.nonzeros},
                      {"element_order", a.o.order},
                      {"max_tet_volume_m3", r.max_tet_volume},
                      {"max_radius_edge", r.quality.max_radius_edge},
                      {"mean_radius_edge", r.quality.mean_radius_edge},
                      {"min_dihedral_deg", r.quality.min_dihedral_deg},
                      {"max_dihedral_deg", r.quality.max_dihedral_deg}};
  j["eigen"] = {{"factorization", r.eigen.factorization},
                {"blas_kernels", precompute::blas_core_name()},
                {"rigid_removed", r.eigen.rigid_removed},
                {"rigid_lambda", r.eigen.rigid_lambda},
                {"computed", r.computed},
                {"lanczos_runs", r.eigen.solves},
                {"operations", r.eigen.operations},
                {"capped", r.eigen.capped},
                {"max_residual", r.max_residual},
                {"factor_seconds", r.eigen.factor_seconds},
                {"lanczos_seconds", r.eigen.lanczos_seconds},
                {"solve_seconds", r.eigen.solve_seconds},
                {"factor_nonzeros", r.eigen.factor_entries},
                {"factor_bytes", r.eigen.factor_bytes},
                {"factor_flops", r.eigen.factor_flops},
                {"factor_seconds_estimate", r.eigen.factor_seconds_estimate},
                {"matrix_bytes", r.eigen.matrix_bytes},
                {"basis_bytes", r.eigen.basis_bytes}};
  j["modes"] = {{"kept", r.kept},
                {"overdamped", r.overdamped},
                {"below_band", r.below_band},
                {"above_band", r.above_band}};
  j["frequency_error_estimate"] = r.frequency_error;
  nlohmann::json passes = nlohmann::json::array();
  for (const auto& m : r.passes)
    passes.push_back({{"tetrahedra", m.tets},
                      {"dofs", m.dofs},
                      {"worst_error", m.worst_error},
                      {"max_tet_volume", m.max_tet_volume},
                      {"expected_modes", m.expected_modes},
                      {"seconds", m.seconds}});
  j["accuracy"] = {{"tolerance", a.o.tolerance},     {"max_meshes", a.o.max_passes},
                   {"refinement", a.refinement},     {"converged", r.converged},
                   {"reason", r.unconverged_reason}, {"meshes", passes}};
  nlohmann::json freqs = nlohmann::json::array();
  for (double w : bank.omega) freqs.push_back(w / (2 * std::numbers::pi));
  j["frequencies_hz"] = freqs;
  nlohmann::json stages = nlohmann::json::object();
  nlohmann::json peaks = nlohmann::json::object();
  for (const auto& s : r.stages) {
    stages[s.name] = s.seconds;
    if (s.peak_bytes > 0) peaks[s.name] = s.peak_bytes / 1048576.0;  // MiB, as peak_rss_mb
  }
  j["seconds"] = stages;
  j["peak_memory_mb"] = peaks;
  if (bank.transfer) {
    const auto& t = r.transfer_times;
    j["transfer"] = {
        {"kernels", r.transfer_kernels},
        {"modes", bank.transfer->mode_count()},
        {"coefficients", bank.transfer->coefficients.size()},
        {"poor_fits", r.poor_fits},
        {"max_held_out_error", r.max_held_out},
        {"thread_seconds", {{"matrices", t.matrix}, {"solve", t.solve}, {"expansion", t.expand}}}};
  }
  j["total_seconds"] = r.total_seconds;
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  // Linux reports KiB; the stages' resets of the high-water mark lower ru_maxrss to the last one's.
  j["peak_rss_mb"] = std::max(double(ru.ru_maxrss) / 1024.0, r.peak_bytes / 1048576.0);
  return j;
}

// The pipeline's options from the command line's.
precompute::PrecomputeOptions precompute_options(const PrecomputeArgs& a) {
  precompute::PrecomputeOptions o = a.o;
  o.scale = precompute::unit_scale(a.unit) * a.scale;
  o.material = find_material(a.material);
  if (!std::isnan(a.E) || !std::isnan(a.nu) || !std::isnan(a.rho))
    o.material.name = a.material + " (modified)";
  if (!std::isnan(a.E)) o.material.youngs_modulus = a.E;
  if (!std::isnan(a.nu)) o.material.poisson_ratio = a.nu;
  if (!std::isnan(a.rho)) o.material.density = a.rho;
  if (!a.damping.empty()) o.material.damping = DampingModel::parse(a.damping);
  o.material.validate();
  if (a.mass == "lumped")
    o.mass = precompute::MassKind::Lumped;
  else if (a.mass != "consistent")
    throw InputError("--mass must be consistent or lumped");
  o.local_refinement = a.refinement == "local";
  o.max_memory = a.max_memory_gb < 0 ? -1.0 : a.max_memory_gb * 1e9;
  o.mode_cap = std::max(o.mode_cap, o.max_modes);
  o.transfer = !a.no_transfer;
  o.acoustic.threads = o.acoustic.bem.threads = o.acoustic.wave.threads = o.threads;
  o.acoustic.method = parse_transfer_method(a.transfer_method, "--transfer-method");
  o.acoustic.validate();
  if (o.transfer) o.gpu = transfer_device(a.transfer_backend);
  if (a.eigensolver == "spectra")
    o.eigensolver = precompute::EigenOptions::Method::Spectra;
  else if (a.eigensolver != "block")
    throw InputError("--eigensolver must be block or spectra");
  return o;
}

// The summary a terminal run ends with.
void print_summary(const PrecomputeArgs& a, const precompute::PrecomputeReport& r,
                   const Soundbank& bank) {
  std::printf("mesh %s: %zu vertices, %zu triangles, volume %.4g m^3", a.mesh.c_str(),
              r.mesh.vertices, r.mesh.triangles, r.mesh.volume);
  if (r.simplified_from)
    std::printf(" (simplified from %zu triangles, within %.3g mm)", r.simplified_from,
                r.simplify_envelope * 1e3);
  if (r.mesh.cavities)  // hollow: the cavities' faces are meshed, not put in the soundbank
    std::printf(", hollow (%zu %s)", r.mesh.cavities, r.mesh.cavities == 1 ? "cavity" : "cavities");
  std::printf("\n");
  for (const auto& line : r.repair.log) std::printf("  repaired: %s\n", line.c_str());
  if (a.o.repair && r.repair.changed())
    std::printf(
        "  repair (%s): the surface moved up to %.3g mm (%.2f %% of its %.3g m size); "
        "volume %.4g -> %.4g m^3 (%+.2f %%%s)\n",
        precompute::to_string(r.repair.rung), r.repair.hausdorff * 1e3,
        100 * r.repair.hausdorff / r.repair.size, r.repair.size, r.repair.volume_input,
        r.repair.volume_repaired, 100 * r.repair.volume_change(),
        r.repair.input_closed ? "" : "; the input's volume estimated across its holes");
  std::printf("material %s: E %.4g Pa, nu %.3g, rho %.4g kg/m^3, damping %s\n",
              bank.material.name.c_str(), bank.material.youngs_modulus, bank.material.poisson_ratio,
              bank.material.density, bank.material.damping.to_string().c_str());
  std::printf(
      "tetrahedra %zu (P%d, %zu nodes, %zu DOFs, max volume %.3g m^3); quality: radius-edge max "
      "%.2f mean %.2f, dihedral angles %.1f-%.1f deg\n",
      r.tets, a.o.order, r.nodes, r.dofs, r.max_tet_volume, r.quality.max_radius_edge,
      r.quality.mean_radius_edge, r.quality.min_dihedral_deg, r.quality.max_dihedral_deg);
  std::string stopped = r.eigen.capped ? " (stopped at --mode-cap before --max-freq)" : "";
  if (a.o.max_modes > 0 && r.computed - r.below_band < a.o.max_modes)
    stopped = " (of the " + std::to_string(a.o.max_modes) + " asked for, those below --max-freq)";
  std::printf("eigen-solve (%s): %zu rigid modes removed, %zu elastic modes, max residual %.2g%s\n",
              r.eigen.factorization.c_str(), r.eigen.rigid_removed, r.computed, r.max_residual,
              stopped.c_str());
  if (!r.passes.empty()) {
    double worst_kept = 0;
    for (double x : r.frequency_error) worst_kept = std::max(worst_kept, x);
    std::printf(
        "accuracy: largest estimated frequency error %.2g %% (tolerance %.2g %%) after %zu "
        "mesh%s%s%s\n",
        100 * worst_kept, 100 * a.o.tolerance, r.passes.size(), r.passes.size() == 1 ? "" : "es",
        r.converged ? "" : "; not converged: ", r.converged ? "" : r.unconverged_reason.c_str());
  }
  std::printf("modes kept %zu; dropped: %zu overdamped, %zu below 20 Hz, %zu above %.0f Hz\n",
              r.kept, r.overdamped, r.below_band, r.above_band,
              std::min(a.o.max_frequency, a.o.sample_rate / 2));
  if (!bank.omega.empty()) {
    std::printf("lowest:");
    for (std::size_t i = 0; i < std::min<std::size_t>(8, bank.omega.size()); ++i)
      std::printf(" %.1f", bank.omega[i] / (2 * std::numbers::pi));
    std::printf(" Hz\n");
  }
  if (bank.transfer) {
    const auto& t = r.transfer_times;
    std::size_t by[3] = {0, 0, 0};  // sources, bem, wave
    for (const ModeTransfer& m : bank.transfer->modes) ++by[std::size_t(m.method) % 3];
    std::printf(
        "transfer (%s): %zu modes (%zu BEM, %zu wave, %zu sources), %zu poor fits (held-out "
        "error > %.0f%%), max held-out %.2g; thread-seconds: matrices %.2f, solve %.2f, "
        "expansion %.2f\n",
        r.transfer_kernels.c_str(), bank.transfer->mode_count(), by[1], by[2], by[0], r.poor_fits,
        100.0 * Transfer::kPoorFit, r.max_held_out, t.matrix, t.solve, t.expand);
  }
  std::printf("time:");
  for (const auto& s : r.stages) std::printf(" %s %.2f s,", s.name.c_str(), s.seconds);
  std::printf(" total %.2f s\n", r.total_seconds);
  if (r.peak_bytes > 0) {
    std::printf("peak memory:");
    for (const auto& s : r.stages)
      if (s.peak_bytes > 0) std::printf(" %s %.2f GB,", s.name.c_str(), s.peak_bytes / 1e9);
    std::printf(" largest %.2f GB\n", r.peak_bytes / 1e9);
  }
  std::printf("wrote %s\n", a.output.c_str());
}

void run_precompute(const PrecomputeArgs& a) {
  // Every output is checked before the work (minutes, sometimes) that fills it.
  check_output_path(a.output, "soundbank");
  if (!a.json_path.empty()) check_output_path(a.json_path, "--json");
  if (!a.o.save_surface.empty()) check_output_path(a.o.save_surface, "--save-surface");
  const precompute::PrecomputeOptions o = precompute_options(a);
  ProgressBar bar(a.quiet);
  precompute::Progress p;
  p.stage = [&](const std::string& s) { bar.stage(s); };
  p.fraction = [&](double f) { bar.fraction(f); };
  p.note = [&](const std::string& s) { bar.note(s); };
  precompute::PrecomputeReport r;
  const Soundbank bank = precompute::precompute_mesh(a.mesh, o, r, p);
  bar.finish();
  write_soundbank(a.output, bank);

  if (!a.json_path.empty())
    write_file_atomic(a.json_path, summary_json(a, r, bank).dump(2) + "\n", "--json");
  if (!a.quiet) print_summary(a, r, bank);
}

// The mesh, its units, the material and the elements.
void add_input_options(CLI::App* cmd, PrecomputeArgs* a) {
  cmd->add_option("mesh", a->mesh, "Closed triangle mesh")->required();
  cmd->add_option("-o,--output", a->output, "Soundbank to write")->required();
  cmd->add_option("--unit", a->unit, "Unit of the mesh coordinates: m, cm, mm")
      ->capture_default_str();
  cmd->add_option("--scale", a->scale, "Extra factor on the coordinates")
      ->check(finite_above(0, 1e12))
      ->capture_default_str();
  cmd->add_option("--material", a->material,
                  "Preset (chladni materials lists them), NAME or NAME:VARIANT")
      ->capture_default_str();
  cmd->add_option("--E", a->E, "Young's modulus (Pa), overrides the preset")
      ->check(finite_in(1e3, 1e13));
  cmd->add_option("--nu", a->nu, "Poisson's ratio, overrides the preset")
      ->check(finite_in(-1, 0.5));
  cmd->add_option("--rho", a->rho, "Density (kg/m^3), overrides the preset")
      ->check(finite_in(1, 1e5));
  cmd->add_option("--damping", a->damping,
                  "rayleigh:A1,A2 | caughey:A1,...,AN | power:A1,A2 | hybrid:R1,R2,P1,P2");
  cmd->add_option("--order", a->o.order, "Element order: 1 (linear) or 2 (quadratic)")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  cmd->add_option("--mass", a->mass, "Mass matrix: consistent or lumped")->capture_default_str();
}

// The repair ladder (docs/repair.md) and its limits.
void add_repair_options(CLI::App* cmd, PrecomputeArgs* a) {
  cmd->add_flag("--repair", a->o.repair,
                "Repair a mesh that is not a valid solid: local fixes, self-intersection removal, "
                "else an alpha wrap; reports how far the surface moved (docs/repair.md)");
  cmd->add_option("--max-hole-edges", a->o.repair_options.max_hole_edges,
                  "--repair fills holes up to this many edges")
      ->check(CLI::Range(3, 1000000))
      ->capture_default_str();
  cmd->add_option("--repair-alpha", a->o.repair_options.wrap_alpha,
                  "The wrap's ball radius (m, after --unit/--scale): gaps and holes narrower "
                  "close (0: the thinnest wall)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--repair-offset", a->o.repair_options.wrap_offset,
                  "How far outside the input the wrap lies (m; 0: a hundredth of the thinnest "
                  "wall)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--repair-max-distance", a->o.repair_options.max_distance,
                  "Refuse a wrap that moves the surface further than this fraction of its size")
      ->check(finite_in(1e-6, 1))
      ->capture_default_str();
  cmd->add_option("--repair-max-volume-change", a->o.repair_options.max_volume_change,
                  "Refuse a wrap that changes the volume by more than this fraction")
      ->check(finite_in(1e-6, 10))
      ->capture_default_str();
}

// What to compute, how accurately, within what memory; checking and repairing the surface.
void add_solver_options(CLI::App* cmd, PrecomputeArgs* a) {
  cmd->add_option("--max-modes", a->o.max_modes,
                  "Compute the first N elastic modes from 20 Hz to --max-freq (0: all below it)")
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--max-freq", a->o.max_frequency, "Highest frequency of interest (Hz)")
      ->check(finite_above(0, 1e6))
      ->capture_default_str();
  cmd->add_option("--sample-rate", a->o.sample_rate, "Drop modes above its Nyquist frequency (Hz)")
      ->check(finite_in(8000, 384000))
      ->capture_default_str();
  cmd->add_option("--max-tet-volume", a->o.max_tet_volume,
                  "Largest tetrahedron (m^3; 0: chosen by the solver, refining until the modes "
                  "asked for are within --tolerance)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--max-surface-triangles", a->o.max_surface_triangles,
                  "A surface of more triangles is simplified toward half as many before "
                  "meshing, within an envelope that moves no frequency by more than a fifth of "
                  "--tolerance (0: never; not with --max-tet-volume)")
      ->check(CLI::Range(std::size_t(0), std::size_t(100000000)))
      ->capture_default_str();
  cmd->add_option("--tolerance", a->o.tolerance,
                  "Target relative frequency error of every mode asked for, by the error "
                  "estimate; the mesh is refined where it asks (at most --max-meshes meshes)")
      ->check(finite_in(1e-4, 0.5))
      ->capture_default_str();
  cmd->add_option("--max-meshes", a->o.max_passes,
                  "Meshes solved at most while refining toward --tolerance (1: the first mesh "
                  "only, with its error estimate)")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cmd->add_option("--refinement", a->refinement,
                  "local: refine where the estimate puts the error (TetGen refining the last "
                  "mesh); uniform: mesh the whole solid again under a smaller bound")
      ->check(CLI::IsMember({"local", "uniform"}))
      ->capture_default_str();
  cmd->add_option("--max-memory", a->max_memory_gb,
                  "Memory the eigen-solve's factor, matrices and basis may take (GB; 0: no limit; "
                  "default "
                  "80 % of the memory available): larger problems are refused before the "
                  "factorization, with what they would need")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--mode-cap", a->o.mode_cap, "Most modes searched for below --max-freq")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--eigensolver", a->eigensolver,
                  "block (block Lanczos, default) or spectra (Spectra's Lanczos), same operator")
      ->capture_default_str();
  add_repair_options(cmd, a);
  cmd->add_option("--save-surface", a->o.save_surface,
                  "Write the checked (repaired, simplified) surface, the one meshed, as OBJ");
  cmd->add_option("--threads", a->o.threads, "Assembly threads (0: all cores)")
      ->check(thread_count())
      ->capture_default_str();
}

}  // namespace

void add_precompute(CLI::App& app, bool run) {
  auto a = std::make_shared<PrecomputeArgs>();
  CLI::App* cmd =
      app.add_subcommand("precompute", "Mesh (OBJ/OFF/PLY/STL) to modal soundbank (.chbank)");
  add_input_options(cmd, a.get());
  add_solver_options(cmd, a.get());
  cmd->add_option("--json", a->json_path, "Write a JSON summary (stages, timings, modes)");
  cmd->add_flag("-q,--quiet", a->quiet, "No progress and no summary");
  cmd->add_flag("--no-transfer", a->no_transfer,
                "Skip acoustic transfer (listener gains then use a compact-source estimate)");
  cmd->add_option("--transfer-order", a->o.acoustic.order,
                  "Multipole order L for every mode (0: per mode from k and the object's size)")
      ->check(CLI::Range(0, 40))
      ->capture_default_str();
  cmd->add_option("--transfer-max-sources", a->o.acoustic.max_sources,
                  "Most equivalent sources per mode")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option(
         "--transfer-method", a->transfer_method,
         "Radiated field per mode: bem (Burton-Miller boundary elements), wave (time-domain "
         "solve with mode conflation, docs/transfer.md), sources (equivalent-source fit) or auto "
         "(per mode: BEM where 6 elements per wavelength need at most 2000 elements, else the "
         "wave solve where its grid fits --max-memory, else BEM or sources)")
      ->capture_default_str();
  cmd->add_option("--transfer-backend", a->transfer_backend,
                  "Transfer kernels: auto (a real GPU if present, else CPU), cpu or gpu")
      ->capture_default_str();
  cmd->add_option("--sound-speed", a->o.acoustic.sound_speed, "Speed of sound in air (m/s)")
      ->check(finite_in(10, 1e4))
      ->capture_default_str();
  cmd->add_option("--air-density", a->o.acoustic.air_density, "Density of air (kg/m^3)")
      ->check(finite_in(1e-3, 1e4))
      ->capture_default_str();
  // Set by `chladni batch` only: recorded so a rerun knows this soundbank is current.
  cmd->add_option("--batch-stamp", a->o.batch_stamp)->group("")->check([](const std::string& s) {
    return s.size() == 32 && s.find_first_not_of("0123456789abcdef") == std::string::npos
               ? std::string()
               : std::string("expected 32 hex digits");
  });
  cmd->callback([a, run] {  // `a` lives as long as the parser that fills it
    if (run) run_precompute(*a);
  });
}

void add_materials(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "materials",
      "List the material presets (and your own, from chladni estimate) with their sources");
  cmd->callback([] {
    auto print = [](const Material& m) {
      std::printf("%-26s E %8.3g Pa  nu %.2f  rho %6.0f  %-30s %s\n", m.name.c_str(),
                  m.youngs_modulus, m.poisson_ratio, m.density, m.damping.to_string().c_str(),
                  m.source.c_str());
    };
    for (const Material& m : material_presets()) print(m);
    const auto own = user_material_presets();
    if (!own.empty()) std::printf("\nyours (%s):\n", user_materials_path().c_str());
    for (const Material& m : own) print(m);
  });
}

}  // namespace chladni::cli
