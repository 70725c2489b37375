#include "chladni/precompute/fem.hpp"

#include <Eigen/LU>
#include <algorithm>

#include <atomic>
#include <limits>
#include <map>
#include <mutex>
#include <thread>
#include <unordered_map>

#include "../huge_pages.hpp"
#include "chladni/core/error.hpp"
#include "fem_element.hpp"

namespace chladni::precompute {
namespace detail {

double barycentric_gradients(const Vec3 x[4], Eigen::Matrix<double, 4, 3>& g) {
  Eigen::Matrix3d J;
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < 3; ++r) J(r, k) = x[k + 1][r] - x[0][r];
  const double det = J.determinant();
  if (!(det > 0))
    throw InputError("degenerate or inverted tetrahedron (volume " + std::to_string(det / 6) + ")");
  const Eigen::Matrix3d Jinv = J.inverse();  // rows: gradients of L1, L2, L3
  g.row(1) = Jinv.row(0), g.row(2) = Jinv.row(1), g.row(3) = Jinv.row(2);
  g.row(0) = -(g.row(1) + g.row(2) + g.row(3));
  return det / 6;
}

// Scalar P2 mass matrix on the unit-volume tet, exact: integral of L^a = 6V a!b!c!d!/(a+b+c+d+3)!
// gives (1/420) [corner diag 6, corner-corner 1, corner-edge -4 (edge at the corner) or -6,
// edge diag 32, edges sharing a corner 16, opposite edges 8].
const Eigen::Matrix<double, 10, 10>& p2_unit_mass() {
  static const Eigen::Matrix<double, 10, 10> unit = [] {
    Eigen::Matrix<double, 10, 10> m;
    for (int a = 0; a < 10; ++a)
      for (int b = 0; b < 10; ++b) {
        double v;
        if (a < 4 && b < 4) {
          v = a == b ? 6 : 1;
        } else if (a >= 4 && b >= 4) {
          const auto& ea = kEdges[a - 4];
          const auto& eb = kEdges[b - 4];
          const int shared =
              (ea[0] == eb[0]) + (ea[0] == eb[1]) + (ea[1] == eb[0]) + (ea[1] == eb[1]);
          v = a == b ? 32 : shared ? 16 : 8;
        } else {
          const int c = a < 4 ? a : b;
          const auto& e = kEdges[(a < 4 ? b : a) - 4];
          v = (e[0] == c || e[1] == c) ? -4 : -6;
        }
        m(a, b) = v / 420.0;
      }
    return m;
  }();
  return unit;
}

}  // namespace detail

namespace {

using detail::barycentric_gradients;
using detail::kEdges;

// K_(a,i),(b,j) += w (lambda g_a,i g_b,j + mu g_a,j g_b,i + mu delta_ij g_a . g_b): the Hessian
// of the strain energy density lambda/2 (div u)^2 + mu eps:eps for u = sum_b u_b N_b.
template <int N>
void add_stiffness(const Eigen::Matrix<double, N, 3>& G, double w, double lambda, double mu,
                   Eigen::Matrix<double, 3 * N, 3 * N>& K) {
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b) {
      const double gg = G.row(a).dot(G.row(b));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          K(3 * a + i, 3 * b + j) +=
              w * (lambda * G(a, i) * G(b, j) + mu * G(a, j) * G(b, i) + (i == j ? mu * gg : 0.0));
    }
}

template <int N>
void expand_mass(const Eigen::Matrix<double, N, N>& m, Eigen::Matrix<double, 3 * N, 3 * N>& M) {
  M.setZero();
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b)
      for (int i = 0; i < 3; ++i) M(3 * a + i, 3 * b + i) = m(a, b);
}

}  // namespace

