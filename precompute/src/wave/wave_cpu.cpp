// The CPU stepper: z-slabs per thread, in step with a barrier; rows vectorized, with clones for
// AVX2 and AVX-512 chosen at load time where the compiler supports them.
#include <algorithm>
#include <barrier>
#include <numeric>
#include <thread>

#include "wave_grid.hpp"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define CHLADNI_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define CHLADNI_CLONES
#endif

namespace chladni::precompute::wave {
namespace {

// w' = a w - b (p[i + s] - p[i]) over a row, a and b per face (x) or one value (y, z).
CHLADNI_CLONES void velocity_row(float* __restrict w, const float* __restrict p, std::size_t s,
                                 std::size_t n, const float* __restrict a,
                                 const float* __restrict b) {
  for (std::size_t i = 0; i < n; ++i) w[i] = a[i] * w[i] - b[i] * (p[i + s] - p[i]);
}

CHLADNI_CLONES void velocity_row(float* __restrict w, const float* __restrict p, std::size_t s,
                                 std::size_t n, float a, float b) {
  for (std::size_t i = 0; i < n; ++i) w[i] = a * w[i] - b * (p[i + s] - p[i]);
}

// Unsplit interior update of cells [i0, i1) of a row (i0 >= 1): p -= lambda div w.
CHLADNI_CLONES void pressure_row(float* __restrict p, const float* __restrict wx,
                                 const float* __restrict wy, const float* __restrict wy0,
                                 const float* __restrict wz, const float* __restrict wz0,
                                 std::size_t i0, std::size_t i1, float lambda) {
  for (std::size_t i = i0; i < i1; ++i)
    p[i] -= lambda * ((wx[i] - wx[i - 1]) + (wy[i] - wy0[i]) + (wz[i] - wz0[i]));
}

struct Rows {
  const Problem& P;
  float *p, *px, *py, *w[3];
  const float* zero;  // a row of zeros for the missing neighbours at j = 0 or k = 0

  // Split-field update of cell i of the row at (j, k): x, y and z parts damped separately.
  void split_cell(std::size_t r, std::size_t i, std::size_t j, std::size_t k, const float* wy0,
                  const float* wz0) const {
    const std::size_t c = r + i;
    const float dx = w[0][c] - (i > 0 ? w[0][c - 1] : 0.0f);
    const float dy = w[1][c] - wy0[i], dz = w[2][c] - wz0[i];
    const float x = P.pa[0][i] * px[c] - P.pb[0][i] * dx;
    const float y = P.pa[1][j] * py[c] - P.pb[1][j] * dy;
    const float z = P.pa[2][k] * (p[c] - px[c] - py[c]) - P.pb[2][k] * dz;
    px[c] = x, py[c] = y, p[c] = x + y + z;
  }

  void velocity(std::size_t j, std::size_t k) const {
    const Grid& g = P.grid;
    const std::size_t n0 = g.n[0], s1 = g.stride(1), s2 = g.stride(2), r = j * s1 + k * s2;
    velocity_row(w[0] + r, p + r, 1, n0 - 1, P.wa[0].data(), P.wb[0].data());
    if (j + 1 < g.n[1]) velocity_row(w[1] + r, p + r, s1, n0, P.wa[1][j], P.wb[1][j]);
    if (k + 1 < g.n[2]) velocity_row(w[2] + r, p + r, s2, n0, P.wa[2][k], P.wb[2][k]);
  }

  void pressure(std::size_t j, std::size_t k) const {
    const Grid& g = P.grid;
    const std::size_t n0 = g.n[0], s1 = g.stride(1), s2 = g.stride(2), r = j * s1 + k * s2;
    const float* wy0 = j > 0 ? w[1] + r - s1 : zero;
    const float* wz0 = k > 0 ? w[2] + r - s2 : zero;
    const bool layer = j < P.pml_lo[1] || j >= P.pml_hi[1] || k < P.pml_lo[2] || k >= P.pml_hi[2];
    const std::size_t i0 = layer ? n0 : std::max<std::size_t>(P.pml_lo[0], 1);
    const std::size_t i1 = layer ? n0 : P.pml_hi[0];
    for (std::size_t i = 0; i < std::min(i0, n0); ++i) split_cell(r, i, j, k, wy0, wz0);
    if (i1 > i0)
      pressure_row(p + r, w[0] + r, w[1] + r, wy0, w[2] + r, wz0, i0, i1, P.pb[0][P.pml_lo[0]]);
    for (std::size_t i = std::max(i1, i0); i < n0; ++i) split_cell(r, i, j, k, wy0, wz0);
  }
};

class CpuStepper final : public Stepper {
 public:
  explicit CpuStepper(int threads) : threads_(threads) {}

