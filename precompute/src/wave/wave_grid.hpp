#pragma once
// The staggered grid of the time-domain transfer solve and what the steppers need of it. Cells
// are indexed x fastest; the face between cell c and c + e_axis is stored at c in that axis's
// velocity array (the last layer along each axis is the domain's rigid outer wall).
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "chladni/core/vec3.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/wave_transfer.hpp"

namespace chladni::precompute::wave {

/// A direction turned: rows d.
inline Vec3 turn_vector(const std::array<Vec3, 3>& rows, const Vec3& d) {
  return {dot(rows[0], d), dot(rows[1], d), dot(rows[2], d)};
}

/// x turned about `pivot`: pivot + rows (x - pivot).
inline Vec3 turn_point(const std::array<Vec3, 3>& rows, const Vec3& pivot, const Vec3& x) {
  return add(pivot, turn_vector(rows, sub(x, pivot)));
}

struct Grid {
  Vec3 origin{0, 0, 0};  ///< corner of cell (0, 0, 0)
  double h = 0;
  std::array<uint32_t, 3> n{0, 0, 0};
  std::size_t cells() const { return std::size_t(n[0]) * n[1] * n[2]; }
  std::size_t stride(int axis) const {
    return axis == 0 ? 1 : axis == 1 ? std::size_t(n[0]) : std::size_t(n[0]) * n[1];
  }
  Vec3 centre(std::size_t i, std::size_t j, std::size_t k) const {
    return {origin[0] + (double(i) + 0.5) * h, origin[1] + (double(j) + 0.5) * h,
            origin[2] + (double(k) + 0.5) * h};
  }
};

/// Faces crossed by the surface, with the surface points where they are crossed: the face's
/// velocity is the mean over those points of the surface velocity along the face's axis.
struct BlockedFaces {
  std::vector<uint32_t> axis;    ///< 0, 1, 2
  std::vector<uint64_t> cell;    ///< the face's lower cell
  std::vector<uint32_t> start;   ///< per face: first entry in vertex/weight (size faces + 1)
  std::vector<uint32_t> vertex;  ///< surface vertices interpolated at the crossings
  std::vector<float> weight;     ///< barycentric weight / crossings of the face
  /// Per entry, n n_a of the crossed triangle (unit normal n, the face's axis a): the face
  /// carries v . n n_a, the normal velocity's share along its axis, so that tangential motion,
  /// which moves no air, drives nothing.
  std::vector<std::array<float, 3>> direction;
  /// Per entry, how far the face lies outside the surface along its normal (m, n_a times the
  /// signed distance from the crossing to the face along the axis): the wave the surface sends
  /// out reaches the face that much later, so the face carries the velocity delayed by
  /// reach / c. The staircase then radiates from where the surface is, not from the grid's
  /// planes, and its first-order phase error goes.
  std::vector<float> reach;
  std::size_t size() const { return axis.size(); }
};

/// Marks every face whose segment between cell centres crosses the surface (any number of times,
/// so a wall thinner than a cell still blocks it). Lines along each axis through the cell centres
/// are intersected with the triangles; a line through an edge or a vertex counts once.
BlockedFaces block_faces(const SurfaceMesh& mesh, const Grid& grid);

/// The recording box: the faces on the boundary of the cell range [lo, hi) with their outward
/// sign. Samples record p (interpolated from the four cells along the axis) and w there; the
/// box must lie two cells inside the domain.
struct RecordFaces {
  std::vector<uint32_t> axis;
  std::vector<uint64_t> cell;  ///< lower cell of the face
  std::vector<int8_t> sign;    ///< +1: the outward normal is +e_axis
  std::size_t size() const { return axis.size(); }
};
RecordFaces record_box(const Grid& grid, const std::array<uint32_t, 3>& lo,
                       const std::array<uint32_t, 3>& hi);

/// Everything a stepper needs. Velocities are scaled (w = rho0 c v); lambda = c dt / h.
struct Problem {
  Grid grid;
  /// Split-field coefficients per axis, per cell along that axis (p) and per face (w):
  /// x' = a x - b (difference). Interior cells have a = 1, b = lambda.
  std::array<std::vector<float>, 3> pa, pb, wa, wb;
  /// Cells in [pml_lo, pml_hi) along every axis are outside the layer (no split fields).
  std::array<uint32_t, 3> pml_lo{0, 0, 0}, pml_hi{0, 0, 0};
  BlockedFaces blocked;  ///< with its directions turned into the object's frame
  /// Drive series: a blocked face's w is sum over series of amplitude x drive. Two per mode, in
  /// phase and in quadrature, so that each face can carry its own delay.
  std::size_t series = 0;
  std::vector<float> amplitude;  ///< per blocked face, per series
  std::vector<float> drive;      ///< per step, per series, at t = (n + 1/2) dt
  std::size_t steps = 0;
  std::size_t first_sample = 0;  ///< recorded after steps first_sample, + stride, ...
  std::size_t stride = 1;
  RecordFaces record;
  /// The grid's frame to the object's: x_object = pivot + turn (x_grid - pivot), rows of a
  /// rotation. Identity unless the object was turned against the grid.
  std::array<Vec3, 3> turn{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  Vec3 pivot{0, 0, 0};
  Vec3 to_object(const Vec3& x) const { return turn_point(turn, pivot, x); }
  /// The grid's axis `a` in the object's frame (a column of turn).
  Vec3 axis_in_object(uint32_t a) const { return {turn[0][a], turn[1][a], turn[2][a]}; }
  std::size_t samples() const {
    return steps > first_sample ? (steps - first_sample + stride - 1) / stride : 0;
  }
};

/// Rows of the rotation by `angle` (radians) about coordinate axis `axis`.
std::array<Vec3, 3> turn_rows(int axis, double angle);
/// The mesh with every vertex x moved to pivot + rows (x - pivot).
SurfaceMesh turned(const SurfaceMesh& mesh, const std::array<Vec3, 3>& rows, const Vec3& pivot);

/// A stepping backend: runs the whole problem and returns the samples, [sample][face][p, w].
/// progress(steps done) is called now and then from the calling thread.
class Stepper {
 public:
  virtual ~Stepper() = default;
  virtual void run(const Problem& problem, std::vector<float>& samples,
                   const std::function<void(std::size_t)>& progress) = 0;
  virtual std::string name() const = 0;
};

std::unique_ptr<Stepper> make_cpu_stepper(int threads);
/// The Vulkan stepper (kernels/wave_*.comp); throws gpu::Error when the device cannot hold the
/// problem's buffers.
std::unique_ptr<Stepper> make_gpu_stepper(std::shared_ptr<gpu::Context> ctx);
/// The GPU stepper where options.gpu is set, else the CPU one.
std::unique_ptr<Stepper> make_stepper(const WaveOptions& options);

}  // namespace chladni::precompute::wave
