#include "chladni/core/transfer.hpp"

#include <algorithm>
#include <cmath>

#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"

namespace chladni {
namespace {
constexpr uint32_t kMaxOrder = 200;
}

const char* to_string(TransferMethod method) {
  return method == TransferMethod::Bem    ? "bem"
         : method == TransferMethod::Wave ? "wave"
                                          : "sources";
}

void Transfer::add_mode(ModeTransfer mode, const std::vector<std::complex<double>>& a) {
  if (a.size() != sh_count(static_cast<int>(mode.order)))
    throw InternalError("transfer: coefficient count does not match the order");
  mode.offset = coefficients.size();
  for (const auto& z : a) coefficients.emplace_back(float(z.real()), float(z.imag()));
  modes.push_back(mode);
}

std::complex<double> Transfer::pressure(std::size_t mode, const Vec3& x) const {
  const ModeTransfer& m = modes[mode];
  const int L = static_cast<int>(m.order);
  const Vec3 d = sub(x, centre);
  const double r = std::max(std::sqrt(dot(d, d)), radius);
  std::vector<double> y(sh_count(L));
  std::vector<std::complex<double>> ratio(static_cast<std::size_t>(L) + 1);
  real_sh(L, d, y.data());
  sph_hankel1_ratio(L, m.wavenumber * r, m.wavenumber * radius, ratio.data());
  const std::complex<float>* a = coefficients_of(mode);
  std::complex<double> p = 0.0;
  for (int l = 0; l <= L; ++l) {
    std::complex<double> s = 0.0;
    for (int mm = -l; mm <= l; ++mm) {
      const std::size_t k = sh_index(l, mm);
      s += std::complex<double>(a[k].real(), a[k].imag()) * y[k];
    }
    p += ratio[l] * s;
  }
  return p;
}

void Transfer::validate() const {
  if (!is_finite(centre)) throw InputError("transfer: centre is not finite");
  if (!(radius > 0) || !std::isfinite(radius)) throw InputError("transfer: radius must be > 0");
  if (!(sound_speed > 0) || !std::isfinite(sound_speed) || !(air_density > 0) ||
      !std::isfinite(air_density)) {
    throw InputError("transfer: sound speed and air density must be finite and > 0");
  }
  uint64_t next = 0;
  for (std::size_t i = 0; i < modes.size(); ++i) {
    const ModeTransfer& m = modes[i];
    const std::string who = "transfer of mode " + std::to_string(i);
    if (!(m.wavenumber > 0) || !std::isfinite(m.wavenumber))
      throw InputError(who + ": wavenumber must be finite and > 0");
    if (m.order > kMaxOrder)
      throw InputError(who + ": order " + std::to_string(m.order) + " exceeds " +
                       std::to_string(kMaxOrder));
    if (m.offset != next) throw InputError(who + ": coefficients are not contiguous");
    next += sh_count(static_cast<int>(m.order));
    if (next > coefficients.size())
      throw InputError(who + ": needs more coefficients than are stored");
    if (!std::isfinite(m.fit_residual) || !std::isfinite(m.held_out_error) ||
        !std::isfinite(m.expansion_error)) {
      throw InputError(who + ": fit statistics are not finite");
    }
  }
  if (next != coefficients.size())
    throw InputError("transfer: " + std::to_string(coefficients.size() - next) +
                     " coefficients belong to no mode");
  for (std::size_t k = 0; k < coefficients.size(); ++k) {
    if (!std::isfinite(coefficients[k].real()) || !std::isfinite(coefficients[k].imag()))
      throw InputError("transfer: coefficient " + std::to_string(k) + " is not finite");
  }
}

Transfer Transfer::subset(const std::vector<std::size_t>& kept) const {
  Transfer out = *this;
  out.modes.clear();
  out.coefficients.clear();
  for (std::size_t i : kept) {
    ModeTransfer m = modes.at(i);
    const std::complex<float>* a = coefficients_of(i);
    m.offset = out.coefficients.size();
    out.coefficients.insert(out.coefficients.end(), a, a + sh_count(static_cast<int>(m.order)));
    out.modes.push_back(m);
  }
  return out;
}

}  // namespace chladni
