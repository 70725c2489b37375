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
};

// Weighted least squares of sum_k a_k g_k(x_j) against c_j in relative error; `keep` marks the
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
    const double s = std::sqrt(pts[j].weight) / pts[j].c;
    for (std::size_t q = 0; q < cols.size(); ++q) A(long(j), long(q)) = basis[cols[q]][j] * s;
    b(long(j)) = std::sqrt(pts[j].weight);
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
    const double e = model.coefficient(std::sqrt(p.x)) / p.c - 1;
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

DampingFit fit_damping(const std::vector<Feature>& features, const DampingModel& shape) {
  std::vector<Point> pts;
  for (const Feature& f : features) {
    if (!(f.decay > 0) || !(f.frequency > 0)) continue;
    const double w = 2 * std::numbers::pi * f.frequency;
    const double rel = f.decay_sigma / f.decay;
    pts.push_back({w * w, 2 * f.decay, 1.0 / (rel * rel + 0.02 * 0.02)});
  }
  const std::size_t need = shape.kind == Kind::Hybrid ? 4 : shape.alpha.size();
  if (pts.size() < need)
    throw InputError("damping fit: " + std::to_string(pts.size()) +
                     " decaying partials, fewer than the model's " + std::to_string(need) +
                     " parameters");
  DampingFit fit;
  fit.partials = pts.size();
  switch (shape.kind) {
    case Kind::Rayleigh:
      fit.model = {Kind::Rayleigh, linear_fit(pts, powers(pts, 2), true)};
      break;
    case Kind::Caughey:
      fit.model = {Kind::Caughey, linear_fit(pts, powers(pts, shape.alpha.size()), false)};
      break;
    case Kind::PowerLaw:
      fit.model = fit_power(pts);
      break;
    case Kind::Hybrid:
      fit.model = fit_hybrid(pts);
      break;
  }
  // A Caughey series fitted freely may turn negative between or beyond the partials.
  double lo = INFINITY, hi = 0;
  for (const Point& p : pts) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
  for (int i = 0; i <= 64; ++i) {
    const double x = lo * std::pow(hi / lo, i / 64.0);
    DampingModel m = fit.model;
    double c = 0, xp = 1;
    for (double a : m.alpha) c += a * xp, xp *= x;
    if (m.kind == Kind::Caughey && c < 0) {
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
