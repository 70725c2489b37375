#include "solve_to_tolerance.hpp"

#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>

#include "band_modes.hpp"
#include "chladni/core/error.hpp"
#include "timing.hpp"

namespace chladni::precompute {
namespace {

FemPass fem_pass(TetMesh tets, const PrecomputeOptions& o, const EigenOptions& eo,
                 const Progress& p, Stopwatch& sw) {
  FemPass f;
  f.quality = tet_quality(tets);
  sw.start("assemble");
  const FemMesh fem = make_fem_mesh(tets, o.order);
  f.tets = std::move(tets);
  f.nodes = fem.nodes.size();
  f.dofs = fem.dofs();
  // Refused before assembly, the largest cost before the factor; the ordering the check found is
  // the factorization's.
  EigenOptions e = eo;
  check_memory_for_mesh(fem, eo, &e.node_ordering);
  FemMatrices km = assemble(fem, o.material, o.mass, o.threads, p.fraction);
  f.nonzeros = std::size_t(km.K.nonZeros());
  sw.start("eigen-solve");
  f.eigen = solve_modes(km.K, km.M, rigid_body_modes(fem.nodes), e, p.note);
  sw.start("error estimate");
  f.errors = estimate_mode_errors(fem, o.material, f.eigen.lambda, f.eigen.vectors, o.threads);
  return f;
}

// The modes the estimate must bring within tolerance: those asked for, in the band.
double worst_error(const FemPass& f, const PrecomputeOptions& o) {
  double worst = 0;
  for (std::size_t i = 0; i < f.eigen.lambda.size(); ++i) {
    const double hz = std::sqrt(std::max(f.eigen.lambda[i], 0.0)) / (2 * std::numbers::pi);
    if (hz >= o.min_frequency && hz <= o.max_frequency)
      worst = std::max(worst, f.errors.relative[i]);
  }
  return worst;
}

// Each mode against the previous mesh's: some mode there must lie within what its estimate
// allowed (kMissAllowed times it, plus a tenth of the tolerance), or the estimate missed an
// error. Patch recovery sees nothing of a twist the mesh cannot yet carry: a 12-triangle steel
// bar's torsion, estimated at 0.03 % on its first mesh, moved 7.7 % on the next. Such a mode's
// estimate here is raised by the miss (at most kMissCap times), so another mesh confirms it.
// Any mode of the previous mesh may vouch, so close modes that swap order (a bell's) do not
// count as misses. Returns how many modes were raised.
constexpr double kMissAllowed = 3, kMissCap = 4;

std::size_t raise_missed(const FemPass& previous, FemPass& f, const PrecomputeOptions& o) {
  std::vector<double> before(previous.eigen.lambda.size());
  for (std::size_t j = 0; j < before.size(); ++j)
    before[j] = std::sqrt(std::max(previous.eigen.lambda[j], 0.0));
  std::size_t raised = 0;
  for (std::size_t i = 0; i < f.eigen.lambda.size(); ++i) {
    const double now = std::sqrt(std::max(f.eigen.lambda[i], 0.0));
    if (!(now > 0) || now / (2 * std::numbers::pi) > o.max_frequency) continue;
    double moved = INFINITY, said = 0;
    bool vouched = false;
    for (std::size_t j = 0; j < before.size() && !vouched; ++j) {
      const double d = std::abs(before[j] - now) / now, e = previous.errors.relative[j];
      vouched = d <= kMissAllowed * e + 0.1 * o.tolerance;
      if (d < moved) moved = d, said = e;
    }
    if (vouched || before.empty()) continue;
    f.errors.relative[i] *= std::min(moved / std::max(said, 1e-12), kMissCap);
    ++raised;
  }
  return raised;
}

// A mesh whose vertices all lie on the surface is one layer of tetrahedra across: patch
// recovery then fits each vertex's strains from one side only and cannot see what the section's
// shape misses (a 12-triangle square bar's first mesh put its torsion 8.9 % high and estimated
// 0.03 %). Such a first mesh is not taken on its estimate alone; fewer than 5 % inside counts.
bool one_layer(const TetMesh& m) {
  return double(m.surface_vertices) >= 0.95 * double(m.nodes.size());
}

// How much the next mesh's edges shrink where the worst mode's error lies: an element of order
// p shrunk by s keeps about s^(2p) of its error (energy error ~ h^p; Zienkiewicz & Zhu 1987),
// so the factor that brings that mode to half the tolerance, by at most 2 at a time. `step` in
// (0, 1] takes that fraction of the step in log size (a milder step when the full one does not
// fit the memory budget).
double shrink_factor(double worst, double step, const PrecomputeOptions& o) {
  const double s = std::clamp(std::pow(0.5 * o.tolerance / worst, 1.0 / (2.0 * o.order)), 0.5, 0.9);
  return std::pow(s, step);
}

// Uniform refinement: the largest tet volume for the next mesh, from the error-weighted mean
// edge shrunk by `s`.
double refined_volume(const FemPass& f, double s) {
  const TetMesh& m = f.tets;
  double weighted = 0, weight = 0;
  for (std::size_t e = 0; e < m.tets.size(); ++e) {
    const double v = std::abs(tet_volume(m, e));
    weighted += f.errors.element[e] * std::cbrt(6 * std::numbers::sqrt2 * v);  // regular edge
    weight += f.errors.element[e];
  }
  return std::pow(s * weighted / weight, 3) / (6 * std::numbers::sqrt2);
}

// Local refinement by Doerfler marking (Doerfler 1996): the tetrahedra of densest estimated
// error, together holding the share theta of it that brings the worst mode to half the tolerance
// once their edges shrink by s (capped at 0.9, so a few sweeps rather than one near-uniform one
// reach a concentrated error), get s^3 times the bound they were meshed under: `level` (the
// last bound of the region), or `own` times their volume where they are smaller (a thin wall).
// For TetGen own = 2: a quality mesh's tetrahedra average 0.7 of their bound, so a bound of s^3
// times each one's own volume would follow its smallest neighbours (21x the tetrahedra for
// s = 1/2 on a box, against 13x this way and 10x for uniform refinement). Bisection, which
// halves a tetrahedron only while it is over its bound, takes own = 1. The rest get none.
std::vector<double> local_bounds(const FemPass& f, double worst, double s, double level, double own,
                                 const PrecomputeOptions& o) {
  const TetMesh& m = f.tets;
  const std::vector<double>& err = f.errors.element;
  const std::size_t n = m.tets.size();
  std::vector<double> volume(n);
  for (std::size_t e = 0; e < n; ++e) volume[e] = std::abs(tet_volume(m, e));
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return err[a] * volume[b] > err[b] * volume[a];  // error density, densest first
  });
  const double total = std::accumulate(err.begin(), err.end(), 0.0);
  const double gain = 1 - std::pow(s, 2.0 * o.order);
  const double theta = std::clamp((worst - 0.5 * o.tolerance) / (worst * gain), 0.0, 0.9);
  std::vector<double> bound(n, -1.0);
  double marked = 0;
  for (std::size_t e : order) {
    if (marked >= theta * total) break;
    bound[e] = s * s * s * std::min(level, own * volume[e]);
    marked += err[e];
  }
  return bound;
}

