#include "chladni/estimate/damping_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "chladni/core/error.hpp"

namespace chladni::estimate {
namespace {

using Kind = DampingModel::Kind;

struct Point {
  double x, c, weight;  // x = omega^2, c = 2 d
  double scale;         // the residual's denominator: c, then the last fit's beta (log errors)
};

// Weighted least squares of sum_k a_k g_k(x_j) against c_j, each residual divided by its
// point's scale (c_j, then the last fit's beta: Gauss-Newton on the log error); `keep` marks the
// basis functions left free (the others are held at 0). Columns are scaled to unit norm so the
// powers of omega^2 (1 to 1e20) do not ruin the conditioning.
Eigen::VectorXd relative_lsq(const std::vector<Point>& pts,
                             const std::vector<std::vector<double>>& basis,
                             const std::vector<bool>& keep) {
  const std::size_t n = pts.size(), m = basis.size();
  std::vector<std::size_t> cols;
  for (std::size_t k = 0; k < m; ++k)
    if (keep[k]) cols.push_back(k);
  Eigen::MatrixXd A(n, cols.size());
  Eigen::VectorXd b(n);
  for (std::size_t j = 0; j < n; ++j) {
    const double s = std::sqrt(pts[j].weight) / pts[j].scale;
    for (std::size_t q = 0; q < cols.size(); ++q) A(long(j), long(q)) = basis[cols[q]][j] * s;
    b(long(j)) = pts[j].c * s;
  }
  Eigen::VectorXd scale = A.colwise().norm().transpose();
  for (long q = 0; q < scale.size(); ++q)
    if (scale(q) > 0) A.col(q) /= scale(q);
  const Eigen::VectorXd y = A.colPivHouseholderQr().solve(b);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(long(m));
  for (std::size_t q = 0; q < cols.size(); ++q)
    a(long(cols[q])) = scale(long(q)) > 0 ? y(long(q)) / scale(long(q)) : 0.0;
  return a;
}

double weighted_rms(const std::vector<Point>& pts, const DampingModel& model) {
  double num = 0, den = 0;
  for (const Point& p : pts) {
    const double e = std::log(model.coefficient(std::sqrt(p.x)) / p.c);
    num += p.weight * e * e;
    den += p.weight;
  }
  return std::sqrt(num / den);
}

// Linear models (Rayleigh, Caughey, hybrid at a fixed exponent): an active set that holds a
// coefficient at zero when the free fit makes it negative, for the models whose coefficients
// must not be (Rayleigh, hybrid).
std::vector<double> linear_fit(const std::vector<Point>& pts,
                               const std::vector<std::vector<double>>& basis, bool nonnegative) {
  std::vector<bool> keep(basis.size(), true);
  Eigen::VectorXd a;
  for (std::size_t round = 0; round <= basis.size(); ++round) {
    a = relative_lsq(pts, basis, keep);
    if (!nonnegative) break;
    long worst = -1;
    for (long k = 0; k < a.size(); ++k)
      if (keep[std::size_t(k)] && a(k) < 0 && (worst < 0 || a(k) < a(worst))) worst = k;
    if (worst < 0) break;
    keep[std::size_t(worst)] = false;
  }
  return {a.data(), a.data() + a.size()};
}

std::vector<std::vector<double>> powers(const std::vector<Point>& pts, std::size_t terms) {
  std::vector<std::vector<double>> basis(terms, std::vector<double>(pts.size()));
  for (std::size_t j = 0; j < pts.size(); ++j) {
    double xp = 1;
    for (std::size_t k = 0; k < terms; ++k, xp *= pts[j].x) basis[k][j] = xp;
  }
  return basis;
}

DampingModel fit_power(const std::vector<Point>& pts) {
  // ln c = ln a1 + a2 ln x: weighted linear least squares in the logarithm.
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const Point& p : pts) {
    const double lx = std::log(p.x), ly = std::log(p.c);
    sw += p.weight, sx += p.weight * lx, sy += p.weight * ly;
    sxx += p.weight * lx * lx, sxy += p.weight * lx * ly;
  }
  const double den = sw * sxx - sx * sx;
  const double a2 = den > 0 ? (sw * sxy - sx * sy) / den : 0.0;
  const double a1 = std::exp((sy - a2 * sx) / sw);
  return {Kind::PowerLaw, {a1, a2}};
}

DampingModel hybrid_at(const std::vector<Point>& pts, double p2) {
  auto basis = powers(pts, 2);
  basis.emplace_back(pts.size());
  for (std::size_t j = 0; j < pts.size(); ++j) basis[2][j] = std::pow(pts[j].x, p2);
  const auto a = linear_fit(pts, basis, true);
  return {Kind::Hybrid, {a[0], a[1], a[2], p2}};
}

DampingModel fit_hybrid(const std::vector<Point>& pts) {
  // Variable projection: the exponent by a grid and golden-section search, the three linear
  // coefficients exactly at each.
  auto cost = [&](double p2) { return weighted_rms(pts, hybrid_at(pts, p2)); };
  double best = 0.5, best_cost = INFINITY;
  for (double p2 = 0.05; p2 < 0.96; p2 += 0.05)
    if (const double c = cost(p2); c < best_cost) best_cost = c, best = p2;
  double lo = std::max(0.01, best - 0.05), hi = std::min(0.99, best + 0.05);
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int it = 0; it < 40; ++it) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    if (cost(a) < cost(b))
      hi = b;
    else
      lo = a;
  }
  return hybrid_at(pts, 0.5 * (lo + hi));
}

}  // namespace

