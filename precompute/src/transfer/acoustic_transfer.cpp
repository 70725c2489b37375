#include "chladni/precompute/acoustic_transfer.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>

#include "../blas_threads.hpp"
#include "../parallel.hpp"
#include "../surface/surface_pieces.hpp"
#include "../timing.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/spherical.hpp"

// Level 3 only: this file is built without EIGEN_USE_BLAS because Debian 12's OpenBLAS
// 0.3.21 zgemv_n kernel reads past the end of its operands (OpenBLAS issue #4013), which
// ASan caught inside Eigen's BLAS-backed LLT; Eigen's own kernels do the level-2 work.
extern "C" void zherk_(const char* uplo, const char* trans, const int* n, const int* k,
                       const double* alpha, const double* a, const int* lda, const double* beta,
                       double* c, const int* ldc);

namespace chladni::precompute {
namespace {

using cd = std::complex<double>;

double dist2(const Vec3& a, const Vec3& b) {
  const Vec3 d = sub(a, b);
  return dot(d, d);
}

// First `count` of `points` in farthest-point order, starting from the one farthest from `from`.
std::vector<uint32_t> farthest_points(const std::vector<Vec3>& points, std::size_t count,
                                      const Vec3& from) {
  const std::size_t n = points.size();
  count = std::min(count, n);
  std::vector<uint32_t> order;
  std::vector<double> d(n, std::numeric_limits<double>::infinity());
  uint32_t next = 0;
  double best = -1;
  for (std::size_t i = 0; i < n; ++i) {
    const double di = dist2(points[i], from);
    if (di > best) best = di, next = static_cast<uint32_t>(i);
  }
  while (order.size() < count) {
    order.push_back(next);
    const Vec3 p = points[next];
    best = -1;
    for (std::size_t i = 0; i < n; ++i) {
      d[i] = std::min(d[i], dist2(points[i], p));
      if (d[i] > best) best = d[i], next = static_cast<uint32_t>(i);
    }
  }
  return order;
}

Vec3 at_barycentric(const SurfaceMesh& m, uint32_t t, const std::array<double, 3>& b) {
  const auto& tri = m.triangles[t];
  Vec3 x{0, 0, 0};
  for (int c = 0; c < 3; ++c) x = add(x, scale(m.vertices[tri[c]], b[c]));
  return x;
}

// Relative weighted error ||w (A q - b)|| / ||w b|| of a column-major matrix.
double relative_error(const Eigen::MatrixXcd& A, const Eigen::VectorXcd& q,
                      const Eigen::VectorXcd& b, const Eigen::VectorXd& w) {
  const double nb = (w.asDiagonal() * b).norm();
  if (nb == 0.0) return 0.0;
  return (w.asDiagonal() * (A * q - b)).norm() / nb;
}

}  // namespace

void AcousticOptions::validate() const {
  auto positive = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(std::string("transfer: ") + what + " must be finite and > 0");
  };
  positive(sound_speed, "sound speed");
  positive(air_density, "air density");
  positive(sources_per_term, "sources per term");
  positive(source_depth, "source depth");
  positive(truncation, "truncation");
  positive(collocation_per_source, "collocation points per source");
  if (!(regularization >= 0) || !std::isfinite(regularization))
    throw InputError("transfer: regularization must be finite and >= 0");
  if (order < 0 || order > 200) throw InputError("transfer: order must lie in [0, 200]");
  if (max_order < 1 || max_order > 200)
    throw InputError("transfer: max order must lie in [1, 200]");
  if (min_sources < 1 || max_sources < min_sources)
    throw InputError("transfer: need 1 <= min sources <= max sources");
  if (max_collocation < 16) throw InputError("transfer: max collocation must be >= 16");
  if (bem_extra_levels < 0 || bem_extra_levels > 3)
    throw InputError("transfer: bem extra levels must lie in [0, 3]");
  if (bem_solvers < 0 || bem_solvers > 2)
    throw InputError("transfer: bem solvers must be 0, 1 or 2");
  if (!(bem_max_memory >= 0) || !std::isfinite(bem_max_memory))
    throw InputError("transfer: bem max memory must be finite and >= 0");
  if (!(bem_shared_frequency >= 0 && bem_shared_frequency <= 1e-2))
    throw InputError("transfer: bem shared frequency must lie in [0, 0.01]");
  bem.validate();
  wave.validate();
}