// TetGen's refinement also mends the quality of every tetrahedron it may, which in a thin wall
// or a flat layer (a plate meshed under -Y) multiplies the mesh beyond what the bounds ask: a
// 2 mm disc went from 1,152 to 26,812 tetrahedra where they asked for 1,764, and the bowl's 20
// modes took 59,574 (0.2 %) where bisection makes 32,643 (0.34 %, each mode within 0.12 % of
// TetGen's, as the two estimates said). Longest-edge bisection of the same marked tetrahedra
// grows only where asked, its shapes within a few classes of the last mesh's (Rivara 1984).
// TetGen's better shapes are worth some size: on a thin fin its 1,684 tetrahedra were 1.6 % off
// where bisection's 1,554 were 2.9 %, what P2 would need 1.55 times the tetrahedra for (error
// ~ N^(-4/3)). So bisection's mesh is solved when TetGen's is over kShapeWorth times its size.
constexpr double kShapeWorth = 1.5;

void prefer_bisection_where_smaller(const TetMesh& last, const std::vector<double>& halving,
                                    const Progress& p, TetMesh& tets) {
  // Bisection makes at least what the bounds ask: a cheap test first.
  if (double(tets.tets.size()) <= kShapeWorth * tetrahedra_asked(last, halving)) return;
  TetMesh bisected = bisect_tets(last, halving);
  if (double(tets.tets.size()) <= kShapeWorth * double(bisected.tets.size())) return;
  if (p.note)
    p.note("TetGen's refinement made " + std::to_string(tets.tets.size()) +
           " tetrahedra, bisection " + std::to_string(bisected.tets.size()) +
           ": taking the bisected mesh");
  tets = std::move(bisected);
}

