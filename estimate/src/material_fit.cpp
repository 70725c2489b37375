#include "chladni/estimate/material_fit.hpp"

#include <nlopt.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"
#include "chladni/runtime/modal/contact_weight.hpp"

namespace chladni::estimate {
namespace {

using Kind = DampingModel::Kind;
constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr std::size_t kCurve = 3;  // theta: ln s, ln scale, ln contact time, then the curve

// The damping curve is searched through its values c at a few reference frequencies (log c
// there), which the optimizer sees as well scaled whatever the model; the model's parameters
// are solved from them. A hybrid model keeps its exponent as a fourth coordinate.
struct CurveCoordinates {
  Kind kind;
  std::size_t terms;
  std::vector<double> x;  ///< omega^2 at the reference frequencies

  std::size_t count() const { return kind == Kind::Hybrid ? 4 : terms; }
  std::size_t values() const { return kind == Kind::Hybrid ? 3 : terms; }

  bool model(const double* theta, DampingModel& out) const {
    const std::size_t n = values();
    std::vector<double> c(n);
    for (std::size_t k = 0; k < n; ++k) c[k] = std::exp(theta[k]);
    if (kind == Kind::PowerLaw) {
      const double a2 = std::log(c[1] / c[0]) / std::log(x[1] / x[0]);
      out = {Kind::PowerLaw, {c[0] / std::pow(x[0], a2), a2}};
      return true;
    }
    const double p2 = kind == Kind::Hybrid ? theta[3] : 0.0;
    Eigen::MatrixXd A(static_cast<long>(n), static_cast<long>(n));
    Eigen::VectorXd b(static_cast<long>(n));
    for (std::size_t j = 0; j < n; ++j) {
      const double u = x[j] / x[0];  // scaled so the system stays conditioned
      for (std::size_t k = 0; k < n; ++k) {
        if (kind == Kind::Hybrid)
          A(long(j), long(k)) = k == 0 ? 1.0 : k == 1 ? u : std::pow(u, p2);
        else
          A(long(j), long(k)) = std::pow(u, double(k));
      }
      b(long(j)) = c[j];
    }
    const Eigen::VectorXd s = A.fullPivLu().solve(b);
    std::vector<double> alpha(n);
    for (std::size_t k = 0; k < n; ++k) {
      const double e = kind == Kind::Hybrid ? (k == 0 ? 0.0 : k == 1 ? 1.0 : p2) : double(k);
      alpha[k] = s(long(k)) / std::pow(x[0], e);
      if (!std::isfinite(alpha[k])) return false;
    }
    if (kind == Kind::Hybrid) {
      if (alpha[0] < 0 || alpha[1] < 0 || alpha[2] < 0) return false;
      alpha.push_back(p2);
    } else if (kind == Kind::Rayleigh && (alpha[0] < 0 || alpha[1] < 0)) {
      return false;
    }
    out = {kind, alpha};
    return true;
  }
};

CurveCoordinates coordinates(const DampingModel& shape, const FeatureSet& fs) {
  double lo = INFINITY, hi = 0;
  for (const Feature& f : fs.features)
    lo = std::min(lo, f.frequency), hi = std::max(hi, f.frequency);
  if (!(hi > lo * 1.5)) lo = hi / 1.5;
  CurveCoordinates cc{shape.kind, shape.kind == Kind::Hybrid ? 4 : shape.alpha.size(), {}};
  const std::size_t n = cc.values();
  for (std::size_t k = 0; k < n; ++k) {
    const double f = n == 1 ? lo : lo * std::pow(hi / lo, double(k) / double(n - 1));
    cc.x.push_back((kTwoPi * f) * (kTwoPi * f));
  }
  return cc;
}

struct Problem {
  const FeatureSet* features;
  const PsychoSpectrogram* target;
  const StruckModes* modes;
  CurveCoordinates curve;
  std::vector<Partial> extracted;
  double max_frequency = 0;
  std::size_t evaluations = 0;