RadiatingSurface::RadiatingSurface(const SurfaceMesh& mesh, const AcousticOptions& o)
    : mesh_(mesh) {
  o.validate();
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  if (nv < 4 || nt < 4) throw InputError("transfer: the surface needs at least 4 triangles");
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3& v : mesh.vertices) {
    if (!is_finite(v)) throw InputError("transfer: a surface vertex is not finite");
    for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
  }
  centre_ = scale(add(lo, hi), 0.5);
  for (const Vec3& v : mesh.vertices) radius_ = std::max(radius_, std::sqrt(dist2(v, centre_)));

  measure_faces();
  place_anchors(o);
  order_collocation(o);
  pick_held_out(o);
}

void RadiatingSurface::measure_faces() {
  const SurfaceMesh& mesh = mesh_;
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  face_normal_.resize(nt);
  face_area_.resize(nt);
  centroid_.resize(nt);
  vertex_normal_.assign(nv, Vec3{0, 0, 0});
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles[t];
    for (uint32_t v : tri) {
      if (v >= nv) throw InputError("transfer: triangle " + std::to_string(t) + " has a bad index");
    }
    const Vec3 n2 =
        triangle_normal(mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]);
    const double len = std::sqrt(dot(n2, n2));
    face_area_[t] = 0.5 * len;
    area_ += face_area_[t];
    face_normal_[t] = len > 0 ? scale(n2, 1.0 / len) : Vec3{0, 0, 0};
    centroid_[t] = at_barycentric(mesh, static_cast<uint32_t>(t), {1.0 / 3, 1.0 / 3, 1.0 / 3});
    for (uint32_t v : tri) vertex_normal_[v] = add(vertex_normal_[v], n2);
  }
  if (!(area_ > 0)) throw InputError("transfer: the surface has no area");
  for (const auto& tri : mesh.triangles) {
    const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    mean_size_ += std::sqrt(std::max({dist2(a, b), dist2(b, c), dist2(c, a)})) / double(nt);
  }
  for (Vec3& n : vertex_normal_) {
    const double len = std::sqrt(dot(n, n));
    n = len > 0 ? scale(n, 1.0 / len) : Vec3{0, 0, 1};
  }
}

void RadiatingSurface::place_anchors(const AcousticOptions& o) {
  // Source anchors: spread vertices, each with the wall thickness below it.
  anchors_ = farthest_points(mesh_.vertices, o.max_sources, centre_);
  anchor_depth_.resize(anchors_.size());
  parallel_for(anchors_.size(), o.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const uint32_t v = anchors_[i];
      const double d =
          ray_depth(mesh_, mesh_.vertices[v], scale(vertex_normal_[v], -1.0), v, 1e-9 * radius_);
      anchor_depth_[i] = std::min(std::isfinite(d) ? 0.45 * d : radius_, 0.5 * radius_);
    }
  });
  std::vector<double> depths = anchor_depth_;
  std::nth_element(depths.begin(), depths.begin() + long(depths.size() / 2), depths.end());
  typical_depth_ = depths[depths.size() / 2];
}