// A refinement over kRunaway times the size of the solid meshed again (below) has run away.
constexpr double kRunaway = 4;

// A first mesh of poorly shaped tetrahedra (TetGen's -Y against long thin surface triangles, the
// CAD parts') is refined at great cost: the rotor's 2,787 tetrahedra, 24 % off, became 126k and
// then 252k (151 s, 10 GB for 12 modes). The solid meshed again with points on the surface, a
// quality mesh of 38k tetrahedra, was 2.9 % off. A thin plate's or shell's first mesh is poorly
// shaped as well, but there refinement is the cheaper way (under 10,000 tetrahedra, where mending
// the 2 mm disc's quality made 72,612). And a remeshed solid is not sized where the error lies:
// the brass bowl's first mesh, 5.5 % off for its 122 modes, refines to 0.3 % in one step (117 s;
// 110k tetrahedra, 2.6 times the remeshed solid), where the remeshed one took three more meshes
// (427 s). So the remeshed solid replaces the refined mesh when it has fewer tetrahedra and
// either one refinement step cannot reach the tolerance (its shrink factor capped at a half, an
// estimate over 8 times the tolerance for P2: the rotor's 24 %, the coupling's 8.7 %) or the
// refinement ran away, over kRunaway times the remeshed solid (the coupling at 0.2 m in
// aluminium, 6.6 % off: 352k tetrahedra against 68k, 18.5 GB).
void prefer_surface_points(const SurfaceMesh& surface, const FemPass& first, double worst,
                           const PrecomputeOptions& po, const TetOptions& topt, const Progress& p,
                           TetMesh& tets, double& meshed) {
  if (!(first.quality.mean_radius_edge > kPoorMeanRadiusEdge)) return;
  TetOptions o = topt;
  o.keep_surface = false;
  TetMesh remeshed;
  try {
    remeshed = tetrahedralize(surface, o);
  } catch (const InputError&) {
    return;  // the refined mesh stands
  }
  const bool capped = shrink_factor(worst, 1, po) <= 0.5;
  const bool runaway = double(tets.tets.size()) > kRunaway * double(remeshed.tets.size());
  if (remeshed.tets.size() >= tets.tets.size() || !(capped || runaway) ||
      !(tet_quality(remeshed).mean_radius_edge < kPoorMeanRadiusEdge))
    return;
  if (p.note)
    p.note("mesh 1 is poorly shaped (mean radius-edge ratio " +
           std::to_string(first.quality.mean_radius_edge).substr(0, 4) +
           "): the solid meshed again with points on its surface, " +
           std::to_string(remeshed.tets.size()) + " tetrahedra, replaces its refinement (" +
           std::to_string(tets.tets.size()) + ")");
  tets = std::move(remeshed);
  meshed = o.max_volume;
}

// The next mesh, refined by `s` where the error lies: locally (TetGen refining `best`'s mesh,
// or where TetGen fails, longest-edge bisection of the same tetrahedra) unless
// o.local_refinement is off, else the surface meshed again under one smaller bound.
// r.max_tet_volume is `best`'s bound (after local refinement, its finest region's); `meshed`
// receives the new one. Returns false, with the reason in r, when no mesh can be made.
bool next_mesh(const SurfaceMesh& surface, const FemPass& best, double worst, double s,
               const PrecomputeOptions& o, const Progress& p, TetOptions& topt, TetMesh& tets,
               double& meshed, PrecomputeReport& r) {
  if (o.local_refinement) {
    meshed = s * s * s * r.max_tet_volume;
    const std::vector<double> halving = local_bounds(best, worst, s, r.max_tet_volume, 1, o);
    bool refined = false;
    try {
      tets = refine_tets(best.tets, local_bounds(best, worst, s, r.max_tet_volume, 2, o), topt);
      prefer_bisection_where_smaller(best.tets, halving, p, tets);
      refined = true;
    } catch (const InputError& e) {
      if (p.note)
        p.note(std::string("TetGen's local refinement failed (") + e.what() +
               "); bisecting the marked tetrahedra instead");
    }
    if (!refined) try {
        tets = bisect_tets(best.tets, halving);
        refined = true;
      } catch (const InputError& e) {
        if (p.note) p.note(std::string("bisection failed (") + e.what() + "); refining all");
      }
    if (refined && r.passes.size() == 1)
      prefer_surface_points(surface, best, worst, o, topt, p, tets, meshed);
    if (refined) return true;
  }
  topt.max_volume = std::min(r.max_tet_volume, refined_volume(best, s));  // never coarser
  meshed = topt.max_volume;
  try {
    tets = tetrahedralize(surface, topt);
    return true;
  } catch (const InputError& e) {  // e.g. more tets than this tool meshes
    r.unconverged_reason = std::string("the next refinement failed: ") + e.what();
    return false;
  }
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g %%", 100 * x);
  return buf;
}

