#pragma once
// Acoustic transfer by equivalent sources (after James, Barbic & Pai 2006, "Precomputed Acoustic
// Transfer"): for a mode vibrating at wavenumber k, monopoles placed inside the object are fitted
// by regularized least squares to the Neumann condition dp/dn = i omega rho0 u_n (e^(-i w t)) at
// surface collocation points, then re-expanded into one multipole series about the centre
// (core/transfer.hpp). The dense kernels run on the CPU (double) or the GPU (float); the solve is
// Eigen's Householder QR in double on the CPU.
#include <array>
#include <complex>
#include <functional>
#include <span>
#include <vector>

#include "chladni/core/soundbank.hpp"
#include "chladni/core/transfer.hpp"
#include "chladni/precompute/bem.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/transfer_kernels.hpp"
#include "chladni/precompute/wave_transfer.hpp"

namespace chladni::precompute {

struct AcousticOptions {
  /// bem: Burton-Miller boundary elements on the surface (docs/transfer.md); sources: the
  /// equivalent-source fit; wave: the time-domain solve with mode conflation (wave_transfer.hpp);
  /// auto: per mode, BEM where it is cheap (the surface resolves the wavelength with at most
  /// bem_cheap_elements elements) or the body is compact (kR below bem_compact_kr, within
  /// bem_auto_elements), else the wave solve where its grid fits the memory, else BEM within
  /// bem_auto_elements, else sources.
  enum class Method { Auto, Bem, Sources, Wave };
  Method method = Method::Auto;
  /// auto's cap: the dense system below BemOptions::hmatrix_limit (16 N^2 bytes, 1 GB at 8000),
  /// a hierarchical one above (2.5 GB and ~10 s per LU at 10,880 elements on 2 cores).
  std::size_t bem_auto_elements = 12000;
  /// auto: BEM rather than the wave solve up to this many elements (a dense LU within about a
  /// second on two cores); 0: the wave solve wherever it fits.
  std::size_t bem_cheap_elements = 2000;
  /// auto: BEM (within bem_auto_elements) for modes with k R below this. There the radiated
  /// field is (kR)^2 of the near field on the wave solve's box, whose grid error the Kirchhoff
  /// integral then magnifies; and the wave solve's steps per period grow as 1/k. 0: off.
  double bem_compact_kr = 1.0;
  /// bem: split the surface's triangles up to this many elements (above BemOptions::
  /// hmatrix_limit the system is a hierarchical matrix: about 1 GB and 20-60 s per frequency
  /// at 26,000 elements on 2 cores).
  std::size_t bem_max_elements = 32768;
  double bem_elements_per_wavelength = 6.0;
  /// Splits beyond what the wavelength asks: 1 halves every element (a convergence check,
  /// bench/bem_convergence.cpp).
  int bem_extra_levels = 0;
  /// Bytes the BEM system may take (bem_memory; 0: no limit). Element meshes over it are not
  /// used: auto gives the mode sources, bem the finest mesh that fits (BudgetError if none does).
  double bem_max_memory = 0;
  /// Modes whose wavenumbers differ by at most this (relative) share one BEM assembly and solve
  /// at their mean wavenumber: the degenerate pairs of symmetric bodies, whose frequencies the
  /// mesh splits by ~1e-5. The change of the radiated field is of the same relative order.
  double bem_shared_frequency = 1e-4;
  /// Solvers side by side on a hierarchical level (hmat-oss runs on one core; the second one in
  /// a forked process): 0 chooses two where two cores and the memory for two systems are there,
  /// else one; 1 or 2 asks.
  int bem_solvers = 1;
  BemOptions bem;
  WaveOptions wave;
  double sound_speed = 343.0;  ///< m/s
  double air_density = 1.204;  ///< kg/m^3 (air at 20 C)
  int order = 0;               ///< fixed expansion order L; 0: per mode from k and the sources
  int max_order = 40;
  std::size_t min_sources = 128;
  std::size_t max_sources = 1024;
  double sources_per_term = 2.0;  ///< sources ~ this x (kR + 3)^2, the field's degrees of freedom
  double source_depth = 2.0;      ///< inward offset in source spacings (capped by the thickness)
  std::size_t max_collocation = 4096;
  /// Collocation points: this many per source, at least min_collocation (rounded up to a level of
  /// the farthest-point order; a fine quadrature keeps spurious low orders out of the far field).
  double collocation_per_source = 3.0;
  std::size_t min_collocation = 1024;
  std::size_t held_out = 1000;   ///< surface points kept out of the fit to measure its error
  double regularization = 1e-6;  ///< Tikhonov weight on column-normalized sources
  enum class Solver { Qr, Normal };
  Solver solver = Solver::Normal;  ///< normal equations (zherk + Cholesky) or QR of the stack
  double truncation = 1e-3;        ///< drop the orders carrying less than this at r = 2R
  int threads = 0;                 ///< modes fitted in parallel (0: all cores)
  void validate() const;           ///< throws InputError naming the bad field
};

/// Normal velocity (m/s, complex amplitude) at barycentric point `b` of triangle `t`.
using NormalVelocity =
    std::function<std::complex<double>(uint32_t t, const std::array<double, 3>& b)>;

/// A closed surface prepared for fits: centre and radius, source anchors with their inward depth,
/// collocation levels with quadrature weights, held-out points. Geometry work shared by all modes.
class RadiatingSurface {
 public:
  RadiatingSurface(const SurfaceMesh& mesh, const AcousticOptions& options);

