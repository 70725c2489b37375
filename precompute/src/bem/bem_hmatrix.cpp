// Hierarchical-matrix storage of the Burton-Miller system (hmat-oss, Airbus's H-matrix library
// for boundary-element acoustics). Far blocks are compressed by ACA+ (Bebendorf & Grzhibovskis
// 2006) from entries computed on demand: the centroid rule for every pair, plus the cached near
// corrections of the pairs closer than far_ratio element sizes, so the compressed matrix is the
// dense solver's matrix to within the compression tolerance. Its LU, computed at a coarser
// tolerance, preconditions GMRES at nearby frequencies.
#include "bem_hmatrix.hpp"

#include <hmat/hmat.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "../blas_threads.hpp"
#include "../parallel.hpp"
#include "bem_near.hpp"
#include "chladni/core/error.hpp"

namespace chladni::precompute::bem_detail {

// Everything below is in hmat-oss's numbering of the elements (h), in which every block is a
// contiguous range of rows and of columns; `client` maps it back to the mesh's.
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
  std::vector<int> client;  // h -> mesh element
  FarGeometry geometry;     // in h order, so a block's centroids are contiguous
  // Near corrections of A at k by rows (row_start; cols sorted ascending; values), and the same
  // entries by columns (col_start; col_rows sorted ascending; col_slot into values), for ACA's
  // row and column requests. slot[cache_start[i] + e]: where cache.rows[i][e] lives in values.
  std::vector<std::size_t> row_start, col_start, col_slot, cache_start, slot;
  std::vector<int> cols, col_rows;
  std::vector<cd> values, diagonal;  // diagonal by mesh element

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
    const int* order = hmat_cluster_get_indices(tree);
    client.assign(order, order + n);
    geometry = FarGeometry(c.far, order);
    std::vector<int> h_of(n);
    for (std::size_t h = 0; h < n; ++h) h_of[std::size_t(client[h])] = int(h);
    cache_start.assign(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) cache_start[i + 1] = cache_start[i] + c.rows[i].size();
    slot.resize(cache_start[n]);
    cols.resize(cache_start[n]);
    row_start.assign(n + 1, 0);
    std::vector<std::size_t> col_count(n + 1, 0);
    std::vector<std::pair<int, std::size_t>> sorted;
    for (std::size_t h = 0; h < n; ++h) {
      const std::size_t i = std::size_t(client[h]);
      row_start[h + 1] = row_start[h] + c.rows[i].size();
      sorted.clear();
      for (std::size_t e = 0; e < c.rows[i].size(); ++e)
        sorted.push_back({h_of[c.rows[i][e].j], e});
      std::sort(sorted.begin(), sorted.end());
      for (std::size_t r = 0; r < sorted.size(); ++r) {
        cols[row_start[h] + r] = sorted[r].first;
        slot[cache_start[i] + sorted[r].second] = row_start[h] + r;
        ++col_count[std::size_t(sorted[r].first) + 1];
      }
    }
    col_start.assign(n + 1, 0);
    for (std::size_t j = 0; j < n; ++j) col_start[j + 1] = col_start[j] + col_count[j + 1];
    col_rows.resize(cols.size());
    col_slot.resize(cols.size());
    std::vector<std::size_t> fill(col_start.begin(), col_start.end() - 1);
    for (std::size_t h = 0; h < n; ++h)  // ascending h: each column's rows come out sorted
      for (std::size_t e = row_start[h]; e < row_start[h + 1]; ++e) {
        const std::size_t j = std::size_t(cols[e]);
        col_rows[fill[j]] = int(h);
        col_slot[fill[j]++] = e;
      }
  }
  ~Impl() {
    if (lu) hi.destroy(lu);
    if (matrix) hi.destroy(matrix);
    if (admissibility) hmat_delete_admissibility(admissibility);
    if (tree) hmat_delete_cluster_tree(tree);
    if (clustering) hmat_delete_clustering(clustering);
  }

  struct Block {  // one block request of hmat-oss: rows row0.., columns col0..
    const Impl* self;
    int row0, col0;
  };
  static void prepare(int row_start, int, int col_start, int, int*, int*, int*, int*, void* context,
                      hmat_block_info_t* info) {
    info->block_type = hmat_block_full;
    info->user_data = new Block{static_cast<const Impl*>(context), row_start, col_start};
    info->release_user_data = [](void* p) { delete static_cast<Block*>(p); };
  }
  // Column-major out (rows x cols) of the sub-block at (br, bc): full blocks, or one row or one
  // column for ACA. The corrections are found by rows or by columns, whichever is shorter.
  static void compute(void* data, int br, int rows, int bc, int ncols, void* out_v) {
    const Block& b = *static_cast<const Block*>(data);
    const Impl& s = *b.self;
    cd* out = static_cast<cd*>(out_v);
    const int r0 = b.row0 + br, c0 = b.col0 + bc, r1 = r0 + rows, c1 = c0 + ncols;
    auto at = [&](int h, int g) -> cd& {
      return out[std::size_t(h - r0) + std::size_t(g - c0) * std::size_t(rows)];
    };
    thread_local std::vector<double> re, im;
    const std::size_t size = std::size_t(rows) * std::size_t(ncols);
    re.resize(size);
    im.resize(size);
    far_block(s.geometry, std::size_t(r0), std::size_t(rows), std::size_t(c0), std::size_t(ncols),
              s.k, s.al, re.data(), im.data());
    for (std::size_t e = 0; e < size; ++e) out[e] = cd(re[e], im[e]);
    for (int h = std::max(r0, c0); h < std::min(r1, c1); ++h)
      at(h, h) = s.diagonal[std::size_t(s.client[std::size_t(h)])];  // the self term
    if (rows <= ncols) {
      for (int h = r0; h < r1; ++h) {
        const int* first = s.cols.data() + s.row_start[std::size_t(h)];
        const int* last = s.cols.data() + s.row_start[std::size_t(h) + 1];
        for (const int* e = std::lower_bound(first, last, c0); e != last && *e < c1; ++e)
          at(h, *e) += s.values[std::size_t(e - s.cols.data())];
      }
    } else {
      for (int g = c0; g < c1; ++g) {
        const int* first = s.col_rows.data() + s.col_start[std::size_t(g)];
        const int* last = s.col_rows.data() + s.col_start[std::size_t(g) + 1];
        for (const int* e = std::lower_bound(first, last, r0); e != last && *e < r1; ++e)
          at(*e, g) += s.values[s.col_slot[std::size_t(e - s.col_rows.data())]];
      }
    }
  }
};

