#pragma once
// Volume meshing with TetGen (only tetrahedralize.cpp includes tetgen.h).
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "chladni/core/material.hpp"
#include "chladni/core/vec3.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

struct TetMesh {
  std::vector<Vec3> nodes;
  std::vector<std::array<uint32_t, 4>> tets;  ///< positively oriented
  /// nodes[0, surface_vertices) are the input surface's vertices in their order: TetGen runs with
  /// -Y (no Steiner points on the surface; without it TetGen 1.5 can abort on poor surfaces).
  /// Where -Y leaves tetrahedra flat (TetOptions::flat_dihedral_deg), or without
  /// TetOptions::keep_surface, points added on the surface are numbered next.
  std::size_t surface_vertices = 0;
  /// The boundary triangles, outward: the input's, indexing nodes[0, surface_vertices), except
  /// where points were added on the surface and after refine_tets, which may split them.
  std::vector<std::array<uint32_t, 3>> surface_triangles;
};

struct TetOptions {
  double max_volume = 0;         ///< m^3; 0: no volume bound
  double max_radius_edge = 1.6;  ///< TetGen -q bound on circumradius / shortest edge
  double min_dihedral_deg = 10;  ///< TetGen -q dihedral bound
  /// Where the surface's own triangles admit no good tetrahedra (rotor.obj), -Y can leave some
  /// flat: a stiffness so large that round-off outweighs any shift and the factorization fails.
  /// A mesh with a dihedral angle below this (degrees) is made again with points added on the
  /// surface, and kept if its worst angle is better.
  double flat_dihedral_deg = 0.01;
  /// true: TetGen's -Y, the input triangles are the mesh's boundary. false: TetGen may add
  /// points on the surface where that is the only way to well-shaped tetrahedra (a CAD part's
  /// long thin triangles: the rotor's mean radius-edge ratio 6.5 under -Y, 1.3 without), within
  /// a minute of CPU time (without -Y TetGen can loop on fine surfaces). Not the default: a thin
  /// plate's or shell's one layer is poorly shaped too, yet refines to the tolerance with far
  /// fewer tetrahedra than mending it makes (a 2 mm disc: under 10,000 against 72,612), so the
  /// refinement loop weighs the two (kPoorMeanRadiusEdge).
  bool keep_surface = true;
  /// Called with a flat mesh before it is made again (larger: the surface is refined to the
  /// quality bounds); may throw to stop there, e.g. when that mesh is already over budget.
  std::function<void(const TetMesh&)> before_remesh;
};

struct TetQuality {
  double max_radius_edge = 0;  ///< worst circumradius / shortest edge (regular tet: 0.612)
  double mean_radius_edge = 0;
  double min_dihedral_deg = 0;  ///< smallest dihedral angle of any tet (regular: 70.5)
  double max_dihedral_deg = 0;  ///< largest (a flat tetrahedron: near 180)
  double volume = 0;            ///< total, m^3
};

/// A quality mesh averages a radius-edge ratio of 1.05-1.35 (the bundled meshes from good
/// surfaces); over this mean a mesh is poorly shaped.
inline constexpr double kPoorMeanRadiusEdge = 1.5;

/// The most tetrahedra this tool makes (meshing and refinement refuse beyond it).
inline constexpr std::size_t kMaxTetrahedra = 20'000'000;

/// Quality tetrahedralization of a valid closed surface. Throws InputError with TetGen's reason
/// when it refuses the surface.
TetMesh tetrahedralize(const SurfaceMesh& surface, const TetOptions& options);

TetQuality tet_quality(const TetMesh& mesh);

/// Refines `mesh` where max_volume (one bound per tetrahedron; <= 0: none) asks, under
/// `options`' quality bounds (its max_volume is not used). The nodes are kept, in order, and new
/// ones appended; boundary faces may be split, so surface_triangles is the new boundary (it may
/// index nodes past surface_vertices, which stays the input's). Throws InputError when TetGen
/// fails.
TetMesh refine_tets(const TetMesh& mesh, const std::vector<double>& max_volume,
                    const TetOptions& options);

/// How many tetrahedra `max_volume` (as for refine_tets) asks of `mesh` at least: each
/// tetrahedron's volume over its bound, and one where that is less or it has none.
double tetrahedra_asked(const TetMesh& mesh, const std::vector<double>& max_volume);

/// The same refinement by longest-edge bisection (Rivara), which cannot fail: every
/// tetrahedron over its bound is halved at its longest edge, its neighbours along the edges cut
/// as conformity asks, until each is within its bound. Without TetGen's quality bounds, the
/// fallback when refine_tets throws. Nodes are kept as refine_tets keeps them.
TetMesh bisect_tets(const TetMesh& mesh, const std::vector<double>& max_volume);

/// The mesh's boundary faces (those of one tetrahedron), oriented outward.
std::vector<std::array<uint32_t, 3>> boundary_faces(const TetMesh& mesh);

/// Signed volume of tetrahedron `e` (positive for the orientation TetMesh keeps).
inline double tet_volume(const TetMesh& m, std::size_t e) {
  const auto& t = m.tets[e];
  const Vec3& a = m.nodes[t[0]];
  return dot(cross(sub(m.nodes[t[1]], a), sub(m.nodes[t[2]], a)), sub(m.nodes[t[3]], a)) / 6;
}

/// The coarsest tets worth meshing with: a few hundred in the surface's bounding box.
double coarse_max_volume(const SurfaceMesh& surface);

/// Largest tet volume that resolves the shortest wave of interest: the shear wavelength at
/// `max_frequency` divided by `per_wavelength` (12 for linear, 6 for quadratic elements) gives
/// the edge length h, and a regular tet of edge h has volume h^3 / (6 sqrt 2). At most
/// coarse_max_volume.
double auto_max_volume(const Material& material, double max_frequency, int order,
                       const SurfaceMesh& surface);

}  // namespace chladni::precompute
