// chladni radiate MESH --freq HZ --velocity FILE|--pattern NAME --points FILE: the pressure a
// closed surface radiates for a prescribed normal velocity, by the same equivalent-source fit
// (and, with --via multipole, the same re-expansion) that precompute stores as transfer.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "chladni/core/error.hpp"
#include "chladni/core/number_table.hpp"
#include "chladni/core/output_file.hpp"
#include "chladni/core/spherical.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/precompute/acoustic_transfer.hpp"
#include "chladni/precompute/memory_budget.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/velocity_pattern.hpp"
#include "commands.hpp"
#include "parse_choices.hpp"

namespace chladni::cli {
namespace {

using cd = std::complex<double>;

struct RadiateArgs {
  std::string mesh, velocity, pattern, points, backend = "cpu", json_path, unit = "m",
                                               via = "sources", method = "auto";
  double freq = 0, scale = 1, sound_speed = 343.0, air_density = 1.204;
  int order = 0;
};

// "sphere-harmonic:l=2,m=0[,U=1]" or "uniform[:U=1]" (velocity_pattern.hpp).
std::vector<cd> pattern_velocity(const std::string& spec, const precompute::SurfaceMesh& mesh) {
  const auto colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  std::map<std::string, double> params{{"l", 0}, {"m", 0}, {"U", 1}};
  if (colon != std::string::npos) {
    std::stringstream ss(spec.substr(colon + 1));
    std::string kv;
    while (std::getline(ss, kv, ',')) {
      const auto eq = kv.find('=');
      char* end = nullptr;
      const double v = eq == std::string::npos ? NAN : std::strtod(kv.c_str() + eq + 1, &end);
      if (eq == std::string::npos || !params.count(kv.substr(0, eq)) || *end != '\0' ||
          !std::isfinite(v))
        throw InputError("--pattern: bad parameter '" + kv + "' (l=INT, m=INT, U=NUMBER)");
      params[kv.substr(0, eq)] = v;
    }
  }
  const int l = int(params["l"]), m = int(params["m"]);
  if (name != "sphere-harmonic" && name != "uniform")
    throw InputError("--pattern: unknown pattern '" + name + "' (sphere-harmonic, uniform)");
  if (name == "uniform") return precompute::uniform_velocity(mesh, params["U"]);
  if (l != params["l"] || m != params["m"]) throw InputError("--pattern: l and m must be integers");
  try {
    return precompute::harmonic_velocity(mesh, l, m, params["U"]);  // it checks their range
  } catch (const InputError& e) {
    throw InputError(std::string("--pattern: ") + e.what());
  }
}

precompute::SurfaceMesh read_radiating_mesh(const RadiateArgs& a) {
  const precompute::SurfaceMesh mesh =
      precompute::read_mesh(a.mesh, precompute::unit_scale(a.unit) * a.scale);
  const precompute::MeshReport checked = precompute::check_mesh(mesh);
  precompute::require_valid(checked, a.mesh, false);
  if (checked.cavities)  // the air touches the outer piece only
    throw InputError(a.mesh + ": the surface has " + std::to_string(checked.cavities) +
                     " inner pieces (cavities); radiate takes the outer surface alone");
  return mesh;
}

std::vector<cd> read_velocity(const RadiateArgs& a, const precompute::SurfaceMesh& mesh) {
  if (!a.pattern.empty()) return pattern_velocity(a.pattern, mesh);
  std::vector<cd> un;
  for (const auto& row : read_number_rows(a.velocity, 1, 2, "velocity file"))
    un.emplace_back(row[0], row.size() > 1 ? row[1] : 0.0);
  if (un.size() != mesh.vertices.size())
    throw InputError(a.velocity + ": " + std::to_string(un.size()) + " velocity values, but " +
                     a.mesh + " has " + std::to_string(mesh.vertices.size()) + " vertices");
  return un;
}

std::vector<Vec3> read_points(const std::string& path) {
  std::vector<Vec3> pts;
  for (const auto& row : read_number_rows(path, 3, 3, "points file"))
    pts.push_back({row[0], row[1], row[2]});
  if (pts.empty()) throw InputError(path + ": no points");
  return pts;
}

struct Radiated {
  ModeTransfer mt;
  bool bem = false;
  std::size_t sources = 0;  // equivalent sources (not BEM)
  double fit_residual = 0, held_out = 0;
  std::vector<cd> pressure;  // at the points
};

// The field at pts by BEM or by equivalent sources (whichever the method asks), read from the
// surface solution, the sources or their multipole series (--via).
Radiated radiate(const RadiateArgs& a, const precompute::SurfaceMesh& mesh,
                 const precompute::RadiatingSurface& surf, double k, const std::vector<cd>& un,
                 const std::vector<Vec3>& pts, precompute::AcousticOptions o,
                 const std::shared_ptr<gpu::Context>& ctx, precompute::TransferKernels& kernels) {
  Radiated r;
  using M = precompute::AcousticOptions::Method;
  // One frequency: auto keeps its single-frequency rule, BEM up to bem_auto_elements.
  r.bem = o.method == M::Bem || (o.method == M::Auto && precompute::bem_level(surf, k, o) >= 0);
  const precompute::NormalVelocity un_of = surf.from_vertex_values(un);
  std::vector<cd> a_lm, surface_p, surface_q;
  precompute::SourceFit fit;
  std::unique_ptr<precompute::BemSurface> elements;
  std::unique_ptr<precompute::BemMesh> bem_mesh;
  if (r.bem) {
    // The surface's triangles, split as often as the wavelength asks (within the element cap).
    elements = std::make_unique<precompute::BemSurface>(
        mesh, std::max(0, precompute::bem_level(surf, k, o)));
    bem_mesh = std::make_unique<precompute::BemMesh>(elements->mesh);
    o.bem.gpu = ctx;
    precompute::BemSolver solver(*bem_mesh, o.bem);
    r.mt = precompute::bem_transfer(surf, *elements, *bem_mesh, solver, k, un_of, o, a_lm, nullptr,
                                    &surface_p, &surface_q);
  } else {
    fit = precompute::fit_sources(surf, k, un_of, o, kernels);
    r.mt = precompute::expand_sources(surf, fit, o, kernels, a_lm);
    r.sources = fit.sources.size(), r.fit_residual = fit.residual, r.held_out = fit.held_out;
  }
  if (a.via == "multipole") {
    Transfer t;
    t.centre = surf.centre();
    t.radius = surf.radius();
    t.add_mode(r.mt, a_lm);
    for (const Vec3& x : pts) r.pressure.push_back(t.pressure(0, x));
  } else if (r.bem) {
    r.pressure = precompute::bem_field(*bem_mesh, k, surface_p, surface_q, pts, o.bem);
  } else {
    r.pressure = precompute::source_pressure(surf, fit, pts, kernels);
  }
  return r;
}

nlohmann::json radiate_json(const RadiateArgs& a, const precompute::RadiatingSurface& surf,
                            double k, const Radiated& r, const std::vector<Vec3>& pts,
                            const std::string& kernels) {
  const ModeTransfer& mt = r.mt;
  nlohmann::json j;
  j["mesh"] = a.mesh;
  j["frequency_hz"] = a.freq;
  j["wavenumber"] = k;
  j["method"] = to_string(mt.method);
  j["kernels"] = kernels;
  j["via"] = a.via == "multipole" ? "multipole" : r.bem ? "surface" : "sources";
  j["fit"] = {{"method", to_string(mt.method)},
              {r.bem ? "elements" : "sources", mt.sources},
              {r.bem ? "residual" : "fit_residual", mt.fit_residual},
              {r.bem ? "null_field_error" : "held_out_error", mt.held_out_error},
              {"iterations", mt.iterations},
              {"order", mt.order},
              {"expansion_error", mt.expansion_error},
              {"centre", surf.centre()},
              {"radius_m", surf.radius()}};
  nlohmann::json out = nlohmann::json::array();
  for (std::size_t i = 0; i < pts.size(); ++i)
    out.push_back({{"x", pts[i][0]},
                   {"y", pts[i][1]},
                   {"z", pts[i][2]},
                   {"pressure", {{"re", r.pressure[i].real()}, {"im", r.pressure[i].imag()}}}});
  j["points"] = out;
  return j;
}

void print_radiated(const RadiateArgs& a, double ka, const Radiated& r,
                    const std::vector<Vec3>& pts, const std::string& kernels) {
  const ModeTransfer& mt = r.mt;
  if (r.bem)
    std::printf(
        "%s at %.6g Hz (ka %.3g) by BEM: %u elements, residual %.2e, %u GMRES iterations, "
        "null-field error %.2e, order %u, expansion error %.2e\n",
        a.mesh.c_str(), a.freq, ka, mt.sources, mt.fit_residual, mt.iterations, mt.held_out_error,
        mt.order, mt.expansion_error);
  else
    std::printf(
        "%s at %.6g Hz (ka %.3g) with %s: %zu sources, fit residual %.2e, held-out %.2e, "
        "order %u, expansion error %.2e\n",
        a.mesh.c_str(), a.freq, ka, kernels.c_str(), r.sources, r.fit_residual, r.held_out,
        mt.order, mt.expansion_error);
  std::printf("%12s %12s %12s %14s %14s %12s\n", "x", "y", "z", "re p (Pa)", "im p (Pa)",
              "|p| (Pa)");
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const cd p = r.pressure[i];
    std::printf("%12.5g %12.5g %12.5g %14.6g %14.6g %12.6g\n", pts[i][0], pts[i][1], pts[i][2],
                p.real(), p.imag(), std::abs(p));
  }
}

void run_radiate(const RadiateArgs& a) {
  if (!a.json_path.empty()) check_output_path(a.json_path, "--json");
  if (a.velocity.empty() == a.pattern.empty())
    throw InputError("give exactly one of --velocity FILE and --pattern NAME");
  if (a.via != "sources" && a.via != "multipole" && a.via != "surface")
    throw InputError("--via must be surface, sources or multipole");
  const precompute::SurfaceMesh mesh = read_radiating_mesh(a);
  const std::vector<cd> un = read_velocity(a, mesh);
  const std::vector<Vec3> pts = read_points(a.points);

  precompute::AcousticOptions o;
  o.sound_speed = a.sound_speed;
  o.air_density = a.air_density;
  o.order = a.order;
  o.bem_max_memory = precompute::default_memory_budget();  // 80 % of the memory available
  const precompute::RadiatingSurface surf(mesh, o);
  // Past a few hundred wavelengths across, no method here resolves the field (BEM elements,
  // sources and multipole orders are all capped): refuse rather than print a wrong field.
  const double k = 2 * std::numbers::pi * a.freq / a.sound_speed, ka = k * surf.radius();
  if (!(ka <= 1000))
    throw InputError(a.mesh + ": k R = " + std::to_string(ka) + " at --freq " +
                     std::to_string(a.freq) +
                     " Hz: the surface is too many wavelengths across (at most k R = 1000)");
  std::shared_ptr<gpu::Context> ctx = a.backend == "gpu" ? transfer_device("gpu") : nullptr;
  if (a.backend != "gpu" && a.backend != "cpu") throw InputError("--backend must be cpu or gpu");
  std::unique_ptr<precompute::TransferKernels> kernels =
      ctx ? precompute::make_gpu_transfer_kernels(ctx) : precompute::make_cpu_transfer_kernels();
  o.method = parse_transfer_method(a.method, "--method");
  if (o.method == precompute::AcousticOptions::Method::Wave)
    throw InputError(
        "--method wave: the time-domain solve runs per soundbank (chladni "
        "precompute --transfer-method wave); radiate takes auto, bem or sources");
  const Radiated r = radiate(a, mesh, surf, k, un, pts, o, ctx, *kernels);
  if (!a.json_path.empty())
    write_file_atomic(a.json_path, radiate_json(a, surf, k, r, pts, kernels->name()).dump(2) + "\n",
                      "--json");
  print_radiated(a, ka, r, pts, kernels->name());
}

}  // namespace