void RadiatingSurface::order_collocation(const AcousticOptions& o) {
  const std::size_t nt = mesh_.triangles.size();
  // Collocation: triangles in farthest-point order; at each level the first `count` of them carry
  // the area of the triangles nearest to them (a Voronoi quadrature of the surface).
  const std::size_t top = std::min(nt, o.max_collocation);
  colloc_order_ = farthest_points(centroid_, top, centre_);
  for (std::size_t count = std::min<std::size_t>(256, top);; count = std::min(count * 3 / 2, top)) {
    Level lv{count, std::vector<double>(count, 0.0)};
    if (count == nt) {
      for (std::size_t i = 0; i < count; ++i) lv.weight[i] = face_area_[colloc_order_[i]];
    } else {
      std::vector<std::size_t> owner(nt);
      parallel_for(nt, o.threads, [&](std::size_t b, std::size_t e) {
        for (std::size_t t = b; t < e; ++t) {
          double best = std::numeric_limits<double>::infinity();
          for (std::size_t i = 0; i < count; ++i) {
            const double d = dist2(centroid_[t], centroid_[colloc_order_[i]]);
            if (d < best) best = d, owner[t] = i;
          }
        }
      });
      for (std::size_t t = 0; t < nt; ++t) lv.weight[owner[t]] += face_area_[t];
    }
    levels_.push_back(std::move(lv));
    if (count == top) break;
  }
}

void RadiatingSurface::pick_held_out(const AcousticOptions& o) {
  const std::size_t nt = mesh_.triangles.size();
  // Held-out points: off-centroid points (2/3, 1/6, 1/6) of spread triangles, never collocated.
  const std::size_t nh = std::min(nt, std::max<std::size_t>(o.held_out, 1));
  const std::vector<uint32_t> held_tris =
      nh <= colloc_order_.size()
          ? std::vector<uint32_t>(colloc_order_.begin(), colloc_order_.begin() + long(nh))
          : farthest_points(centroid_, nh, centre_);
  for (uint32_t t : held_tris) {
    held_.push_back({t, {2.0 / 3, 1.0 / 6, 1.0 / 6}});
    held_weight_.push_back(nh == nt ? face_area_[t] : area_ / double(nh));
  }
}

std::vector<Vec3> RadiatingSurface::interior_points(std::size_t count, double min_depth) const {
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < anchors_.size() && out.size() < count; ++i) {
    if (!(anchor_depth_[i] >= min_depth)) continue;
    const uint32_t v = anchors_[i];
    out.push_back(sub(mesh_.vertices[v], scale(vertex_normal_[v], anchor_depth_[i])));
  }
  return out;
}

NormalVelocity RadiatingSurface::from_vertex_values(std::span<const cd> un) const {
  if (un.size() != mesh_.vertices.size()) {
    throw InputError("transfer: " + std::to_string(un.size()) + " velocity values for " +
                     std::to_string(mesh_.vertices.size()) + " vertices");
  }
  for (std::size_t v = 0; v < un.size(); ++v) {
    if (!std::isfinite(un[v].real()) || !std::isfinite(un[v].imag()))
      throw InputError("transfer: velocity of vertex " + std::to_string(v) + " is not finite");
  }
  std::vector<cd> values(un.begin(), un.end());
  return [this, values](uint32_t t, const std::array<double, 3>& b) {
    const auto& tri = mesh_.triangles[t];
    return b[0] * values[tri[0]] + b[1] * values[tri[1]] + b[2] * values[tri[2]];
  };
}

NormalVelocity RadiatingSurface::from_mode_shape(const float* shape, double omega) const {
  return [this, shape, omega](uint32_t t, const std::array<double, 3>& b) {
    const auto& tri = mesh_.triangles[t];
    double vn = 0;
    for (int c = 0; c < 3; ++c) {
      const float* s = shape + 3 * std::size_t(tri[c]);
      vn += b[c] *
            (s[0] * face_normal_[t][0] + s[1] * face_normal_[t][1] + s[2] * face_normal_[t][2]);
    }
    return cd(0.0, -omega * vn);  // u = -i omega v (DESIGN.md convention)
  };
}

