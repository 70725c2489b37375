#pragma once
// Linear isotropic elasticity on linear (P1, 4-node) and quadratic (P2, 10-node) tetrahedra:
// stiffness K and mass M assembled as Eigen sparse matrices (DOF 3n + k is node n's axis k).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>

#include "chladni/core/material.hpp"
#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

struct FemMesh {
  int order = 1;  ///< 1: 4 nodes per element; 2: 10 (corners, then edges 01 12 02 03 13 23)
  std::vector<Vec3> nodes;
  std::vector<uint32_t> elements;    ///< nodes_per_element() indices per element
  std::size_t surface_vertices = 0;  ///< nodes[0, surface_vertices) are the surface's vertices
  int nodes_per_element() const { return order == 1 ? 4 : 10; }
  std::size_t element_count() const { return elements.size() / nodes_per_element(); }
  std::size_t dofs() const { return 3 * nodes.size(); }
};

/// P1: the tet mesh as is. P2: adds one node at the midpoint of every edge (straight sides).
FemMesh make_fem_mesh(const TetMesh& tets, int order);

enum class MassKind { Consistent, Lumped };

struct FemMatrices {
  /// Full symmetric storage. M stores only what can be nonzero: one direction coupled with
  /// itself (m_ab I3), so a third of K's entries, and only the diagonal when lumped.
  SparseMatrix K, M;
};

/// Assembles K and M with `threads` workers (0: all cores), each into its own copy of the shared
/// sparsity pattern, summed at the end: the result is the same on every run with the same thread
/// count (only the order of floating-point sums changes with it).
FemMatrices assemble(const FemMesh& mesh, const Material& material, MassKind mass, int threads = 0,
                     const std::function<void(double)>& progress = {});

// Element matrices (exposed for tests). x: the four corners; DOF order node-major (3a + i).
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Mat30 = Eigen::Matrix<double, 30, 30>;
void p1_element(const Vec3 x[4], double lambda, double mu, double rho, Mat12& K, Mat12& M);
void p2_element(const Vec3 x[4], double lambda, double mu, double rho, Mat30& K, Mat30& M);

/// The six rigid-body motions (three translations, three rotations about the centroid) as DOF
/// vectors, one per column.
Eigen::MatrixXd rigid_body_modes(const std::vector<Vec3>& nodes);

}  // namespace chladni::precompute