// A refusal of the whole band says how many modes it holds (`band`, from band_modes), so the
// user can ask for fewer.
[[noreturn]] void refuse_band(const BudgetError& e, std::size_t band, const PrecomputeOptions& o) {
  if (o.max_modes > 0) throw e;
  throw BudgetError(std::string(e.what()) + "; about " + std::to_string(band) +
                    " modes lie below " + std::to_string(int(o.max_frequency)) +
                    " Hz: ask for the first N with --max-modes");
}

// The first mesh: under the user's bound, or sized from max_frequency, or with max_modes the
// coarsest quality mesh; its memory checked before it is made wherever that is known. `topt`
// receives the options it was made with.
TetMesh first_mesh(const SurfaceMesh& surface, const PrecomputeOptions& o, const EigenOptions& eo,
                   const PrecomputeReport& r, TetOptions& topt) {
  const bool chosen = o.max_tet_volume > 0;
  topt.max_volume = chosen ? o.max_tet_volume
                    : o.max_modes > 0
                        ? coarse_max_volume(surface)
                        : auto_max_volume(o.material, o.max_frequency, o.order, surface);
  try {
    if (chosen || o.max_modes == 0)
      check_memory_for_surface(surface, std::abs(r.mesh.volume), topt.max_volume, o.order, o.tet,
                               eo);
    // A flat mesh over the budget is refused before it is made again, larger.
    TetOptions first_options = topt;
    first_options.before_remesh = [&](const TetMesh& m) {
      check_memory_for_mesh(make_fem_mesh(m, o.order), eo);
    };
    return tetrahedralize(surface, first_options);
  } catch (const BudgetError& e) {
    refuse_band(e, eo.expected_modes, o);
  }
}

// The refinement loop's state: the mesh to solve next, the best solved so far and its worst
// estimate, and the step the next refinement takes (smaller after one over the memory budget).
struct Loop {
  const SurfaceMesh& surface;
  const PrecomputeOptions& o;
  const Progress& p;
  Stopwatch& sw;
  PrecomputeReport& r;
  EigenOptions eo;
  TetOptions topt;
  TetMesh tets;
  double meshed = 0;  // the bound `tets` was made with
  std::optional<FemPass> best;
  double worst = 0, step = 1;

  // The next mesh from `best`, refined by `step`; false (with r.converged set) when none can be
  // made.
  bool refine(double step_now) {
    sw.start("tetrahedralize");
    const double aim = std::max(worst, o.tolerance);  // a confirming mesh halves the error
    if (next_mesh(surface, *best, aim, shrink_factor(aim, step_now, o), o, p, topt, tets, meshed,
                  r))
      return true;
    r.converged = worst <= o.tolerance;
    return false;
  }
};