void p1_element(const Vec3 x[4], double lambda, double mu, double rho, Mat12& K, Mat12& M) {
  Eigen::Matrix<double, 4, 3> g;
  const double V = barycentric_gradients(x, g);
  K.setZero();
  add_stiffness<4>(g, V, lambda, mu, K);  // constant strain: one-point rule is exact
  Eigen::Matrix<double, 4, 4> m;
  m.setConstant(rho * V / 20);  // integral L_a L_b = V (1 + delta_ab) / 20
  m.diagonal().setConstant(rho * V / 10);
  expand_mass<4>(m, M);
}

void p2_element(const Vec3 x[4], double lambda, double mu, double rho, Mat30& K, Mat30& M) {
  Eigen::Matrix<double, 4, 3> g;
  const double V = barycentric_gradients(x, g);
  // The stiffness integrand is quadratic in L: the 4-point degree-2 rule is exact.
  constexpr double a = 0.5854101966249685, b = 0.1381966011250105;
  K.setZero();
  for (int q = 0; q < 4; ++q) {
    double L[4] = {b, b, b, b};
    L[q] = a;
    Eigen::Matrix<double, 10, 3> G;
    for (int c = 0; c < 4; ++c) G.row(c) = (4 * L[c] - 1) * g.row(c);  // N_c = L_c (2 L_c - 1)
    for (int e = 0; e < 6; ++e) {                                      // N_e = 4 L_i L_j
      const int i = kEdges[e][0], j = kEdges[e][1];
      G.row(4 + e) = 4 * (L[i] * g.row(j) + L[j] * g.row(i));
    }
    add_stiffness<10>(G, V / 4, lambda, mu, K);
  }
  const Eigen::Matrix<double, 10, 10>& unit = detail::p2_unit_mass();
  const Eigen::Matrix<double, 10, 10> m = rho * V * unit;
  expand_mass<10>(m, M);
}

