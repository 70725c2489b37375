#pragma once
// Boundary elements for the exterior Neumann Helmholtz problem (e^(-i w t), G = e^(ikr)/(4 pi r),
// n outward from the body), Burton & Miller (1971):
//   (1/2) p - K p - a D p = -S q - a K' q - (a/2) q,   q = dp/dn = i w rho0 u_n,   a = i/k,
// with S q = int G q, K p = PV int p dG/dn_y, K' q = int dG/dn_x q and D p = FP int p d2G/dn_x dn_y
// (a = i/k at high frequency; i h, h the element size, where that is smaller: see bem_solve.cpp).
// Constant elements on flat triangles, collocation at the centroids. The combination has a unique
// solution at every k (no spurious interior resonances). Quadrature (element_integrals): on the
// element itself polar coordinates about the centroid with the radial integrals in closed form
// (the hypersingular one as a Hadamard finite part); near elements (thin walls, neighbours)
// adaptive subdivision into 4 until each piece is small against its distance, then a degree-5
// rule; far elements 3 points or 1.
#include <array>
#include <complex>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "chladni/core/vec3.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::gpu {
class Context;
}

namespace chladni::precompute {
namespace bem_detail {
class HMatrixSystem;
}

/// A closed triangle surface as constant boundary elements.
struct BemMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<Vec3> centroid, normal;  ///< per element; unit outward normals
  std::vector<double> area, size;      ///< size: longest edge

  BemMesh() = default;
  /// Throws InputError for a degenerate (zero-area) triangle or a bad index.
  explicit BemMesh(const SurfaceMesh& mesh);
  std::size_t elements() const { return triangles.size(); }
  double mean_size() const;
};

struct BemOptions {
  double far_ratio = 8.0;       ///< distance / element size beyond which one point suffices
  double near_ratio = 3.0;      ///< below this, adaptive subdivision (3 points in between)
  double subdivision = 0.3;     ///< adaptive: piece diameter <= this x distance to the point
  double coupling_scale = 1.0;  ///< Burton-Miller coupling i min(1/k, this x mean element size)
  int max_depth = 9;
  std::size_t direct_limit = 1200;  ///< dense LU per solve up to this many elements; GMRES above
  double gmres_tolerance = 1e-6;    ///< relative residual
  int gmres_restart = 80;
  int gmres_max_iterations = 50;  ///< then factorize at this frequency (an LU ~ 50 iterations)
  /// Above direct_limit: GMRES preconditioned by the single-precision LU of the last factorized
  /// frequency k0 while |k - k0| x (bounding-box diagonal) stays below this; else a new LU.
  double refactor_phase = 1.0;
  /// Above this many elements the matrix is a hierarchical matrix (hmat-oss): far blocks
  /// compressed to hmatrix_epsilon, GMRES preconditioned by its LU at hmatrix_lu_epsilon.
  std::size_t hmatrix_limit = 8000;
  double hmatrix_epsilon = 1e-4;
  double hmatrix_lu_epsilon = 0.1;
  int threads = 0;  ///< 0: all cores
  /// Vulkan device for the centroid-rule rows (kernels/bem_far.comp, float); null: the CPU loop.
  std::shared_ptr<gpu::Context> gpu;
  void validate() const;
};

using cd = std::complex<double>;

/// Integrals over element j of G, dG/dn_y, dG/dn_x and d2G/(dn_x dn_y) seen from x (normal nx),
/// and of the last one's static (k = 0) part. x may be element j's centroid (the self term) or any
/// point off the element.
struct ElementIntegrals {
  cd single, dbl, adjoint, hyper;
  double hyper_static;
};
ElementIntegrals element_integrals(const BemMesh& mesh, uint32_t j, const Vec3& x, const Vec3& nx,
                                   double k, const BemOptions& options);

