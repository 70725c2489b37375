#pragma once
// Pieces of the tetrahedral elements shared by the assembly (fem.cpp) and the error estimate
// (mode_error.cpp).
#include <Eigen/Core>

#include "chladni/core/vec3.hpp"

namespace chladni::precompute::detail {

/// Edge order of the quadratic tet's mid-edge nodes 4..9.
inline constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};

/// Gradients of the barycentric coordinates L0..L3 (constant on a straight-sided tet); returns
/// the volume. Throws InputError for a degenerate or inverted tet.
double barycentric_gradients(const Vec3 x[4], Eigen::Matrix<double, 4, 3>& g);

/// The scalar P2 mass matrix of a unit-volume tet, exact.
const Eigen::Matrix<double, 10, 10>& p2_unit_mass();

}  // namespace chladni::precompute::detail