DampingModel damping_kind(const std::string& text) {
  if (text == "rayleigh") return {Kind::Rayleigh, {0, 0}};
  if (text == "power") return {Kind::PowerLaw, {0, 0}};
  if (text == "hybrid") return {Kind::Hybrid, {0, 0, 0, 0}};
  if (text.rfind("caughey", 0) == 0) {
    int k = 3;
    if (text.size() > 7) {
      if (text[7] != ':' || text.size() != 9 || text[8] < '1' || text[8] > '6')
        throw InputError("--damping '" + text + "': caughey:K takes K from 1 to 6");
      k = text[8] - '0';
    }
    return {Kind::Caughey, std::vector<double>(std::size_t(k), 0.0)};
  }
  throw InputError("--damping '" + text + "': expected rayleigh, caughey:K, power or hybrid");
}

namespace {

DampingModel fit_model(const std::vector<Point>& pts, const DampingModel& shape) {
  switch (shape.kind) {
    case Kind::Rayleigh:
      return {Kind::Rayleigh, linear_fit(pts, powers(pts, 2), true)};
    case Kind::Caughey:
      return {Kind::Caughey, linear_fit(pts, powers(pts, shape.alpha.size()), false)};
    case Kind::PowerLaw:
      return fit_power(pts);
    case Kind::Hybrid:
      return fit_hybrid(pts);
  }
  return shape;
}

// The scatter of real partials about any smooth curve (mode types, mounts, radiation) is far
// above their measurement error. The spread s that makes sum h_i e_i^2 / (sigma_i^2 + s^2) equal
// to the (Huber-weighted) degrees of freedom, a random-effects estimate, is added to every
// partial's variance, so that a few very clean partials do not decide the curve alone; s is at
// least 2 %.
double model_spread(const std::vector<double>& e2, const std::vector<double>& rel,
                    const std::vector<double>& huber, std::size_t parameters) {
  double n = 0;
  for (double h : huber) n += h;
  const double dof = n - double(parameters);
  if (dof <= 0) return 0.02;
  auto chi2 = [&](double s) {
    double sum = 0;
    for (std::size_t i = 0; i < e2.size(); ++i) sum += huber[i] * e2[i] / (rel[i] * rel[i] + s * s);
    return sum;
  };
  double lo = 0.02, hi = 10;
  if (chi2(lo) <= dof) return lo;
  for (int it = 0; it < 60; ++it) {
    const double mid = std::sqrt(lo * hi);
    (chi2(mid) > dof ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace

DampingFit fit_damping(const std::vector<Feature>& features, const DampingModel& shape) {
  std::vector<Point> pts;
  std::vector<double> rel;
  for (const Feature& f : features) {
    if (!(f.decay > 0) || !(f.frequency > 0)) continue;
    const double w = 2 * std::numbers::pi * f.frequency;
    rel.push_back(f.decay_sigma / f.decay);
    pts.push_back({w * w, 2 * f.decay, 0.0, 2 * f.decay});
  }
  const std::size_t need = shape.kind == Kind::Hybrid ? 4 : shape.alpha.size();
  if (pts.size() < need)
    throw InputError("damping fit: " + std::to_string(pts.size()) +
                     " decaying partials, fewer than the model's " + std::to_string(need) +
                     " parameters");
  DampingFit fit;
  fit.partials = pts.size();
  // Iteratively reweighted: a partial more than 2.5 deviations off the curve (a decay spoilt by
  // a beat, or a mode of another kind) is weighted down as Huber's loss does, and the spread is
  // estimated again from the others.
  double spread = 0.02;
  std::vector<double> huber(pts.size(), 1.0), e2(pts.size());
  for (int round = 0; round < 6; ++round) {
    for (std::size_t i = 0; i < pts.size(); ++i)
      pts[i].weight = huber[i] / (rel[i] * rel[i] + spread * spread);
    fit.model = fit_model(pts, shape);
    try {
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const double beta = fit.model.coefficient(std::sqrt(pts[i].x));
        const double e = std::log(std::max(beta, 1e-300) / pts[i].c);
        e2[i] = e * e;
        // Dividing by the last beta makes the next linear fit a Gauss-Newton step on ln(beta/c).
        pts[i].scale = std::max(beta, 1e-3 * pts[i].c);
        const double z = std::sqrt(e2[i] / (rel[i] * rel[i] + spread * spread));
        huber[i] = z > 2.5 ? 2.5 / z : 1.0;
      }
    } catch (const InputError&) {
      break;  // a curve negative at some partial: keep it, the check below says so
    }
    const double next = model_spread(e2, rel, huber, need);
    if (round > 0 && std::abs(next - spread) < 0.01 * spread) break;
    spread = next;
  }
  fit.spread = spread;
  // A Caughey series fitted freely may turn negative between or beyond the partials.
  double lo = INFINITY, hi = 0;
  for (const Point& p : pts) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
  for (int i = 0; i <= 64; ++i) {
    const double x = lo * std::pow(hi / lo, i / 64.0);
    double c = 0, xp = 1;
    for (double a : fit.model.alpha) c += a * xp, xp *= x;
    if (fit.model.kind == Kind::Caughey && c < 0) {
      fit.warnings.push_back("the fitted Caughey series is negative near " +
                             std::to_string(std::sqrt(x) / (2 * std::numbers::pi)) +
                             " Hz; try fewer terms or another model");
      break;
    }
  }
  if (fit.warnings.empty()) fit.rms_relative_error = weighted_rms(pts, fit.model);
  return fit;
}

}  // namespace chladni::estimate
