#pragma once
// The Burton-Miller matrix as a hierarchical matrix (hmat-oss: cluster tree on the element
// centroids, standard admissibility, ACA+ compression of the far blocks), for surfaces too large
// for a dense matrix. Internal to the BEM files.
#include <complex>
#include <memory>
#include <span>
#include <vector>

#include "chladni/precompute/bem.hpp"

namespace chladni::precompute::bem_detail {

class HMatrixSystem {
 public:
  using cd = std::complex<double>;
  HMatrixSystem(const BemMesh& mesh, const BemSolver::NearCache& cache, const BemOptions& o);
  ~HMatrixSystem();
  HMatrixSystem(const HMatrixSystem&) = delete;
  HMatrixSystem& operator=(const HMatrixSystem&) = delete;

  /// Compresses A(k) (relative accuracy o.hmatrix_epsilon) and returns the right-hand sides
  /// bs[v] = B qs[v] exactly (centroid rule over all elements plus the near corrections).
  void assemble(double k, std::span<const std::vector<cd>> qs, std::vector<std::vector<cd>>& bs);
  /// y = A x for the last assembled k (element numbering).
  void apply(const cd* x, cd* y) const;
  /// Hierarchical LU of the last assembled A at the coarser o.hmatrix_lu_epsilon: the
  /// preconditioner of the next solves. Throws InternalError when it fails.
  void factorize();
  /// x = LU^-1 x with the last factorization.
  void precondition(cd* x) const;
  bool factorized() const;
  double factor_k() const;
  /// Bytes held by the compressed matrix and its factors.
  std::size_t bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chladni::precompute::bem_detail