HMatrixSystem::HMatrixSystem(const BemMesh& mesh, const BemSolver::NearCache& cache,
                             const BemOptions& o)
    : impl_(std::make_unique<Impl>(mesh, cache, o)) {}

HMatrixSystem::~HMatrixSystem() = default;

void HMatrixSystem::assemble(double k, std::span<const std::vector<cd>> qs,
                             std::vector<std::vector<cd>>& bs) {
  Impl& s = *impl_;
  const BemMesh& m = s.mesh;
  const std::size_t n = m.elements(), count = qs.size();
  const cd alpha = coupling(m, k, s.options);
  s.k = k;
  s.al = alpha.imag();
  s.values.resize(s.cols.size());
  s.diagonal.resize(n);
  bs.assign(count, std::vector<cd>(n, cd(0.0)));
  // Per row: the near corrections, the self term, and b_i = -(alpha/2) q_i - sum_j B_ij q_j with
  // the centroid rule's B row (far_rhs) corrected near i, for every q at once.
  const SplitRightHandSides split(qs, 0);
  parallel_for(n, s.options.threads, [&](std::size_t i0, std::size_t i1) {
    std::vector<cd> rhs(count);
    for (std::size_t i = i0; i < i1; ++i) {
      far_rhs(s.cache.far, m.centroid[i], m.normal[i], k, s.al, split.pre, split.pim, i,
              rhs.data());
      std::size_t e = s.cache_start[i];
      near_row(m, s.cache, k, alpha, i, [&](uint32_t j, cd da, cd db) {
        s.values[s.slot[e++]] = da;
        for (std::size_t v = 0; v < count; ++v) rhs[v] += db * qs[v][j];
      });
      const SelfTerms self = self_terms(m, s.cache, k, alpha, s.options, i);
      s.diagonal[i] = self.a;
      for (std::size_t v = 0; v < count; ++v)
        bs[v][i] = -0.5 * alpha * qs[v][i] - rhs[v] - self.b * qs[v][i];
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
