#include "chladni/precompute.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "chladni/core/error.hpp"
#include "chladni/core/version.hpp"
#include "chladni/precompute/mode_error.hpp"
#include "fem/surface_sample.hpp"
#include "peak_memory.hpp"
#include "solve_to_tolerance.hpp"
#include "surface/simplify_surface.hpp"
#include "surface/surface_pieces.hpp"

namespace chladni::precompute {

std::vector<std::array<float, 3>> vertex_normals(const SurfaceMesh& m) {
  std::vector<Vec3> acc(m.vertices.size(), Vec3{0, 0, 0});
  for (const auto& t : m.triangles) {
    const Vec3 n = triangle_normal(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
    for (uint32_t v : t)
      for (int k = 0; k < 3; ++k) acc[v][k] += n[k];
  }
  std::vector<std::array<float, 3>> out(acc.size());
  for (std::size_t v = 0; v < acc.size(); ++v) {
    const double l =
        std::sqrt(acc[v][0] * acc[v][0] + acc[v][1] * acc[v][1] + acc[v][2] * acc[v][2]);
    if (!(l > 0))
      throw InputError("surface vertex " + std::to_string(v) +
                       " belongs to no face of positive area");
    out[v] = {float(acc[v][0] / l), float(acc[v][1] / l), float(acc[v][2] / l)};
  }
  return out;
}

namespace {

std::string fmt_g(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

// The shift-invert's shift (Hz): 20 Hz, or below a large body's lowest modes. Shift-invert
// crowds modes far below the shift together (theta = 1 / (lambda - sigma) tends to -1 / sigma),
// and a 200 km beam's, at 0.6 mHz, never converged under 20 Hz. A free body's lowest mode lies
// above about a hundredth of c_shear / L except for slender or thin ones, whose modes still
// converge within a few hundred times the shift (a 170 m cow's 4.4 Hz under 20 Hz does).
double shift_for(const Material& m, const MeshReport& mesh) {
  double extent = 0;
  for (int k = 0; k < 3; ++k) extent = std::max(extent, mesh.bbox_max[k] - mesh.bbox_min[k]);
  const double scaled = 0.01 * m.shear_speed() / extent;
  return std::isfinite(scaled) && scaled > 0 ? std::min(EigenOptions{}.shift_hz, scaled)
                                             : EigenOptions{}.shift_hz;
}

// The surface meshed is the checked one, or where it is denser than max_surface_triangles a
// simplification of it, taken only if it is still a valid solid. Returns whether it was taken.
bool simplify_if_dense(SurfaceMesh& surface, const PrecomputeOptions& o, PrecomputeReport& r,
                       const Progress& p, Stopwatch& sw) {
  const std::size_t n = surface.triangles.size();
  // An alpha wrap is denser than its shape by construction (its facets round every convex edge
  // at the offset's radius), so it is simplified whatever its size.
  const bool wrapped = r.repair.rung == RepairRung::Wrap;
  if (o.max_surface_triangles == 0 || (n <= o.max_surface_triangles && !wrapped) ||
      o.max_tet_volume > 0)
    return false;
  sw.start("simplify surface");
  const double envelope = simplification_envelope(surface, o.tolerance);
  std::string why;
  if (envelope > 0) {
    try {
      SurfaceMesh simpler =
          simplify_surface(surface, std::min(n, o.max_surface_triangles) / 2, envelope, p.fraction);
      const MeshReport check = check_mesh(simpler);
      const bool valid = check.ok() && check.outer_pieces == r.mesh.outer_pieces &&
                         check.cavities == r.mesh.cavities;
      // A thin curved wall's envelope may allow few collapses: then the file's surface is kept.
      const bool fewer = double(simpler.triangles.size()) < 0.9 * double(n);
      if (valid && fewer) {
        r.simplified_from = n, r.simplify_envelope = envelope, r.mesh = check;
        surface = std::move(simpler);
        if (p.note)
          p.note("surface simplified from " + std::to_string(n) + " to " +
                 std::to_string(surface.triangles.size()) + " triangles, within " +
                 std::to_string(envelope * 1e3) + " mm of it (--max-surface-triangles)");
        return true;
      }
      why = !valid ? "the simplified surface is not a valid solid with the same pieces"
                   : "the envelope of " + std::to_string(envelope * 1e3) + " mm allows only " +
                         std::to_string(n - simpler.triangles.size()) + " fewer";
    } catch (const InputError& e) {
      why = e.what();
    }
  } else {
    why = "no thickness could be measured";
  }
  if (p.note) p.note("surface kept at " + std::to_string(n) + " triangles (" + why + ")");
  return false;
}

// The modes kept (damped, in the band) with their shapes on `surface`; refuses a bank with none.
Soundbank damped_bank(const SurfaceMesh& surface, const Eigen::MatrixXd& shapes,
                      const ModeErrors& errors, const std::string& origin,
                      const PrecomputeOptions& o, PrecomputeReport& r) {
  ModalModel model;
  for (double l : r.eigen.lambda) model.omega.push_back(std::sqrt(std::max(l, 0.0)));
  const ModeSelection sel =
      apply_damping(model, o.material.damping, o.min_frequency, o.max_frequency, o.sample_rate);
  r.overdamped = sel.overdamped, r.below_band = sel.below_band, r.above_band = sel.above_band;
  r.kept = sel.kept.size();
  if (sel.kept.empty()) {
    // The solve stops at max_frequency: with nothing below it, the lowest lies above.
    std::string lowest = model.omega.empty()
                             ? "above " + std::to_string(int(o.max_frequency)) + " Hz"
                             : std::to_string(model.omega[0] / (2 * std::numbers::pi)) + " Hz";
    throw InputError(origin + ": no mode lies in [" + std::to_string(int(o.min_frequency)) +
                     " Hz, " + std::to_string(int(std::min(o.max_frequency, o.sample_rate / 2))) +
                     " Hz] (lowest elastic mode: " + lowest + "; " +
                     std::to_string(sel.overdamped) +
                     " overdamped): check --unit/--scale, the material, or raise --max-freq");
  }
  for (std::size_t i : sel.kept) r.frequency_error.push_back(errors.relative[i]);

  Soundbank bank;
  bank.material = o.material;
  bank.vertices = surface.vertices;
  bank.triangles = surface.triangles;
  bank.normals = vertex_normals(surface);
  const std::size_t nv = surface.vertices.size();
  bank.shapes.reserve(sel.kept.size() * nv * 3);
  for (std::size_t i : sel.kept) {
    bank.omega.push_back(model.omega[i]);
    bank.decay.push_back(model.decay[i]);
    bank.residual.push_back(float(r.eigen.residual[i]));
    const auto col = shapes.col(Eigen::Index(i));
    for (std::size_t v = 0; v < nv; ++v)
      for (int k = 0; k < 3; ++k) bank.shapes.push_back(float(col(Eigen::Index(3 * v + k))));
  }
  return bank;
}

void add_transfer(Soundbank& bank, const SurfaceMesh& surface, double max_memory,
                  const std::string& origin, const PrecomputeOptions& o, PrecomputeReport& r,
                  const Progress& p) {
  const RadiatingSurface rs(surface, o.acoustic);
  std::unique_ptr<TransferKernels> kernels =
      o.gpu ? make_gpu_transfer_kernels(o.gpu) : make_cpu_transfer_kernels(1);
  r.transfer_kernels = kernels->name();
  AcousticOptions acoustic = o.acoustic;
  if (acoustic.bem_max_memory <= 0) acoustic.bem_max_memory = max_memory;
  if (acoustic.wave.max_memory <= 0) acoustic.wave.max_memory = max_memory;
  if (!acoustic.wave.gpu) acoustic.wave.gpu = o.gpu;
  if (!acoustic.bem.gpu) acoustic.bem.gpu = o.gpu;  // BEM rows on the same device
  try {
    bank.transfer = compute_transfer(
        rs, bank, acoustic, *kernels, &r.transfer_times,
        [&](std::size_t done, std::size_t total) {
          if (p.fraction) p.fraction(double(done) / double(total));
        },
        p.note);
  } catch (const BudgetError& e) {
    throw BudgetError(origin + ": " + e.what());
  }
  r.poor_fits += bank.transfer->poor_fits();
  for (const ModeTransfer& m : bank.transfer->modes)
    r.max_held_out = std::max(r.max_held_out, double(m.held_out_error));
}

// What --repair did and how far it moved the surface (docs/repair.md), rounded for reading.
nlohmann::json repair_json(const RepairReport& r) {
  auto round = [](double x) { return std::isfinite(x) ? std::stod(fmt_g(x)) : -1.0; };
  nlohmann::json j = {{"rung", to_string(r.rung)},
                      {"size_m", round(r.size)},
                      {"hausdorff_m", round(r.hausdorff)},
                      {"input_to_repaired_m", round(r.to_repaired)},
                      {"repaired_to_input_m", round(r.to_input)},
                      {"volume_input_m3", round(r.volume_input)},
                      {"volume_repaired_m3", round(r.volume_repaired)},
                      {"volume_change", round(r.volume_change())},
                      {"input_closed", r.input_closed}};
  if (r.rung == RepairRung::Wrap)
    j["wrap"] = {{"alpha_m", round(r.alpha)},
                 {"offset_m", round(r.offset)},
                 {"thinnest_wall_m", round(r.thinnest)}};
  return j;
}

// The soundbank's META section: how it was made, for `chladni info` and the batch's stamp.
std::string metadata(const Soundbank& bank, const std::string& origin, const PrecomputeOptions& o,
                     const PrecomputeReport& r) {
  nlohmann::json meta;
  meta["generator"] = std::string("chladni ") + kVersion;
  if (!o.batch_stamp.empty()) meta["batch_stamp"] = o.batch_stamp;
  meta["source"] = origin;
  meta["element_order"] = o.order;
  meta["mass"] = o.mass == MassKind::Lumped ? "lumped" : "consistent";
  meta["max_frequency_hz"] = o.max_frequency;
  meta["sample_rate_hz"] = o.sample_rate;
  meta["tetrahedra"] = r.tets;
  meta["nodes"] = r.nodes;
  meta["max_tet_volume_m3"] = r.max_tet_volume;
  meta["tolerance"] = o.tolerance;
  meta["converged"] = r.converged;
  if (!r.frequency_error.empty()) {
    nlohmann::json e = nlohmann::json::array();
    for (double x : r.frequency_error)
      e.push_back(std::isfinite(x) ? nlohmann::json(std::round(x * 1e5) / 1e5) : nlohmann::json());
    meta["frequency_error_estimate"] = e;
  }
  meta["factorization"] = r.eigen.factorization;
  meta["modes_dropped"] = {
      {"overdamped", r.overdamped}, {"below_band", r.below_band}, {"above_band", r.above_band}};
  meta["repairs"] = r.repair.log;
  if (o.repair) meta["repair"] = repair_json(r.repair);
  if (r.simplified_from)  // the bank's surface is not the file's: strikes go by position
    meta["surface_simplified"] = {{"from_triangles", r.simplified_from},
                                  {"envelope_m", r.simplify_envelope}};
  if (o.transfer) {
    meta["transfer"] = {{"kernels", r.transfer_kernels},
                        {"order", o.acoustic.order == 0 ? nlohmann::json("auto")
                                                        : nlohmann::json(o.acoustic.order)},
                        {"max_sources", o.acoustic.max_sources},
                        {"poor_fits", r.poor_fits}};
    using M = AcousticOptions::Method;
    const M m = o.acoustic.method;
    std::size_t bem = 0, wave = 0;
    for (const ModeTransfer& t : bank.transfer->modes) {
      bem += t.method == TransferMethod::Bem;
      wave += t.method == TransferMethod::Wave;
    }
    meta["transfer"]["method"] = m == M::Auto   ? "auto"
                                 : m == M::Bem  ? "bem"
                                 : m == M::Wave ? "wave"
                                                : "sources";
    meta["transfer"]["bem_modes"] = bem;
    meta["transfer"]["wave_modes"] = wave;
  }
  return meta.dump();
}

}  // namespace

Soundbank precompute_mesh(const std::string& mesh_path, const PrecomputeOptions& o,
                          PrecomputeReport& r, const Progress& p) {
  const auto t0 = std::chrono::steady_clock::now();
  if (p.stage) p.stage("read mesh");
  reset_peak_memory();
  SurfaceMesh surface = read_mesh(mesh_path, o.scale);
  const auto read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double read_peak = peak_memory_bytes();
  Soundbank bank = precompute_surface(std::move(surface), mesh_path, o, r, p);
  r.stages.insert(r.stages.begin(), StageTime{"read mesh", read_s, read_peak});
  r.peak_bytes = std::max(r.peak_bytes, read_peak);
  r.total_seconds += read_s;
  return bank;
}

Soundbank precompute_surface(SurfaceMesh surface, const std::string& origin,
                             const PrecomputeOptions& o, PrecomputeReport& r, const Progress& p) {
  const auto t_begin = std::chrono::steady_clock::now();
  validate(o);
  Stopwatch sw(r, p);

  sw.start("check surface");
  if (o.repair) {
    try {
      r.repair = repair_mesh(surface, o.repair_options);
    } catch (const std::bad_alloc&) {
      throw BudgetError(origin + ": --repair ran out of memory (" +
                        std::to_string(surface.triangles.size()) +
                        " triangles); a larger --repair-alpha or --repair-offset makes a coarser "
                        "wrap");
    }
    if (p.note)
      for (const auto& line : r.repair.log) p.note("repair: " + line);
    if (!r.repair.refusal.empty())
      throw InputError(origin + ": --repair cannot make a valid solid of it: " + r.repair.refusal);
  }
  r.mesh = check_mesh(surface);
  if (!o.save_surface.empty()) write_obj(o.save_surface, surface);
  require_valid(r.mesh, origin, o.repair);
  if (simplify_if_dense(surface, o, r, p, sw) && !o.save_surface.empty())
    write_obj(o.save_surface, surface);

  EigenOptions eo;
  eo.modes = o.max_modes;
  eo.max_frequency = o.max_frequency;
  eo.min_frequency = o.min_frequency;
  eo.shift_hz = shift_for(o.material, r.mesh);
  eo.mode_cap = o.mode_cap;
  eo.method = o.eigensolver;
  eo.max_memory = o.max_memory < 0 ? default_memory_budget() : o.max_memory;
  SurfaceMesh first;
  FemPass fp = solve_to_tolerance(surface, o, eo, p, sw, r, first);
  r.quality = fp.quality;
  r.tets = fp.tets.tets.size();
  r.nodes = fp.nodes;
  r.dofs = fp.dofs;
  r.nonzeros = fp.nonzeros;
  r.eigen = std::move(fp.eigen);
  first = outer_surface(first);  // a hollow body's cavities neither radiate nor get struck
  const Eigen::MatrixXd shapes = sample_on_surface(fp.tets, r.eigen.vectors, first);
  surface = std::move(first);
  r.computed = r.eigen.lambda.size();
  for (double res : r.eigen.residual) r.max_residual = std::max(r.max_residual, res);

  sw.start("damping and soundbank");
  Soundbank bank = damped_bank(surface, shapes, fp.errors, origin, o, r);
  r.eigen.vectors.resize(0, 0);
  if (o.transfer) {
    sw.start("transfer");
    add_transfer(bank, surface, eo.max_memory, origin, o, r, p);
  }
  sw.stop();
  for (const StageTime& s : r.stages) r.peak_bytes = std::max(r.peak_bytes, s.peak_bytes);
  r.total_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_begin).count();
  bank.metadata_json = metadata(bank, origin, o, r);
  bank.validate();
  return bank;
}

}  // namespace chladni::precompute