  const SurfaceMesh& mesh() const { return mesh_; }
  const Vec3& centre() const { return centre_; }
  double radius() const { return radius_; }
  /// Mean longest edge of the triangles (m).
  double mean_element_size() const { return mean_size_; }
  double area() const { return area_; }
  const Vec3& face_normal(uint32_t t) const { return face_normal_[t]; }
  const std::vector<Vec3>& vertex_normals() const { return vertex_normal_; }
  /// Up to `count` spread points inside the body (absolute), each at most half the local wall
  /// thickness below a vertex and at least `min_depth` deep.
  std::vector<Vec3> interior_points(std::size_t count, double min_depth) const;

  /// Normal velocity interpolated from per-vertex values (m/s).
  NormalVelocity from_vertex_values(std::span<const std::complex<double>> un) const;
  /// u_n = -i omega (v . n) of a mode whose shape at the vertices is `shape` (xyz per vertex).
  NormalVelocity from_mode_shape(const float* shape, double omega) const;

 private:
  void measure_faces();                              // normals, areas, centroids, size
  void place_anchors(const AcousticOptions& o);      // source anchors and their depths
  void order_collocation(const AcousticOptions& o);  // collocation levels and weights
  void pick_held_out(const AcousticOptions& o);
  friend struct SourceFitter;
  SurfaceMesh mesh_;
  Vec3 centre_{0, 0, 0};
  double radius_ = 0, area_ = 0, mean_size_ = 0;
  std::vector<Vec3> face_normal_, vertex_normal_, centroid_;
  std::vector<double> face_area_;
  std::vector<uint32_t> anchors_;     // vertices in farthest-point order
  std::vector<double> anchor_depth_;  // deepest source offset: below mid-wall, at most R/2
  double typical_depth_ = 0;          // median of anchor_depth_
  struct Level {
    std::size_t count;
    std::vector<double> weight;  // quadrature area of each of the first `count` triangles
  };
  std::vector<uint32_t> colloc_order_;  // triangles in farthest-point order
  std::vector<Level> levels_;
  std::vector<std::pair<uint32_t, std::array<double, 3>>> held_;  // triangle, barycentric
  std::vector<double> held_weight_;
};

/// Equivalent sources fitted for one frequency. Positions are relative to the surface's centre.
struct SourceFit {
  double k = 0;
  std::vector<Vec3> sources;
  std::vector<std::complex<double>> strength;
  double residual = 0;  ///< relative weighted residual at the collocation points
  double held_out = 0;  ///< relative error at the held-out points
};

/// Seconds spent per stage, summed over calls.
struct TransferTimes {
  double matrix = 0;  ///< collocation and held-out matrices (the kernels); BEM: assembly
  double solve = 0;   ///< regularized least squares (CPU); BEM: LU and GMRES
  double expand = 0;  ///< re-expansion into a_lm and its check at 2R; BEM: quadrature, checks
};

SourceFit fit_sources(const RadiatingSurface& surface, double k, const NormalVelocity& un,
                      const AcousticOptions& options, TransferKernels& kernels,
                      TransferTimes* times = nullptr);

/// Pressure (Pa) of the fitted sources at absolute points.
std::vector<std::complex<double>> source_pressure(const RadiatingSurface& surface,
                                                  const SourceFit& fit,
                                                  std::span<const Vec3> points,
                                                  TransferKernels& kernels);

/// Re-expands the sources into a_lm about the centre (core/transfer.hpp): c_lm = i k sum_s q_s
/// j_l(k r_s) Y_lm(y_s) (addition theorem for e^(ikr)/(4 pi r)), a_lm = c_lm h_l(k R), orders
/// trimmed by options.truncation; expansion_error compares it with the sources at r = 2R.
ModeTransfer expand_sources(const RadiatingSurface& surface, const SourceFit& fit,
                            const AcousticOptions& options, TransferKernels& kernels,
                            std::vector<std::complex<double>>& a, TransferTimes* times = nullptr);

/// Trims a full-order expansion a (a_lm = c_lm h_l(kR), order L) to the orders that carry more
/// than options.truncation of the pressure at 2R and measures it against `direct` (the pressure
/// at points given relative to the centre) at 2 (L+1)^2 points of that sphere, 64 to max_check.
ModeTransfer finish_expansion(
    const RadiatingSurface& surface, double k, int L, std::vector<std::complex<double>>& a,
    const AcousticOptions& options,
    const std::function<void(const std::vector<Vec3>&, std::complex<double>*)>& direct,
    std::size_t max_check = 512);

/// Expansion order for wavenumber k on a surface of radius R: kR + 2 (kR)^(1/3) + 8, capped.
int expansion_order(double k, double radius, const AcousticOptions& options);

/// The boundary elements of a surface: its triangles split into four at their edge midpoints
/// `level` times (the geometry stays the surface's; the elements halve per level), each element
/// with its parent triangle and its corners' barycentric coordinates in it, so the normal
/// velocity (linear on each parent) carries over.
struct BemSurface {
  BemSurface(const SurfaceMesh& base, int level);
  int level = 0;
  SurfaceMesh mesh;
  std::vector<uint32_t> parent;
  std::vector<std::array<std::array<double, 3>, 3>> corners;
};

/// One mode by boundary elements on `mesh`, the elements of `elements`: dp/dn per element from
/// `un`, the Burton-Miller solve, c_lm by quadrature, trimmed and checked. Optionally returns the
/// surface pressure and dp/dn per element.
ModeTransfer bem_transfer(const RadiatingSurface& surface, const BemSurface& elements,
                          const BemMesh& mesh, BemSolver& solver, double k,
                          const NormalVelocity& un, const AcousticOptions& options,
                          std::vector<std::complex<double>>& a, TransferTimes* times = nullptr,
                          std::vector<std::complex<double>>* pressure = nullptr,
                          std::vector<std::complex<double>>* dpdn = nullptr);

/// Several modes at one wavenumber k (of nearly equal frequencies): one assembly and at most one
/// factorization, then each mode's expansion into *a[v]. pressure/dpdn: the first mode's.
std::vector<ModeTransfer> bem_transfer(const RadiatingSurface& surface, const BemSurface& elements,
                                       const BemMesh& mesh, BemSolver& solver, double k,
                                       std::span<const NormalVelocity> un,
                                       const AcousticOptions& options,
                                       std::vector<std::vector<std::complex<double>>*> a,
                                       TransferTimes* times = nullptr,
                                       std::vector<std::complex<double>>* pressure = nullptr,
                                       std::vector<std::complex<double>>* dpdn = nullptr);

/// Whether the wave solve's grid for a mode of wavenumber k alone fits options.wave.max_memory
/// and max_cell_steps.
bool wave_fits(const RadiatingSurface& surface, double k, const AcousticOptions& options);

/// The method compute_transfer uses for a mode of wavenumber k on this surface (never Auto).
AcousticOptions::Method resolve_method(const RadiatingSurface& surface, double k,
                                       const AcousticOptions& options);

/// Estimated peak bytes of a BEM solve on n elements: the dense matrix and its LU up to
/// BemOptions::hmatrix_limit, the measured per-element cost of the hierarchical one above.
double bem_memory(std::size_t n, const BemOptions& options);

/// How many times BEM splits the surface's triangles for wavenumber k: the fewest that give
/// bem_elements_per_wavelength within bem_auto_elements elements and bem_max_memory; -1 when
/// none does (with method Bem forced: the most that fit; BudgetError when not even the
/// surface's own triangles fit the memory).
int bem_level(const RadiatingSurface& surface, double k, const AcousticOptions& options);

/// compute_transfer's BEM path for the listed modes (ascending frequency, so each GMRES solve is
/// preconditioned by the LU of a nearby frequency); fills modes[i] and coeffs[i] of each and
/// calls done() per mode (from a second thread too, with bem_solvers 2).
void compute_transfer_bem(const RadiatingSurface& surface, const Soundbank& bank,
                          const std::vector<std::size_t>& which, const AcousticOptions& options,
                          std::vector<ModeTransfer>& modes,
                          std::vector<std::vector<std::complex<double>>>& coeffs,
                          TransferTimes* times, const std::function<void()>& done);

/// compute_transfer's time-domain path for the listed modes: chords, one grid and run each,
/// separation and the box integral into multipoles; note() gets a line per chord. Throws
/// BudgetError when a chord's grid exceeds options.wave.max_memory.
void compute_transfer_wave(const RadiatingSurface& surface, const Soundbank& bank,
                           const std::vector<std::size_t>& which, const AcousticOptions& options,
                           std::vector<ModeTransfer>& modes,
                           std::vector<std::vector<std::complex<double>>>& coeffs,
                           TransferTimes* times, const std::function<void()>& done,
                           const std::function<void(const std::string&)>& note = {});

/// Transfer of every mode of a bank whose surface is `surface` (the bank's SURF). `progress`
/// gets (modes done, modes total); `note` a line per stage of the wave solve.
Transfer compute_transfer(const RadiatingSurface& surface, const Soundbank& bank,
                          const AcousticOptions& options, TransferKernels& kernels,
                          TransferTimes* times = nullptr,
                          const std::function<void(std::size_t, std::size_t)>& progress = {},
                          const std::function<void(const std::string&)>& note = {});

}  // namespace chladni::precompute