// Friend with access to the prepared geometry.
struct SourceFitter {
  static SourceFit fit(const RadiatingSurface& s, double k, const NormalVelocity& un,
                       const AcousticOptions& o, TransferKernels& kernels, TransferTimes* times) {
    SourceFit f;
    f.k = k;
    const double omega = k * o.sound_speed;
    // Sources ~ the field's multipole degrees of freedom at this k.
    // and no sparser than their depth allows (thin walls need close sources).
    const double terms = (k * s.radius_ + 3.0) * (k * s.radius_ + 3.0);
    const double wanted =
        std::max(o.sources_per_term * terms, s.area_ / (s.typical_depth_ * s.typical_depth_));
    // In double: a huge kR must not overflow; never more sources than anchor vertices.
    const double most = double(std::min(o.max_sources, s.anchors_.size()));
    const auto ns = static_cast<std::size_t>(
        std::min(std::max(std::ceil(wanted), double(o.min_sources)), most));
    const double spacing = std::sqrt(s.area_ / double(ns));
    for (std::size_t i = 0; i < ns; ++i) {
      const uint32_t v = s.anchors_[i];
      // Inside the wall (below its middle) and not deeper than R/2: deep sources must cancel each
      // other to make the surface's detail, which single precision cannot afford.
      const double depth = std::min(o.source_depth * spacing, s.anchor_depth_[i]);
      f.sources.push_back(
          sub(sub(s.mesh_.vertices[v], scale(s.vertex_normal_[v], depth)), s.centre_));
    }
    const RadiatingSurface::Level* lv = &s.levels_.back();
    for (const auto& l : s.levels_) {
      if (double(l.count) >=
          std::max(o.collocation_per_source * double(ns), double(o.min_collocation))) {
        lv = &l;
        break;
      }
    }
    const std::size_t nc = lv->count;
    std::vector<Vec3> xc(nc), nc_n(nc);
    Eigen::VectorXcd b(static_cast<Eigen::Index>(nc));
    Eigen::VectorXd w(static_cast<Eigen::Index>(nc));
    const cd neumann(0.0, omega * o.air_density);  // dp/dn = i omega rho0 u_n
    for (std::size_t i = 0; i < nc; ++i) {
      const uint32_t t = s.colloc_order_[i];
      xc[i] = sub(s.centroid_[t], s.centre_);
      nc_n[i] = s.face_normal_[t];
      b(Eigen::Index(i)) = neumann * un(t, {1.0 / 3, 1.0 / 3, 1.0 / 3});
      w(Eigen::Index(i)) = std::sqrt(lv->weight[i]);
    }
    const std::size_t nh = s.held_.size();
    std::vector<Vec3> xh(nh), nh_n(nh);
    Eigen::VectorXcd bh(static_cast<Eigen::Index>(nh));
    Eigen::VectorXd wh(static_cast<Eigen::Index>(nh));
    for (std::size_t i = 0; i < nh; ++i) {
      const auto& [t, bary] = s.held_[i];
      xh[i] = sub(at_barycentric(s.mesh_, t, bary), s.centre_);
      nh_n[i] = s.face_normal_[t];
      bh(Eigen::Index(i)) = neumann * un(t, bary);
      wh(Eigen::Index(i)) = std::sqrt(s.held_weight_[i]);
    }

    auto t0 = std::chrono::steady_clock::now();
    Eigen::MatrixXcd A(static_cast<Eigen::Index>(nc), static_cast<Eigen::Index>(ns));
    Eigen::MatrixXcd Ah(static_cast<Eigen::Index>(nh), static_cast<Eigen::Index>(ns));
    kernels.matrix(xc, nc_n, f.sources, k, A.data());
    kernels.matrix(xh, nh_n, f.sources, k, Ah.data());
    if (times) times->matrix += seconds_since(t0);

    t0 = std::chrono::steady_clock::now();
    f.strength.assign(ns, cd(0.0));
    if ((w.asDiagonal() * b).norm() > 0) {
      // min ||W (A q - b)||^2 + lambda^2 ||D q||^2 with D the column norms of W A: in x = D q,
      // B = W A D^-1 has unit columns. Either Householder QR of the stacked [B; lambda I] (no
      // squared condition number) or Cholesky of B^H B + lambda^2 I (a quarter of the flops, one
      // BLAS product; lambda bounds the condition number by ns / lambda^2).
      const auto nce = static_cast<Eigen::Index>(nc), nse = static_cast<Eigen::Index>(ns);
      Eigen::MatrixXcd B = w.asDiagonal() * A;
      Eigen::VectorXd d = B.colwise().norm().transpose();
      for (Eigen::Index j = 0; j < nse; ++j) {
        if (!(d(j) > 0)) d(j) = 1.0;
      }
      B = B * d.cwiseInverse().asDiagonal();
      const Eigen::VectorXcd wb = w.asDiagonal() * b;
      Eigen::VectorXcd x;
      if (o.solver == AcousticOptions::Solver::Normal) {
        Eigen::MatrixXcd G(nse, nse);
        const int n = static_cast<int>(nse), kk = static_cast<int>(nce);
        const double one = 1.0, zero = 0.0;
        // Lower triangle of B^H B by the BLAS's Hermitian rank-k update: half the flops of a
        // general product, and the dominant cost of the fit (ns^2 nc against ns^3 / 3).
        zherk_("L", "C", &n, &kk, &one, reinterpret_cast<const double*>(B.data()), &kk, &zero,
               reinterpret_cast<double*>(G.data()), &n);
        G.diagonal().array() += o.regularization * o.regularization;
        const Eigen::LLT<Eigen::MatrixXcd> llt(G);
        if (llt.info() == Eigen::Success) x = llt.solve(B.adjoint() * wb);
      }
      if (x.size() == 0) {  // QR requested, or round-off broke the Cholesky factorization
        Eigen::MatrixXcd S(nce + nse, nse);
        S.topRows(nce) = B;
        S.bottomRows(nse).setZero();
        S.bottomRows(nse).diagonal().setConstant(o.regularization);
        Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(nce + nse);
        rhs.head(nce) = wb;
        x = S.householderQr().solve(rhs);
      }
      const Eigen::VectorXcd q = d.cwiseInverse().asDiagonal() * x;
      for (std::size_t j = 0; j < ns; ++j) f.strength[j] = q(Eigen::Index(j));
      f.residual = relative_error(A, q, b, w);
      f.held_out = relative_error(Ah, q, bh, wh);
    }
    if (times) times->solve += seconds_since(t0);
    for (const cd& z : f.strength) {
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag()))
        throw InternalError("transfer: the least-squares fit produced non-finite sources");
    }
    return f;
  }
};

