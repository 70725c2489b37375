#pragma once
#include <Eigen/Dense>

#include "chladni/precompute/fem.hpp"

namespace chladni::precompute {

/// Y = A X for a symmetric A (both triangles stored). Column j of the column-major A is also its
/// row j, so each row of Y gathers rows of X; with X held row-major a few columns at a time,
/// every stored entry costs one short contiguous multiply-add (Eigen's sparse * dense scatters
/// into Y column by column). Rows are shared among the cores.
void symmetric_product(const SparseMatrix& A, const Eigen::MatrixXd& X, Eigen::MatrixXd& Y);

}  // namespace chladni::precompute
