#include "symmetric_product.hpp"

#include "../huge_pages.hpp"

#include <algorithm>
#include <thread>
#include <vector>

namespace chladni::precompute {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Rows [lo, hi) of Y = A X, X and Y row-major with B (or, for B = 0, b) columns.
template <int B>
void rows(const SparseMatrix& A, const double* x, double* y, Eigen::Index b, Eigen::Index lo,
          Eigen::Index hi) {
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* val = A.valuePtr();
  const Eigen::Index w = B > 0 ? B : b;
  double acc[16];
  for (Eigen::Index r = lo; r < hi; ++r) {
    std::fill(acc, acc + w, 0.0);
    for (int p = outer[r]; p < outer[r + 1]; ++p) {
      const double a = val[p];
      const double* xr = x + Eigen::Index(inner[p]) * w;
      for (Eigen::Index c = 0; c < w; ++c) acc[c] += a * xr[c];
    }
    std::copy(acc, acc + w, y + r * w);
  }
}

}  // namespace

void symmetric_product(const SparseMatrix& A, const Eigen::MatrixXd& X, Eigen::MatrixXd& Y) {
  const Eigen::Index n = A.rows();
  const double* before = Y.data();
  Y.resize(n, X.cols());
  if (Y.data() != before) advise_huge_pages(Y);  // only a fresh buffer is still untouched
  constexpr Eigen::Index kChunk = 16;  // columns at a time: the row-major copies stay small
  const int threads = int(std::clamp<Eigen::Index>(std::thread::hardware_concurrency(), 1,
                                                   std::max<Eigen::Index>(1, n / 4096)));
  RowMajor x, y;
  for (Eigen::Index c0 = 0; c0 < X.cols(); c0 += kChunk) {
    const Eigen::Index b = std::min(kChunk, X.cols() - c0);
    x = X.middleCols(c0, b);
    y.resize(n, b);
    auto work = [&](Eigen::Index lo, Eigen::Index hi) {
      if (b == 16)  // whole chunks of a wide X
        rows<16>(A, x.data(), y.data(), b, lo, hi);
      else if (b == 8)  // the eigen-solve's blocks
        rows<8>(A, x.data(), y.data(), b, lo, hi);
      else
        rows<0>(A, x.data(), y.data(), b, lo, hi);
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t)
      pool.emplace_back(work, n * t / threads, n * (t + 1) / threads);
    work(0, n / threads);
    for (auto& th : pool) th.join();
    Y.middleCols(c0, b) = y;
  }
}

}  // namespace chladni::precompute
