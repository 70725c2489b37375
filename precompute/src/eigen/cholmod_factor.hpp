#pragma once
// Supernodal Cholesky through CHOLMOD's long-index interface, every call checked. The symbolic
// analysis comes first and reports what the numeric factorization will need (entries of L,
// bytes, flops), so a caller can refuse before the memory is spent; factorizations then reuse it.
// Only cholmod_factor.cpp includes CHOLMOD.
#include <cstdint>
#include <memory>
#include <vector>

#include "chladni/precompute/fem.hpp"

namespace chladni::precompute {

struct FactorEstimate {
  double entries = 0;  ///< nonzeros of L
  double bytes = 0;    ///< memory of the numeric factor (values, indices, workspace)
  double flops = 0;    ///< floating-point operations of one factorization
};

class CholmodFactor {
 public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  /// Orders and analyzes the pattern of A (symmetric, both triangles stored; the upper one is
  /// kept, in long indices). With
  /// `block` > 1, A is made of dense block x block blocks (3: a node's displacements), and the
  /// ordering is found on the graph of the blocks, a ninth of the entries, then expanded; or,
  /// where `block_order` holds one, taken from it (an analysis of that graph has found it).
  /// Throws InputError when CHOLMOD runs out of memory or the problem exceeds its index range.
  FactorEstimate analyze(const SparseMatrix& A, int block = 1,
                         const std::vector<std::int64_t>* block_order = nullptr);
  /// The fill-reducing ordering the last analysis chose (row k of L is row order[k] of A).
  std::vector<std::int64_t> ordering() const;
  /// Numeric factorization of A + beta B: A must have the analyzed pattern, B's must lie within
  /// it (K - sigma M is factorized without a copy of it). False when the sum is not positive
  /// definite; throws InputError on any other CHOLMOD failure.
  bool factorize(const SparseMatrix& A, double beta = 0, const SparseMatrix* B = nullptr);
  /// Column-major x (rows x cols) in place: x <- P^T L^-T x, and x <- L^-1 P x.
  void upper_solve(double* x, long rows, long cols);
  void lower_solve(double* x, long rows, long cols);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chladni::precompute
