#pragma once
// Acoustic transfer of a modal object: per mode, the far-field multipole expansion of the pressure
// it radiates per unit modal amplitude (DESIGN.md conventions, e^(-i w t)):
//   p(x) = sum_(l<=L) sum_m c_lm h_l(k r) Y_lm(x^),   x = position - centre in the object frame,
// with real orthonormal Y_lm (core/spherical.hpp). Stored as a_lm = c_lm h_l(k R): each term's
// pressure at the reference radius R, which keeps every number in float range and makes the
// coefficients' sizes mean something (Pa). Valid for r >= R, the radius of the sphere about the
// centre that encloses the surface; nearer points are evaluated at R in their direction.
#include <complex>
#include <cstdint>
#include <string>
#include <vector>

#include "chladni/core/vec3.hpp"

namespace chladni {

/// How a mode's field was found: equivalent sources fitted to the Neumann data, a
/// boundary-element (Burton-Miller) solve, or the time-domain wave solve (since format 1.3).
enum class TransferMethod : uint16_t { Sources = 0, Bem = 1, Wave = 2 };
const char* to_string(TransferMethod method);

struct ModeTransfer {
  double wavenumber = 0;  ///< k = omega / c (rad/m)
  uint32_t order = 0;     ///< L
  /// Equivalent sources used in the fit; boundary elements for BEM; grid cells for the wave solve.
  uint32_t sources = 0;
  /// Sources: relative residual of the Neumann fit at collocation points. BEM: relative residual
  /// of the linear solve. Wave: relative residual of the chord's separation over its window.
  float fit_residual = 0;
  /// Sources: relative Neumann error at held-out surface points. BEM: relative null-field error
  /// (the representation must vanish) at interior points deeper than 1.5 elements; 0 where the
  /// walls are too thin to hold such points. Wave: the separation's standard error relative to
  /// the mode's own recorded amplitude.
  float held_out_error = 0;
  float expansion_error = 0;  ///< relative error of the expansion against the surface at 2R
  TransferMethod method = TransferMethod::Sources;
  uint16_t iterations = 0;  ///< BEM: GMRES iterations (0: direct LU); wave: chord (1-based)
  uint64_t offset = 0;      ///< first coefficient in Transfer::coefficients
};

struct Transfer {
  /// Fits whose held-out error exceeds this are flagged as poor (chladni info).
  static constexpr float kPoorFit = 0.3f;
  /// Beyond this the fit misses the surface data by more than the data itself: the runtime falls
  /// back to the compact-source estimate for such modes.
  static constexpr float kUnusable = 1.0f;

  Vec3 centre{0, 0, 0};        ///< expansion centre (m, object frame)
  double radius = 0;           ///< R (m)
  double sound_speed = 343.0;  ///< c (m/s)
  double air_density = 1.204;  ///< rho0 (kg/m^3)
  std::vector<ModeTransfer> modes;
  std::vector<std::complex<float>> coefficients;  ///< a_lm per mode, (L+1)^2 each, sh_index order

  std::size_t mode_count() const { return modes.size(); }
  const std::complex<float>* coefficients_of(std::size_t mode) const {
    return coefficients.data() + modes[mode].offset;
  }
  /// Appends one mode's expansion (coefficients a_lm, (order+1)^2 of them).
  void add_mode(ModeTransfer mode, const std::vector<std::complex<double>>& a);
  /// Complex pressure per unit modal amplitude at x (object frame), in double precision.
  std::complex<double> pressure(std::size_t mode, const Vec3& x) const;
  bool poor(std::size_t mode) const { return !(modes[mode].held_out_error <= kPoorFit); }
  bool usable(std::size_t mode) const { return modes[mode].held_out_error <= kUnusable; }
  /// How many modes are poor().
  std::size_t poor_fits() const {
    std::size_t n = 0;
    for (std::size_t i = 0; i < modes.size(); ++i) n += poor(i);
    return n;
  }
  /// Throws InputError naming the first bad count, order or non-finite value.
  void validate() const;
  /// The listed modes only, in that order.
  Transfer subset(const std::vector<std::size_t>& kept) const;
};

}  // namespace chladni
