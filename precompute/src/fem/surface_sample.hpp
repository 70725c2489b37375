#pragma once
// Mode shapes at the points of a surface that lies on a (finer) tet mesh's boundary: the
// soundbank keeps the surface of the first mesh solved while refinement solves on finer ones,
// so vertex indices, and the transfer's cost, do not change with the accuracy asked for.
#include <Eigen/Core>

#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {

/// `vectors`: DOF vectors (3 per node, node-major) on `tets`' nodes, one column per mode.
/// Returns 3 rows per vertex of `surface`: exact where the vertex is a node of `tets`, else
/// linear on the nearest of `tets`' boundary triangles.
Eigen::MatrixXd sample_on_surface(const TetMesh& tets, const Eigen::MatrixXd& vectors,
                                  const SurfaceMesh& surface);

}  // namespace chladni::precompute