  double cost(const double* theta, MaterialFit* out = nullptr) {
    ++evaluations;
    DampingModel d;
    if (!curve.model(theta + kCurve, d)) return 1e30;
    std::vector<Partial> model;
    try {
      model = model_partials(*modes, std::exp(theta[0]), std::exp(theta[1]), std::exp(theta[2]), d,
                             max_frequency);
    } catch (const InputError&) {
      return 1e30;  // the curve turns negative at some mode
    }
    const double psycho = target->difference(target->of_partials(model));
    const double mrp = match_ratio_product(extracted, model, features->duration);
    const double h = hybrid_metric(psycho, mrp);
    if (out) {
      out->frequency_scale = std::exp(theta[0]);
      out->amplitude_scale = std::exp(theta[1]);
      out->contact_time = std::exp(theta[2]);
      out->damping = d;
      out->psycho = psycho;
      out->mrp = mrp;
      out->hybrid = h;
      out->modes = std::move(model);
    }
    return std::isfinite(h) ? h : 1e30;
  }
};

double nlopt_cost(unsigned, const double* theta, double*, void* data) {
  return static_cast<Problem*>(data)->cost(theta);
}

// The search's damping is pulled by whatever the model gets wrong in the partials' levels (the
// mesh, the microphone, radiation read at the reference frequencies). Each partial's decay was
// measured directly, so the final curve goes through the decays of the partials that the fitted
// modes explain (within 1 % in frequency), which also leaves out partials no mode accounts for.
void refine_damping(const FeatureSet& features, Problem& p, const MaterialFitOptions& o,
                    MaterialFit& best) {
  best.search_damping = best.damping;
  std::vector<Feature> matched;
  for (const Feature& f : features.features) {
    const bool explained = std::any_of(best.modes.begin(), best.modes.end(), [&](const Partial& m) {
      return std::abs(m.frequency - f.frequency) <
             std::max(0.01 * f.frequency, 3 * f.frequency_sigma);
    });
    if (explained) matched.push_back(f);
  }
  best.matched_partials = matched.size();
  DampingFit fit;
  try {
    fit = fit_damping(matched, o.shape);
  } catch (const InputError&) {
    return;  // too few: keep the search's curve
  }
  if (!fit.warnings.empty()) return;
  std::vector<Partial> model;
  try {
    model = model_partials(*p.modes, best.frequency_scale, best.amplitude_scale, best.contact_time,
                           fit.model, p.max_frequency);
  } catch (const InputError&) {
    return;
  }
  best.damping = fit.model;
  best.psycho = p.target->difference(p.target->of_partials(model));
  best.mrp = match_ratio_product(p.extracted, model, features.duration);
  best.hybrid = hybrid_metric(best.psycho, best.mrp);
  best.modes = std::move(model);
}

}  // namespace

std::vector<Partial> model_partials(const StruckModes& modes, double frequency_scale,
                                    double amplitude_scale, double contact_time,
                                    const DampingModel& damping, double max_frequency) {
  std::vector<Partial> out;
  for (std::size_t i = 0; i < modes.omega.size(); ++i) {
    const double w = modes.omega[i] * frequency_scale;
    const double d = 0.5 * damping.coefficient(w);
    if (d >= w) continue;
    const double f = std::sqrt(w * w - d * d) / kTwoPi;
    if (f < 20 || f > max_frequency) continue;
    const double wd = kTwoPi * f;
    // The strike's half-sine force over contact_time weights each mode by its spectrum there.
    const double contact = std::abs(runtime::contact_weight(1.0, contact_time, wd, d));
    out.push_back({f, d, amplitude_scale * modes.amplitude[i] * contact});
  }
  return out;
}

namespace {

// Damping start: the curve through the features, read at the reference frequencies.
std::vector<double> curve_start(const Problem& p, const DampingFit& damping_start,
                                const DampingModel& shape) {
  std::vector<double> curve0(p.curve.count());
  for (std::size_t k = 0; k < p.curve.values(); ++k) {
    double c = 0;
    try {
      c = damping_start.model.coefficient(std::sqrt(p.curve.x[k]));
    } catch (const InputError&) {
    }
    curve0[k] = std::log(std::max(c, 1e-3));
  }
  if (shape.kind == Kind::Hybrid)
    curve0[3] = damping_start.model.kind == Kind::Hybrid ? damping_start.model.alpha[3] : 0.5;
  return curve0;
}

struct Start {
  std::vector<double> theta;
  double cost;
};

// Starting points, best first: each of the three most energetic partials taken as each
// candidate mode (Sec. 1.3.1.2), the scale matching their amplitudes, for a hard, a medium and a
// soft strike. Candidate modes are the 40 lowest that a strike at this point excites at all (the
// mallet's softness, still unknown, decides which of them are loudest).
std::vector<Start> starting_points(const FeatureSet& features, const StruckModes& modes, Problem& p,
                                   const std::vector<double>& curve0) {
  std::vector<const Feature*> dominant;
  for (const Feature& f : features.features) dominant.push_back(&f);
  std::sort(dominant.begin(), dominant.end(),
            [](const Feature* a, const Feature* b) { return a->energy_share > b->energy_share; });
  dominant.resize(std::min<std::size_t>(dominant.size(), 3));
  double loudest = 0;
  for (double a : modes.amplitude) loudest = std::max(loudest, a);
  std::vector<std::size_t> order(modes.omega.size()), loud;
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return modes.omega[a] < modes.omega[b]; });
  for (std::size_t i : order)
    if (loud.size() < 40 && modes.amplitude[i] > 1e-3 * loudest) loud.push_back(i);
  std::vector<Start> starts;
  for (const Feature* f : dominant)
    for (std::size_t i : loud)
      for (double tau : {2e-5, 2e-4, 2e-3}) {
        std::vector<double> theta(kCurve + curve0.size());
        const double w = kTwoPi * f->frequency;
        const double contact = std::abs(runtime::contact_weight(1.0, tau, w, f->decay));
        theta[0] = std::log(w / modes.omega[i]);
        theta[1] = std::log(f->amplitude / (modes.amplitude[i] * std::max(contact, 1e-9)));
        theta[2] = std::log(tau);
        std::copy(curve0.begin(), curve0.end(), theta.begin() + kCurve);
        const double c = p.cost(theta.data());
        starts.push_back({theta, c});
      }
  std::sort(starts.begin(), starts.end(),
            [](const Start& a, const Start& b) { return a.cost < b.cost; });
  return starts;
}