  void run(const Problem& P, std::vector<float>& samples,
           const std::function<void(std::size_t)>& progress) override {
    const Grid& g = P.grid;
    const std::size_t cells = g.cells(), J = P.series;
    std::vector<float> p(cells, 0.0f), px(cells, 0.0f), py(cells, 0.0f);
    std::array<std::vector<float>, 3> w;
    for (auto& v : w) v.assign(cells, 0.0f);
    std::vector<float> zero(g.n[0], 0.0f);
    Rows rows{P,          p.data(), px.data(), py.data(), {w[0].data(), w[1].data(), w[2].data()},
              zero.data()};
    const std::size_t hw = std::max(1u, std::thread::hardware_concurrency());
    const std::size_t T = std::min<std::size_t>(threads_ > 0 ? std::size_t(threads_) : hw, g.n[2]);
    // Blocked faces by plane: each is set right after its plane's velocities.
    std::vector<std::size_t> order(P.blocked.size());
    std::iota(order.begin(), order.end(), 0);
    const std::size_t s2 = g.stride(2);
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return P.blocked.cell[a] < P.blocked.cell[b]; });
    auto slab = [&](std::size_t t) {
      return std::pair<std::size_t, std::size_t>{g.n[2] * t / T, g.n[2] * (t + 1) / T};
    };
    std::vector<std::size_t> plane_begin(g.n[2] + 1, order.size());
    for (std::size_t k = 0, f = 0; k <= g.n[2]; ++k) {
      while (f < order.size() && P.blocked.cell[order[f]] / s2 < k) ++f;
      plane_begin[k] = f;
    }
    const std::size_t nrec = P.record.size(), ns = P.samples();
    samples.assign(ns * nrec * 2, 0.0f);
    std::barrier sync(static_cast<std::ptrdiff_t>(T));

    auto worker = [&](std::size_t t) {
      const auto [k0, k1] = slab(t);
      const std::size_t r0 = nrec * t / T, r1 = nrec * (t + 1) / T;
      // Plane by plane, velocity then pressure while the plane is in cache: the pressure of
      // plane k needs the new z velocities of plane k - 1, the velocity of plane k the old
      // pressure of plane k + 1. The slab's last plane's velocities go first, so the next slab
      // may update its first plane's pressure after the barrier.
      for (std::size_t n = 0; n < P.steps; ++n) {
        const float* drive = P.drive.data() + n * J;
        auto velocity = [&](std::size_t k) {
          for (std::size_t j = 0; j < g.n[1]; ++j) rows.velocity(j, k);
          for (std::size_t f = plane_begin[k]; f < plane_begin[k + 1]; ++f) {
            const std::size_t q = order[f];
            const float* amp = P.amplitude.data() + q * J;
            float v = 0;
            for (std::size_t m = 0; m < J; ++m) v += amp[m] * drive[m];
            w[P.blocked.axis[q]][P.blocked.cell[q]] = v;
          }
        };
        auto pressure = [&](std::size_t k) {
          for (std::size_t j = 0; j < g.n[1]; ++j) rows.pressure(j, k);
        };
        velocity(k1 - 1);
        sync.arrive_and_wait();
        for (std::size_t k = k0; k + 1 < k1; ++k) velocity(k), pressure(k);
        pressure(k1 - 1);
        sync.arrive_and_wait();
        if (n >= P.first_sample && (n - P.first_sample) % P.stride == 0) {
          float* out = samples.data() + (n - P.first_sample) / P.stride * nrec * 2;
          for (std::size_t q = r0; q < r1; ++q) {
            const uint32_t a = P.record.axis[q];
            const std::size_t c = P.record.cell[q], d = g.stride(int(a));
            // Four-point interpolation to the face (the two-point mean reads a wave crossing the
            // face cos(kh/2) low: 8 % at 8 cells a wavelength; this, 0.8 %).
            out[2 * q] = (9.0f * (p[c] + p[c + d]) - (p[c - d] + p[c + 2 * d])) * (1.0f / 16.0f);
            out[2 * q + 1] = w[a][c];
          }
          sync.arrive_and_wait();
        }
        if (t == 0 && progress && (n + 1) % 256 == 0) progress(n + 1);
      }
    };
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < T; ++t) pool.emplace_back(worker, t);
    worker(0);
    for (auto& th : pool) th.join();
    if (progress) progress(P.steps);
  }

  std::string name() const override { return "cpu"; }

 private:
  int threads_;
};

}  // namespace

std::unique_ptr<Stepper> make_cpu_stepper(int threads) {
  return std::make_unique<CpuStepper>(threads);
}

}  // namespace chladni::precompute::wave
