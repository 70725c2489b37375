#include <cmath>
#include <numbers>

#include "../parallel.hpp"
#include "chladni/precompute/transfer_kernels.hpp"

namespace chladni::precompute {
namespace {

constexpr double kInv4Pi = 0.25 / std::numbers::pi;

class CpuTransferKernels final : public TransferKernels {
 public:
  explicit CpuTransferKernels(int threads) : threads_(threads) {}

  void matrix(std::span<const Vec3> x, std::span<const Vec3> n, std::span<const Vec3> y, double k,
              std::complex<double>* out) override {
    const std::size_t np = x.size();
    const bool neumann = !n.empty();
    parallel_for(y.size(), threads_, [&](std::size_t b, std::size_t e) {
      for (std::size_t s = b; s < e; ++s) {
        std::complex<double>* col = out + s * np;
        for (std::size_t p = 0; p < np; ++p) {
          const Vec3 d = sub(x[p], y[s]);
          const double r = std::sqrt(dot(d, d));
          std::complex<double> g = std::polar(kInv4Pi / r, k * r);
          // dG/dn = G (ik - 1/r) (d.n) / r
          if (neumann) g *= std::complex<double>(-1.0 / r, k) * (dot(d, n[p]) / r);
          col[p] = g;
        }
      }
    });
  }

  void field(std::span<const Vec3> x, std::span<const Vec3> y,
             std::span<const std::complex<double>> q, double k,
             std::complex<double>* out) override {
    parallel_for(x.size(), threads_, [&](std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) {
        std::complex<double> p = 0.0;
        for (std::size_t s = 0; s < y.size(); ++s) {
          const Vec3 d = sub(x[j], y[s]);
          const double r = std::sqrt(dot(d, d));
          p += q[s] * std::polar(1.0 / r, k * r);
        }
        out[j] = p * kInv4Pi;
      }
    });
  }

  std::string name() const override { return "cpu (double)"; }
  bool thread_safe() const override { return true; }

 private:
  int threads_;
};

}  // namespace

std::unique_ptr<TransferKernels> make_cpu_transfer_kernels(int threads) {
  return std::make_unique<CpuTransferKernels>(threads);
}

}  // namespace chladni::precompute