// After mesh `pass` failed: true to solve a smaller refinement instead, false to stop with the
// best mesh so far. A refinement over the memory budget is retried at half the step in log size
// (a factor of 8 in volume becomes 2.8, then 1.7): a thin part may need only a little more. Any
// other failure leaves the previous mesh standing. Without one, a first mesh over the budget is
// refused, saying how many modes the band holds (a coarser one would resolve neither the band
// nor its modes); any other error goes on up.
bool retry_after(const InputError& e, int pass, Loop& l) {
  const auto* budget = dynamic_cast<const BudgetError*>(&e);
  if (!l.best) {
    if (!budget) throw;
    refuse_band(*budget, l.eo.expected_modes, l.o);
  }
  if (budget && l.step > 0.3) {
    if (l.p.note)
      l.p.note("mesh " + std::to_string(pass) + " would exceed --max-memory; trying a smaller " +
               "refinement step");
    l.step /= 2;
    return l.refine(l.step);
  }
  // a mesh within the tolerance, only not confirmed, stands as converged
  l.r.converged = l.worst <= l.o.tolerance;
  l.r.unconverged_reason = std::string("the next refinement failed: ") + e.what();
  return false;
}

// Takes mesh `pass`'s solve as the best: its estimates checked against the previous mesh's, its
// worst error and its line in the report.
void record(FemPass f, int pass, double seconds, Loop& l) {
  const std::size_t raised = l.best ? raise_missed(*l.best, f, l.o) : 0;
  l.worst = worst_error(f, l.o);
  if (raised && l.p.note)
    l.p.note(std::to_string(raised) + " modes moved by more than mesh " + std::to_string(pass - 1) +
             "'s estimate allowed; their estimates are raised");
  l.r.passes.push_back(
      {f.tets.tets.size(), f.dofs, l.worst, seconds, l.meshed, l.eo.expected_modes});
  if (l.p.note)
    l.p.note("mesh " + std::to_string(pass) + ": " + std::to_string(f.tets.tets.size()) +
             " tetrahedra, largest estimated frequency error " + percent(l.worst));
  // A band search on the next mesh holds what this one found, not the estimate made before
  // meshing: a finer mesh's frequencies are lower by about the error, so its count is higher
  // by the cube of that (Weyl). Its memory check then counts the basis the search will fill.
  if (l.o.max_modes == 0)
    l.eo.expected_modes =
        std::size_t(std::ceil(double(f.eigen.lambda.size()) * std::pow(1 + l.worst, 3))) + 1;
  l.best = std::move(f);
  l.r.max_tet_volume = l.meshed;
  l.step = 1;
}

}  // namespace

FemPass solve_to_tolerance(const SurfaceMesh& surface, const PrecomputeOptions& o,
                           const EigenOptions& eigen, const Progress& p, Stopwatch& sw,
                           PrecomputeReport& r, SurfaceMesh& first) {
  Loop l{surface, o, p, sw, r, eigen, o.tet, {}};
  if (o.max_modes == 0)
    l.eo.expected_modes =
        std::size_t(std::llround(band_modes(surface, r.mesh, o.material, o.max_frequency)));
  const bool chosen = o.max_tet_volume > 0;
  sw.start("tetrahedralize");
  l.tets = first_mesh(surface, o, l.eo, r, l.topt);
  l.meshed = l.topt.max_volume;
  first.vertices.assign(l.tets.nodes.begin(),
                        l.tets.nodes.begin() + std::ptrdiff_t(l.tets.surface_vertices));
  first.triangles = l.tets.surface_triangles;
  for (int pass = 1;; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    FemPass f;
    try {
      f = fem_pass(std::move(l.tets), o, l.eo, p, sw);
    } catch (const InputError& e) {
      if (!retry_after(e, pass, l)) break;
      --pass;
      continue;
    }
    record(std::move(f), pass, seconds_since(t0), l);
    const bool confirm = pass == 1 && !chosen && pass < o.max_passes && one_layer(l.best->tets);
    if (l.worst <= o.tolerance && !confirm) {
      r.converged = true;
      break;
    }
    if (l.worst <= o.tolerance && p.note)
      p.note("mesh 1 is one layer of tetrahedra (no vertex inside): a second mesh confirms it");
    r.converged = false;
    if (chosen) {
      r.unconverged_reason = "--max-tet-volume fixes the elements";
      break;
    }
    if (pass >= o.max_passes) {
      r.unconverged_reason = std::to_string(pass) + " meshes solved";
      break;
    }
    if (!l.refine(1)) break;
  }
  if (!r.converged && p.note)
    p.note("warning: the largest estimated frequency error is " +
           percent(r.passes.back().worst_error) + ", above --tolerance " + percent(o.tolerance) +
           " (" + r.unconverged_reason + ")");
  return std::move(*l.best);
}

}  // namespace chladni::precompute
