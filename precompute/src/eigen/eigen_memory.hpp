#pragma once
// What the eigen-solve needs in memory, from the symbolic analysis of its factor: the checks
// before assembly and before meshing, and the Lanczos basis the budget leaves room for.
#include <string>

#include "chladni/precompute/eigensolve.hpp"
#include "cholmod_factor.hpp"

namespace chladni::precompute {

std::string gigabytes(double bytes);  ///< "1.23 GB"

/// The matrices and the copies the factorization makes, per entry of K (bytes).
constexpr double kFactorizingBytesPerEntry = 12 + 4 + 8 + 8;

/// The largest Lanczos basis (vectors) the budget leaves room for after `reserved` bytes, at least
/// the smallest worth factorizing for; `by_memory` says whether the budget, not the count, set it.
Eigen::Index lanczos_dim(Eigen::Index n, double reserved, const EigenOptions& o,
                         bool* by_memory = nullptr);

/// What the eigen-solve of n DOFs with factor `est` and K of `entries` entries needs at most
/// (bytes). Throws BudgetError above o.max_memory, with the parts; `how` ends the parenthesis
/// and `amount` qualifies the total ("about ", "at least ").
double check_budget(Eigen::Index n, const FactorEstimate& est, double entries,
                    const EigenOptions& o, const std::string& how, const char* amount = "about ");

/// The bytes the iteration may count on before the basis: the factor, the matrices and the
/// Ritz vectors.
double iteration_reserve(Eigen::Index n, const FactorEstimate& est, double entries,
                         const EigenOptions& o);

}  // namespace chladni::precompute