SourceFit fit_sources(const RadiatingSurface& surface, double k, const NormalVelocity& un,
                      const AcousticOptions& options, TransferKernels& kernels,
                      TransferTimes* times) {
  if (!(k > 0) || !std::isfinite(k))
    throw InputError("transfer: wavenumber must be finite and > 0");
  return SourceFitter::fit(surface, k, un, options, kernels, times);
}

std::vector<cd> source_pressure(const RadiatingSurface& surface, const SourceFit& fit,
                                std::span<const Vec3> points, TransferKernels& kernels) {
  std::vector<Vec3> rel(points.size());
  for (std::size_t j = 0; j < points.size(); ++j) {
    if (!is_finite(points[j]))
      throw InputError("field point " + std::to_string(j) + " is not finite");
    rel[j] = sub(points[j], surface.centre());
  }
  std::vector<cd> p(points.size());
  kernels.field(rel, fit.sources, fit.strength, fit.k, p.data());
  return p;
}

Transfer compute_transfer(const RadiatingSurface& surface, const Soundbank& bank,
                          const AcousticOptions& o, TransferKernels& kernels, TransferTimes* times,
                          const std::function<void(std::size_t, std::size_t)>& progress,
                          const std::function<void(const std::string&)>& note) {
  const std::size_t nm = bank.mode_count(), nv = bank.vertices.size();
  if (nv != surface.mesh().vertices.size() || bank.shapes.size() != nm * nv * 3)
    throw InternalError("transfer: the bank's shapes do not match the surface");
  Transfer out;
  out.centre = surface.centre();
  out.radius = surface.radius();
  out.sound_speed = o.sound_speed;
  out.air_density = o.air_density;
  std::vector<ModeTransfer> modes(nm);
  std::vector<std::vector<cd>> coeffs(nm);
  std::atomic<std::size_t> done{0};
  std::mutex kernel_mutex, progress_mutex;
  TransferTimes total;
  // Serialize kernel calls (the GPU queue is one), fit modes in parallel.
  struct Locked final : TransferKernels {
    TransferKernels& inner;
    std::mutex& mu;
    Locked(TransferKernels& k, std::mutex& m) : inner(k), mu(m) {}
    void matrix(std::span<const Vec3> x, std::span<const Vec3> n, std::span<const Vec3> y, double k,
                cd* out) override {
      std::lock_guard lock(mu);
      inner.matrix(x, n, y, k, out);
    }
    void field(std::span<const Vec3> x, std::span<const Vec3> y, std::span<const cd> q, double k,
               cd* out) override {
      std::lock_guard lock(mu);
      inner.field(x, y, q, k, out);
    }
    std::string name() const override { return inner.name(); }
  } locked(kernels, kernel_mutex);
  TransferKernels& shared = kernels.thread_safe() ? kernels : static_cast<TransferKernels&>(locked);
  // Per mode: boundary elements where the surface resolves the wavelength (auto), else sources.
  std::vector<std::size_t> by_bem, by_sources, by_wave;
  for (std::size_t i = 0; i < nm; ++i) {
    const double k = bank.damped_omega(i) / o.sound_speed;  // radiates at the damped frequency
    const auto m = resolve_method(surface, k, o);
    (m == AcousticOptions::Method::Bem    ? by_bem
     : m == AcousticOptions::Method::Wave ? by_wave
                                          : by_sources)
        .push_back(i);
  }
  auto tick = [&] {
    const std::size_t n = ++done;
    if (progress) {
      std::lock_guard lock(progress_mutex);
      progress(n, nm);
    }
  };
  compute_transfer_bem(surface, bank, by_bem, o, modes, coeffs, &total, tick);
  compute_transfer_wave(surface, bank, by_wave, o, modes, coeffs, &total, tick, note);
  std::exception_ptr error;
  // Modes are fitted in parallel, one per core: a threaded BLAS inside each fit would only
  // oversubscribe the cores (measured: 1.6x slower on 2 cores).
  std::optional<SingleThreadedBlas> blas;
  if (o.threads != 1 && by_sources.size() > 1) blas.emplace();
  parallel_for(by_sources.size(), o.threads, [&](std::size_t b, std::size_t e) {
    TransferTimes mine;
    try {
      for (std::size_t s = b; s < e; ++s) {
        const std::size_t i = by_sources[s];
        const double omega = bank.damped_omega(i);
        const NormalVelocity un = surface.from_mode_shape(bank.shapes.data() + i * nv * 3, omega);
        const SourceFit fit = fit_sources(surface, omega / o.sound_speed, un, o, shared, &mine);
        modes[i] = expand_sources(surface, fit, o, shared, coeffs[i], &mine);
        tick();
      }
    } catch (...) {
      std::lock_guard lock(progress_mutex);
      if (!error) error = std::current_exception();
    }
    std::lock_guard lock(progress_mutex);
    total.matrix += mine.matrix, total.solve += mine.solve, total.expand += mine.expand;
  });
  if (error) std::rethrow_exception(error);
  for (std::size_t i = 0; i < nm; ++i) out.add_mode(modes[i], coeffs[i]);
  if (times)
    times->matrix += total.matrix, times->solve += total.solve, times->expand += total.expand;
  return out;
}

}  // namespace chladni::precompute
