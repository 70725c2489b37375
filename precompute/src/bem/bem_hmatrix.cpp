// Hierarchical-matrix storage of the Burton-Miller system (hmat-oss, Airbus's H-matrix library
// for boundary-element acoustics). Far blocks are compressed by ACA+ (Bebendorf & Grzhibovskis
// 2006) from entries computed on demand: the centroid rule for every pair, plus the cached near
// corrections of the pairs closer than far_ratio element sizes, so the compressed matrix is the
// dense solver's matrix to within the compression tolerance. Its LU, computed at a coarser
// tolerance, preconditions GMRES at nearby frequencies.
#include "bem_hmatrix.hpp"

#include <hmat/hmat.h>

#include <cmath>
#include <numbers>
#include <string>

#include "../blas_threads.hpp"
#include "../parallel.hpp"
#include "bem_near.hpp"
#include "chladni/core/error.hpp"

namespace chladni::precompute::bem_detail {

struct HMatrixSystem::Impl {
  const BemMesh& mesh;
  const BemSolver::NearCache& cache;
  BemOptions options;
  hmat_interface_t hi{};
  hmat_clustering_algorithm_t* clustering = nullptr;
  hmat_cluster_tree_t* tree = nullptr;
  hmat_admissibility_t* admissibility = nullptr;
  hmat_matrix_t* matrix = nullptr;  // A at k
  hmat_matrix_t* lu = nullptr;      // LU of A at lu_k
  double k = 0, al = 0, lu_k = 0;
  // Near corrections of A at k: by rows (row_start, cols, values) and the same entries by
  // columns (col_start, col_rows, col_slot into values), for ACA's row and column requests.
  std::vector<std::size_t> row_start, col_start, col_slot;
  std::vector<uint32_t> cols, col_rows;
  std::vector<cd> values, diagonal;

  Impl(const BemMesh& m, const BemSolver::NearCache& c, const BemOptions& o)
      : mesh(m), cache(c), options(o) {
    hmat_init_default_interface(&hi, HMAT_DOUBLE_COMPLEX);
    const std::size_t n = m.elements();
    std::vector<double> coord(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) coord[3 * i + std::size_t(d)] = m.centroid[i][d];
    clustering = hmat_create_clustering_median();
    tree = hmat_create_cluster_tree(coord.data(), 3, int(n), clustering);
    admissibility = hmat_create_admissibility_standard(2.0);
    if (!tree || !admissibility)
      throw InternalError("bem: hmat-oss could not build its cluster tree");
    row_start.assign(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) row_start[i + 1] = row_start[i] + c.rows[i].size();
    cols.resize(row_start[n]);
    std::vector<std::size_t> count(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t e = 0; e < c.rows[i].size(); ++e) {
        cols[row_start[i] + e] = c.rows[i][e].j;
        ++count[c.rows[i][e].j + 1];
      }
    col_start.assign(n + 1, 0);
    for (std::size_t j = 0; j < n; ++j) col_start[j + 1] = col_start[j] + count[j + 1];
    col_rows.resize(cols.size());
    col_slot.resize(cols.size());
    std::vector<std::size_t> fill(col_start.begin(), col_start.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t s = row_start[i]; s < row_start[i + 1]; ++s) {
        col_rows[fill[cols[s]]] = uint32_t(i);
        col_slot[fill[cols[s]]++] = s;
      }
  }
  ~Impl() {
    if (lu) hi.destroy(lu);
    if (matrix) hi.destroy(matrix);
    if (admissibility) hmat_delete_admissibility(admissibility);
    if (tree) hmat_delete_cluster_tree(tree);
    if (clustering) hmat_delete_clustering(clustering);
  }