// BOBYQA from `s`: the frequency scale within +-0.2 (in its log) of the start, so that starts
// explore different mode-to-partial mappings; the rest within wide bounds.
Start local_search(Problem& p, const Start& s, const MaterialFitOptions& o) {
  const std::size_t dims = s.theta.size();
  nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, unsigned(dims));
  if (!opt) throw InternalError("material fit: NLopt could not make its optimizer");
  std::vector<double> lb(dims), ub(dims), step(dims), theta = s.theta;
  lb[0] = theta[0] - 0.2, ub[0] = theta[0] + 0.2, step[0] = 0.01;
  lb[1] = theta[1] - 6, ub[1] = theta[1] + 6, step[1] = 0.3;
  lb[2] = std::log(1e-6), ub[2] = std::log(0.02), step[2] = 0.5;
  for (std::size_t k = kCurve; k < dims; ++k)
    lb[k] = theta[k] - 6, ub[k] = theta[k] + 6, step[k] = 0.3;
  if (o.shape.kind == Kind::Hybrid)
    lb[kCurve + 3] = 0.01, ub[kCurve + 3] = 1.5, step[kCurve + 3] = 0.1;
  for (std::size_t k = 0; k < dims; ++k) theta[k] = std::clamp(theta[k], lb[k], ub[k]);
  nlopt_set_lower_bounds(opt, lb.data());
  nlopt_set_upper_bounds(opt, ub.data());
  nlopt_set_initial_step(opt, step.data());
  nlopt_set_min_objective(opt, nlopt_cost, &p);
  nlopt_set_xtol_rel(opt, 1e-6);
  nlopt_set_ftol_rel(opt, 1e-7);
  nlopt_set_maxeval(opt, int(o.evaluations));
  double value = s.cost;
  // A failed or round-off-limited search still leaves its best point in theta.
  nlopt_optimize(opt, theta.data(), &value);
  nlopt_destroy(opt);
  return {theta, value};
}

}  // namespace

MaterialFit fit_material(const FeatureSet& features, const PsychoSpectrogram& target,
                         const StruckModes& modes, const DampingFit& damping_start,
                         const MaterialFitOptions& o) {
  if (modes.omega.empty() || modes.omega.size() != modes.amplitude.size())
    throw InputError("material fit: the object has no modes");
  for (std::size_t i = 0; i < modes.omega.size(); ++i)
    if (!(modes.omega[i] > 0) || !(modes.amplitude[i] >= 0) || !std::isfinite(modes.amplitude[i]))
      throw InputError("material fit: mode " + std::to_string(i) +
                       " has no valid frequency or "
                       "amplitude");
  if (features.features.empty()) throw InputError("material fit: the recording has no partials");
  Problem p{&features, &target, &modes, coordinates(o.shape, features), {}, 0, 0};
  p.max_frequency = o.max_frequency > 0 ? o.max_frequency : 0.45 * features.sample_rate;
  for (const Feature& f : features.features)
    p.extracted.push_back({f.frequency, f.decay, f.amplitude});
  const std::vector<Start> starts =
      starting_points(features, modes, p, curve_start(p, damping_start, o.shape));

  MaterialFit best;
  Start found{{}, INFINITY};
  std::vector<double> used_scales;
  for (const Start& s : starts) {
    if (best.starts_tried >= o.starts) break;
    // One local search per distinct frequency scale.
    if (std::any_of(used_scales.begin(), used_scales.end(),
                    [&](double u) { return std::abs(u - s.theta[0]) < 0.01; }))
      continue;
    used_scales.push_back(s.theta[0]);
    ++best.starts_tried;
    if (Start r = local_search(p, s, o); r.cost < found.cost) found = std::move(r);
  }
  if (found.theta.empty()) throw InputError("material fit: no starting point gives a valid model");
  const std::size_t tried = best.starts_tried;
  p.cost(found.theta.data(), &best);
  best.starts_tried = tried;
  best.evaluations = p.evaluations;
  best.gamma = modes.gamma * best.frequency_scale * best.frequency_scale;
  refine_damping(features, p, o, best);
  return best;
}

MaterialFit fit_material(std::span<const double> x, double sample_rate, const FeatureSet& features,
                         const StruckModes& modes, const DampingFit& damping_start,
                         const MaterialFitOptions& options) {
  if (features.origin >= x.size()) throw InputError("material fit: the strike is past the end");
  MaterialFitOptions o = options;  // one default band for the target and the search
  if (!(o.max_frequency > 0)) o.max_frequency = 0.45 * sample_rate;
  PsychoSpectrogram target(x.subspan(features.origin), sample_rate, o.max_frequency);
  target.set_noise(features.residual);
  return fit_material(features, target, modes, damping_start, o);
}

}  // namespace chladni::estimate
