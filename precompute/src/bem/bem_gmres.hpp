#pragma once
// Restarted GMRES with right preconditioning for the Burton-Miller systems, whatever holds the
// matrix (dense rows or a hierarchical matrix). Internal to the BEM files.
#include <complex>
#include <functional>
#include <vector>

#include "chladni/precompute/bem.hpp"

namespace chladni::precompute::bem_detail {

/// y = A x (n entries each).
using MatVec = std::function<void(const std::complex<double>* x, std::complex<double>* y)>;
/// x = M^-1 x in place.
using Precondition = std::function<void(std::complex<double>* x)>;

/// Solves A M^-1 z = b, x = M^-1 z by GMRES(o.gmres_restart) from the x given, until the relative
/// residual is below o.gmres_tolerance or o.gmres_max_iterations were taken. Returns the
/// iterations taken. Buffers passed to apply and precondition hold n + pad entries.
int gmres(const MatVec& apply, const Precondition& precondition,
          const std::vector<std::complex<double>>& b, const BemOptions& o, std::size_t pad,
          std::vector<std::complex<double>>& x);

double norm2(const std::vector<std::complex<double>>& v);

}  // namespace chladni::precompute::bem_detail
