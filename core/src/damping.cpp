#include "chladni/core/damping.hpp"

#include <charconv>
#include <cmath>
#include <exception>
#include <numbers>
#include <sstream>

#include "chladni/core/error.hpp"

namespace chladni {
namespace {

const char* kind_name(DampingModel::Kind k) {
  switch (k) {
    case DampingModel::Kind::Rayleigh:
      return "rayleigh";
    case DampingModel::Kind::Caughey:
      return "caughey";
    case DampingModel::Kind::PowerLaw:
      return "power";
    case DampingModel::Kind::Hybrid:
      return "hybrid";
  }
  return "?";
}

}  // namespace

void DampingModel::validate() const {
  const std::size_t n = alpha.size();
  const bool count_ok = (kind == Kind::Caughey && n >= 1) ||
                        ((kind == Kind::Rayleigh || kind == Kind::PowerLaw) && n == 2) ||
                        (kind == Kind::Hybrid && n == 4);
  if (!count_ok) {
    throw InputError(std::string("damping model '") + kind_name(kind) + "' got " +
                     std::to_string(n) + " parameters");
  }
  for (std::size_t j = 0; j < n; ++j) {
    if (!std::isfinite(alpha[j])) {
      throw InputError(std::string("damping model '") + kind_name(kind) + "': parameter " +
                       std::to_string(j + 1) + " is not finite");
    }
  }
}

double DampingModel::coefficient(double omega) const {
  const double x = omega * omega;
  double c = 0.0;
  switch (kind) {
    case Kind::Rayleigh:
      c = alpha[0] + alpha[1] * x;
      break;               // beta(x) = a1 + a2 x
    case Kind::Caughey: {  // beta(x) = sum_j a_j x^(j-1)
      double xp = 1.0;
      for (double a : alpha) {
        c += a * xp;
        xp *= x;
      }
      break;
    }
    case Kind::PowerLaw:
      c = alpha[0] * std::pow(x, alpha[1]);
      break;  // beta(x) = a1 x^a2
    case Kind::Hybrid:
      c = alpha[0] + alpha[1] * x + alpha[2] * std::pow(x, alpha[3]);
      break;
  }
  if (!std::isfinite(c) || c < 0.0) {
    std::ostringstream os;
    os << "damping model " << to_string() << " gives c = " << c << " at omega = " << omega
       << " rad/s (must be finite and >= 0)";
    throw InputError(os.str());
  }
  return c;
}

DampingModel DampingModel::parse(std::string_view text) {
  const auto colon = text.find(':');
  if (colon == std::string_view::npos) {
    throw InputError("damping '" + std::string(text) +
                     "': expected NAME:A1,A2,... with NAME rayleigh, caughey, power or hybrid");
  }
  const std::string_view name = text.substr(0, colon);
  DampingModel m;
  if (name == "rayleigh")
    m.kind = Kind::Rayleigh;
  else if (name == "caughey")
    m.kind = Kind::Caughey;
  else if (name == "power")
    m.kind = Kind::PowerLaw;
  else if (name == "hybrid")
    m.kind = Kind::Hybrid;
  else
    throw InputError("damping '" + std::string(text) + "': unknown model '" + std::string(name) +
                     "'");
  m.alpha.clear();
  std::string_view rest = text.substr(colon + 1);
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    const std::string item(rest.substr(0, comma));
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size()) {
      throw InputError("damping '" + std::string(text) + "': '" + item + "' is not a number");
    }
    m.alpha.push_back(v);
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  m.validate();
  return m;
}

std::string DampingModel::to_string() const {
  std::ostringstream os;
  os << kind_name(kind) << ':';
  for (std::size_t j = 0; j < alpha.size(); ++j) os << (j ? "," : "") << alpha[j];
  return os.str();
}

void damping_ratio_curve(const DampingModel& m, double lo, double hi, int steps,
                         std::vector<double>& f, std::vector<double>& zeta) {
  for (int k = 0; k <= steps; ++k) {
    const double x = lo * std::pow(hi / lo, double(k) / steps), w = 2 * std::numbers::pi * x;
    f.push_back(x);
    try {
      zeta.push_back(m.coefficient(w) / (2 * w));
    } catch (const std::exception&) {
      zeta.push_back(NAN);
    }
  }
}

}  // namespace chladni