void add_radiate(CLI::App& app) {
  auto a = std::make_shared<RadiateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "radiate", "Pressure radiated by a closed surface for a prescribed normal velocity");
  cmd->add_option("mesh", a->mesh, "Closed triangle mesh (OBJ/OFF/PLY/STL)")->required();
  cmd->add_option("--freq", a->freq, "Frequency (Hz)")->check(finite_above(0, 1e6))->required();
  cmd->add_option("--velocity", a->velocity,
                  "Outward normal velocity per vertex, one line each: 're' or 're im' (m/s)");
  cmd->add_option("--pattern", a->pattern,
                  "Analytic velocity: sphere-harmonic:l=L,m=M[,U=1] (U P_l^m(cos t) about the "
                  "surface centroid) or uniform[:U=1]");
  cmd->add_option("--points", a->points, "Field points, one 'x y z' per line (m)")->required();
  cmd->add_option("--backend", a->backend, "Kernels: cpu (double) or gpu (Vulkan, float)")
      ->capture_default_str();
  cmd->add_option(
         "--method", a->method,
         "Surface pressure: bem (Burton-Miller boundary elements), sources "
         "(equivalent-source fit) or auto (BEM where the surface has 6 elements per wavelength "
         "and at most 12000 elements, else sources)")
      ->capture_default_str();
  cmd->add_option("--via", a->via,
                  "Evaluate directly from the surface solution (surface; 'sources' is its old "
                  "name), or by the stored multipole series (multipole, r >= R)")
      ->capture_default_str();
  cmd->add_option("--order", a->order, "Multipole order (0: automatic)")
      ->check(CLI::Range(0, 40))
      ->capture_default_str();
  cmd->add_option("--unit", a->unit, "Unit of the mesh coordinates: m, cm, mm")
      ->capture_default_str();
  cmd->add_option("--scale", a->scale, "Extra factor on the coordinates")
      ->check(finite_above(0, 1e12))
      ->capture_default_str();
  cmd->add_option("--sound-speed", a->sound_speed, "m/s")
      ->check(finite_in(10, 1e4))
      ->capture_default_str();
  cmd->add_option("--air-density", a->air_density, "kg/m^3")
      ->check(finite_in(1e-3, 1e4))
      ->capture_default_str();
  cmd->add_option("--json", a->json_path, "Write the fit and the pressures as JSON");
  cmd->callback([a] { run_radiate(*a); });
}

}  // namespace chladni::cli