  // One block request of hmat-oss (rows r0.., columns c0.., in its numbering).
  struct Block {
    const Impl* self;
    int row0, col0;
    const int *row_client, *col_client, *row_hmat, *col_hmat;
  };
  static void prepare(int row_start, int, int col_start, int, int* row_h2c, int* row_c2h,
                      int* col_h2c, int* col_c2h, void* context, hmat_block_info_t* info) {
    info->block_type = hmat_block_full;
    info->user_data = new Block{static_cast<const Impl*>(context),
                                row_start,
                                col_start,
                                row_h2c,
                                col_h2c,
                                row_c2h,
                                col_c2h};
    info->release_user_data = [](void* p) { delete static_cast<Block*>(p); };
  }
  // Column-major out (rows x cols) of the sub-block at (br, bc): full blocks, or one row or one
  // column for ACA. The corrections are found by rows or by columns, whichever is shorter.
  static void compute(void* data, int br, int rows, int bc, int ncols, void* out_v) {
    const Block& b = *static_cast<const Block*>(data);
    const Impl& s = *b.self;
    cd* out = static_cast<cd*>(out_v);
    const int r0 = b.row0 + br, c0 = b.col0 + bc;
    thread_local std::vector<uint32_t> ri, ci;
    thread_local std::vector<double> re, im;
    ri.assign(b.row_client + r0, b.row_client + r0 + rows);
    ci.assign(b.col_client + c0, b.col_client + c0 + ncols);
    const std::size_t size = std::size_t(rows) * std::size_t(ncols);
    re.resize(size);
    im.resize(size);
    far_block(s.cache.far, ri.data(), ri.size(), ci.data(), ci.size(), s.k, s.al, re.data(),
              im.data());
    for (std::size_t e = 0; e < size; ++e) out[e] = cd(re[e], im[e]);
    for (int c = 0; c < ncols; ++c) {
      const int r = b.row_hmat[ci[std::size_t(c)]] - r0;  // the diagonal: the self term
      if (r >= 0 && r < rows)
        out[std::size_t(r) + std::size_t(c) * std::size_t(rows)] = s.diagonal[ci[std::size_t(c)]];
    }
    if (rows <= ncols) {
      for (int r = 0; r < rows; ++r) {
        const std::size_t i = std::size_t(b.row_client[r0 + r]);
        for (std::size_t e = s.row_start[i]; e < s.row_start[i + 1]; ++e) {
          const int c = b.col_hmat[s.cols[e]] - c0;
          if (c >= 0 && c < ncols)
            out[std::size_t(r) + std::size_t(c) * std::size_t(rows)] += s.values[e];
        }
      }
    } else {
      for (int c = 0; c < ncols; ++c) {
        const std::size_t j = std::size_t(b.col_client[c0 + c]);
        for (std::size_t e = s.col_start[j]; e < s.col_start[j + 1]; ++e) {
          const int r = b.row_hmat[s.col_rows[e]] - r0;
          if (r >= 0 && r < rows)
            out[std::size_t(r) + std::size_t(c) * std::size_t(rows)] += s.values[s.col_slot[e]];
        }
      }
    }
  }
};

HMatrixSystem::HMatrixSystem(const BemMesh& mesh, const BemSolver::NearCache& cache,
                             const BemOptions& o)
    : impl_(std::make_unique<Impl>(mesh, cache, o)) {}

HMatrixSystem::~HMatrixSystem() = default;

void HMatrixSystem::assemble(double k, std::span<const cd> q, std::vector<cd>& b) {
  Impl& s = *impl_;
  const BemMesh& m = s.mesh;
  const std::size_t n = m.elements();
  const cd alpha = coupling(m, k, s.options);
  s.k = k;
  s.al = alpha.imag();
  s.values.resize(s.cols.size());
  s.diagonal.resize(n);
  b.assign(n, cd(0.0));
  // Per row: the near corrections, the self term, and b_i = -(alpha/2) q_i - sum_j B_ij q_j with
  // the centroid rule's B row (far_rhs) corrected near i.
  std::vector<double> qre(n), qim(n);
  for (std::size_t j = 0; j < n; ++j) qre[j] = q[j].real(), qim[j] = q[j].imag();
  parallel_for(n, s.options.threads, [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) {
      cd rhs = far_rhs(s.cache.far, m.centroid[i], m.normal[i], k, s.al, qre.data(), qim.data(), i);
      std::size_t slot = s.row_start[i];
      near_row(m, s.cache, k, alpha, i, [&](uint32_t j, cd da, cd db) {
        s.values[slot++] = da;
        rhs += db * q[j];
      });
      const SelfTerms self = self_terms(m, s.cache, k, alpha, s.options, i);
      s.diagonal[i] = self.a;
      b[i] = -0.5 * alpha * q[i] - rhs - self.b * q[i];
    }
  });
  const SingleThreadedBlas blas;
  if (s.matrix) s.hi.destroy(s.matrix);
  s.matrix = s.hi.create_empty_hmatrix_admissibility(s.tree, s.tree, 0, s.admissibility);
  if (!s.matrix) throw InternalError("bem: hmat-oss could not create the matrix");
  s.hi.set_low_rank_epsilon(s.matrix, s.options.hmatrix_epsilon);
  hmat_assemble_context_t ctx;
  hmat_assemble_context_init(&ctx);
  hmat_compression_algorithm_t* aca = hmat_create_compression_aca_plus(s.options.hmatrix_epsilon);
  ctx.compression = aca;
  ctx.prepare = &Impl::prepare;
  ctx.block_compute = &Impl::compute;
  ctx.user_context = &s;
  ctx.progress = nullptr;
  ctx.factorization = hmat_factorization_none;
  const int rc = s.hi.assemble_generic(s.matrix, &ctx);
  hmat_delete_compression(aca);
  if (rc != 0)
    throw InternalError("bem: hmat-oss failed to assemble (code " + std::to_string(rc) + ")");
}