FemMesh make_fem_mesh(const TetMesh& t, int order) {
  if (order != 1 && order != 2) throw InputError("element order must be 1 or 2");
  FemMesh f;
  f.order = order;
  f.nodes = t.nodes;
  f.surface_vertices = t.surface_vertices;
  if (order == 1) {
    f.elements.reserve(4 * t.tets.size());
    for (const auto& tet : t.tets) f.elements.insert(f.elements.end(), tet.begin(), tet.end());
    return f;
  }
  std::unordered_map<uint64_t, uint32_t> mid;
  mid.reserve(t.tets.size() * 2);
  f.elements.reserve(10 * t.tets.size());
  for (const auto& tet : t.tets) {
    f.elements.insert(f.elements.end(), tet.begin(), tet.end());
    for (const auto& e : kEdges) {
      const uint32_t u = std::min(tet[e[0]], tet[e[1]]), v = std::max(tet[e[0]], tet[e[1]]);
      const uint64_t key = uint64_t(u) << 32 | v;
      auto [it, fresh] = mid.emplace(key, uint32_t(f.nodes.size()));
      if (fresh) {
        const Vec3 &p = t.nodes[u], &q = t.nodes[v];
        f.nodes.push_back({(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2});
      }
      f.elements.push_back(it->second);
    }
  }
  return f;
}

namespace {

// The node graph (CSR): sorted neighbours of every node, itself included, and where each node
// pair's entries sit in K (9 per pair: column 3n + c holds rows 3m + r for m in nbr(n)) and in
// M, which couples a direction only with itself (m_ab I3, expand_mass) and so stores rows 3m + c
// only: a third of the memory and of the work of every mass product. `per_pair` (9 or 3) says
// which; a column holds per_pair / 3 rows per neighbour.
struct NodeGraph {
  std::vector<std::size_t> ptr;
  std::vector<uint32_t> nbr;

  explicit NodeGraph(const FemMesh& mesh) {
    const int npe = mesh.nodes_per_element();
    const std::size_t ne = mesh.element_count(), nn = mesh.nodes.size();
    std::vector<uint64_t> pairs;
    pairs.reserve(ne * npe * npe);
    for (std::size_t e = 0; e < ne; ++e) {
      const uint32_t* en = &mesh.elements[e * npe];
      for (int a = 0; a < npe; ++a)
        for (int b = 0; b < npe; ++b) pairs.push_back(uint64_t(en[b]) << 32 | en[a]);
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    ptr.assign(nn + 1, 0);
    nbr.resize(pairs.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      ++ptr[(pairs[k] >> 32) + 1];
      nbr[k] = uint32_t(pairs[k]);
    }
    for (std::size_t n = 0; n < nn; ++n) ptr[n + 1] += ptr[n];
  }
  std::size_t column_start(int per_pair, std::size_t n, int c) const {
    return per_pair * ptr[n] + c * (per_pair / 3) * (ptr[n + 1] - ptr[n]);
  }
  // Where row_node sits among col_node's sorted neighbours.
  std::size_t rank(uint32_t row_node, uint32_t col_node) const {
    const uint32_t* b = &nbr[ptr[col_node]];
    const uint32_t* e = &nbr[ptr[col_node + 1]];
    return std::size_t(std::lower_bound(b, e, row_node) - b);
  }
  void pattern(SparseMatrix& A, int per_pair) const {
    const std::size_t nn = ptr.size() - 1, entries = std::size_t(per_pair) * nbr.size();
    A.resize(int(3 * nn), int(3 * nn));
    A.resizeNonZeros(int(entries));
    advise_huge_pages(A.valuePtr(), entries * sizeof(double));
    advise_huge_pages(A.innerIndexPtr(), entries * sizeof(int));
    int* outer = A.outerIndexPtr();
    int* inner = A.innerIndexPtr();
    const int rows = per_pair / 3;
    for (std::size_t n = 0; n < nn; ++n)
      for (int c = 0; c < 3; ++c) {
        const std::size_t start = column_start(per_pair, n, c);
        outer[3 * n + c] = int(start);
        for (std::size_t k = ptr[n]; k < ptr[n + 1]; ++k)
          for (int r = 0; r < rows; ++r)
            inner[start + rows * (k - ptr[n]) + r] = int(3 * nbr[k] + (rows == 3 ? r : c));
      }
    outer[3 * nn] = int(entries);
  }
};

// Elements lo..hi of `mesh` added into one worker's values of K (kv) and M (mv), laid out as
// `g` says.
void scatter_elements(const FemMesh& mesh, const NodeGraph& g, const Material& mat, std::size_t lo,
                      std::size_t hi, std::vector<double>& kv, std::vector<double>& mv,
                      const std::function<void(double)>* progress) {
  const int npe = mesh.nodes_per_element();
  const double lambda = mat.lame_lambda(), mu = mat.lame_mu(), rho = mat.density;
  Mat12 K1, M1;
  Mat30 K2, M2;
  for (std::size_t e = lo; e < hi; ++e) {
    const uint32_t* en = &mesh.elements[e * npe];
    const Vec3 x[4] = {mesh.nodes[en[0]], mesh.nodes[en[1]], mesh.nodes[en[2]], mesh.nodes[en[3]]};
    const double* Kp;
    const double* Mp;
    try {
      if (npe == 4)
        p1_element(x, lambda, mu, rho, K1, M1), Kp = K1.data(), Mp = M1.data();
      else
        p2_element(x, lambda, mu, rho, K2, M2), Kp = K2.data(), Mp = M2.data();
    } catch (const InputError& err) {
      throw InputError("element " + std::to_string(e) + ": " + err.what());
    }
    const int ndof = 3 * npe;  // element matrices are column-major
    for (int b = 0; b < npe; ++b) {
      std::size_t at[10];  // each node's rank among node b's neighbours
      for (int a = 0; a < npe; ++a) at[a] = g.rank(en[a], en[b]);
      for (int c = 0; c < 3; ++c) {
        const int col = 3 * b + c;
        const std::size_t k0 = g.column_start(9, en[b], c), m0 = g.column_start(3, en[b], c);
        for (int a = 0; a < npe; ++a) {
          for (int r = 0; r < 3; ++r) kv[k0 + 3 * at[a] + r] += Kp[col * ndof + 3 * a + r];
          mv[m0 + at[a]] += Mp[col * ndof + 3 * a + c];
        }
      }
    }
    if (progress && *progress && (e - lo) % 4096 == 0)
      (*progress)(double(e - lo) / double(hi - lo));
  }
}

// HRZ lumping: keep the diagonal, scaled so that each direction keeps the total mass (row sums
// would give P2 corners negative mass).
void hrz_lump(SparseMatrix& M) {
  double total = 0, diag = 0;
  for (int col = 0; col < M.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(M, col); it; ++it) {
      total += it.value();
      if (it.row() == col) diag += it.value();
    }
  const double s = total / diag;
  for (int col = 0; col < M.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(M, col); it; ++it)
      it.valueRef() = it.row() == col ? it.value() * s : 0.0;
  M.prune([](Eigen::Index row, Eigen::Index col, double) { return row == col; });
}

}  // namespace

FemMatrices assemble(const FemMesh& mesh, const Material& mat, MassKind mass_kind, int threads,
                     const std::function<void(double)>& progress) {
  mat.validate();
  const std::size_t ne = mesh.element_count();
  if (ne == 0) throw InputError("the volume mesh has no elements");
  const NodeGraph g(mesh);
  const std::size_t nnz = 9 * g.nbr.size();
  if (nnz > std::size_t(std::numeric_limits<int>::max()))
    throw InputError("mesh too large: " + std::to_string(nnz) + " matrix entries");

  // Each worker adds its share of the elements into its own copy of the values.
  const int nt = std::max(1, threads > 0 ? threads : int(std::thread::hardware_concurrency()));
  std::vector<std::vector<double>> kv(nt), mv(nt);
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](int t) {
    try {
      for (auto* v : {&kv[t], &mv[t]}) {
        const std::size_t entries = v == &kv[t] ? nnz : nnz / 3;
        v->reserve(entries);
        advise_huge_pages(v->data(), entries * sizeof(double));
        v->assign(entries, 0.0);
      }
      scatter_elements(mesh, g, mat, ne * t / nt, ne * (t + 1) / nt, kv[t], mv[t],
                       t == 0 ? &progress : nullptr);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < nt; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);

  FemMatrices out;
  g.pattern(out.K, 9);
  g.pattern(out.M, 3);
  auto sum_workers = [&](const std::vector<std::vector<double>>& parts, SparseMatrix& A) {
    double* v = A.valuePtr();
    for (std::size_t k = 0; k < std::size_t(A.nonZeros()); ++k) {
      double sum = 0;
      for (int t = 0; t < nt; ++t) sum += parts[t][k];
      v[k] = sum;
    }
  };
  sum_workers(kv, out.K);
  sum_workers(mv, out.M);
  if (mass_kind == MassKind::Lumped) hrz_lump(out.M);
  if (progress) progress(1.0);
  return out;
}

Eigen::MatrixXd rigid_body_modes(const std::vector<Vec3>& nodes) {
  const std::size_t n = nodes.size();
  Vec3 c{0, 0, 0};
  for (const Vec3& p : nodes)
    for (int k = 0; k < 3; ++k) c[k] += p[k] / double(n);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(3 * n, 6);
  for (std::size_t v = 0; v < n; ++v) {
    const double x = nodes[v][0] - c[0], y = nodes[v][1] - c[1], z = nodes[v][2] - c[2];
    for (int k = 0; k < 3; ++k) R(3 * v + k, k) = 1;
    // omega x r for omega = e_x, e_y, e_z
    R(3 * v + 1, 3) = -z, R(3 * v + 2, 3) = y;
    R(3 * v + 0, 4) = z, R(3 * v + 2, 4) = -x;
    R(3 * v + 0, 5) = -y, R(3 * v + 1, 5) = x;
  }
  return R;
}

}  // namespace chladni::precompute