/// The centroid-rule part of rows of the Burton-Miller system on a Vulkan device, in float: per
/// row the entries -K - a D of every element (0 on the diagonal) and the right-hand side's far
/// part sum_(j != i) (S + a K')_j q_j, with a = i al. bem_far_row.cpp is its double reference.
class BemGpuRows {
 public:
  BemGpuRows(std::shared_ptr<gpu::Context> ctx, const BemMesh& mesh);
  ~BemGpuRows();
  /// Most rows one call may ask for (the device's storage-buffer range and dispatch limits).
  std::size_t block_rows() const;
  void rows(double k, double al, std::span<const std::complex<double>> q, std::size_t row0,
            std::size_t count, std::vector<std::complex<float>>& entries,
            std::vector<std::complex<float>>& rhs);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The Burton-Miller system of one mesh, solved for any wavenumber. Keeps the LU factors of the
/// last factorized frequency to precondition GMRES at the next ones (modes come in ascending k).
class BemSolver {
 public:
  BemSolver(const BemMesh& mesh, const BemOptions& options);
  ~BemSolver();
  BemSolver(const BemSolver&) = delete;
  BemSolver& operator=(const BemSolver&) = delete;

  struct Result {
    std::vector<cd> pressure;  ///< per element (Pa)
    double residual = 0;       ///< ||A p - b|| / ||b||
    int iterations = 0;        ///< GMRES iterations; 0 for a direct solve
    bool factorized = false;   ///< an LU factorization was computed for this solve
  };
  struct Times {
    double assembly = 0, factorization = 0, iteration = 0;
  };
  /// dpdn: dp/dn per element (Pa/m). Throws InternalError when the solve fails.
  Result solve(double k, std::span<const cd> dpdn);
  /// Several right-hand sides at one wavenumber: one assembly, at most one factorization.
  std::vector<Result> solve(double k, std::span<const std::vector<cd>> dpdn);
  const Times& times() const { return times_; }
  const BemMesh& mesh() const { return mesh_; }

  struct NearCache;  ///< frequency-independent static near-field integrals
  struct Lu;         ///< LAPACK LU factors of one frequency's matrix

  /// The near-field integrals (computed on first use, on options.threads): solvers of the same
  /// mesh share them through the constructor below.
  std::shared_ptr<const NearCache> near_field();
  BemSolver(const BemMesh& mesh, const BemOptions& options, std::shared_ptr<const NearCache> near);

 private:
  std::vector<Result> solve_dense(double k, std::span<const std::vector<cd>> dpdn);
  std::vector<Result> solve_hierarchical(double k, std::span<const std::vector<cd>> dpdn);
  const BemMesh& mesh_;
  BemOptions options_;
  std::unique_ptr<Lu> lu_;
  std::shared_ptr<const NearCache> near_;
  std::unique_ptr<BemGpuRows> gpu_rows_;
  std::unique_ptr<bem_detail::HMatrixSystem> hmatrix_;
  std::vector<cd> matrix_;  // the current frequency's system, kept to reuse its memory
  double extent_ = 0;
  Times times_;
};

/// Pressure at field points from the surface data (Kirchhoff-Helmholtz representation):
/// p(x) = sum_j p_j int dG/dn_y - q_j int G. Points may be anywhere off the surface.
std::vector<cd> bem_field(const BemMesh& mesh, double k, std::span<const cd> pressure,
                          std::span<const cd> dpdn, std::span<const Vec3> points,
                          const BemOptions& options);

/// Far-field multipole coefficients about `centre` by quadrature of the representation against
/// the regular waves: c_lm = i k sum_j int [p_j d/dn (j_l Y_lm) - q_j j_l Y_lm], so that
/// p(x) = sum c_lm h_l(k |x - c|) Y_lm outside the sphere about c enclosing the surface.
std::vector<cd> bem_multipoles(const BemMesh& mesh, double k, const Vec3& centre, int order,
                               std::span<const cd> pressure, std::span<const cd> dpdn,
                               int threads = 0);

}  // namespace chladni::precompute