void HMatrixSystem::apply(const cd* x, cd* y) const {
  const Impl& s = *impl_;
  const std::size_t n = s.mesh.elements();
  std::vector<cd> in(x, x + n);  // gemv renumbers its operands in place
  std::fill(y, y + n, cd(0.0));
  cd one = 1.0, zero = 0.0;
  const SingleThreadedBlas blas;
  s.hi.gemv('N', &one, s.matrix, in.data(), &zero, y, 1);
}

void HMatrixSystem::factorize() {
  Impl& s = *impl_;
  const SingleThreadedBlas blas;
  if (s.lu) s.hi.destroy(s.lu), s.lu = nullptr;
  hmat_matrix_t* lu = s.hi.copy(s.matrix);
  if (!lu) throw InternalError("bem: hmat-oss could not copy the matrix");
  s.hi.set_low_rank_epsilon(lu, s.options.hmatrix_lu_epsilon);
  hmat_factorization_context_t ctx;
  hmat_factorization_context_init(&ctx);
  ctx.factorization = hmat_factorization_lu;
  ctx.progress = nullptr;
  if (s.hi.factorize_generic(lu, &ctx) != 0) {
    s.hi.destroy(lu);
    throw InternalError("bem: the hierarchical LU failed (degenerate surface?)");
  }
  s.lu = lu;
  s.lu_k = s.k;
}

void HMatrixSystem::precondition(cd* x) const {
  const Impl& s = *impl_;
  const SingleThreadedBlas blas;
  s.hi.solve_systems(s.lu, x, 1);
}

bool HMatrixSystem::factorized() const {
  return impl_->lu != nullptr;
}
double HMatrixSystem::factor_k() const {
  return impl_->lu_k;
}

std::size_t HMatrixSystem::bytes() const {
  const Impl& s = *impl_;
  std::size_t total = 0;
  for (hmat_matrix_t* h : {s.matrix, s.lu}) {
    if (!h) continue;
    hmat_info_t info;
    s.hi.get_info(h, &info);
    total += info.compressed_size * sizeof(cd);
  }
  return total;
}

}  // namespace chladni::precompute::bem_detail
