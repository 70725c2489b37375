#include "chladni/precompute/mode_error.hpp"

#include <algorithm>
#include <array>
#include <thread>

#include <Eigen/QR>

#include "../parallel.hpp"
#include "chladni/core/error.hpp"
#include "fem_element.hpp"

namespace chladni::precompute {
namespace {

using Strain = std::array<double, 6>;
using Coefficients = Eigen::Matrix<double, 10, 6>;
constexpr double kSafety = 1.0;  // xx yy zz yz xz xy (tensor components)

// The element's geometry, shared by every mode.
struct ElementGeometry {
  Eigen::Matrix<double, 4, 3> g;  // barycentric gradients
  double volume = 0;
};

Strain symmetric_part(const Eigen::Matrix3d& H) {
  return {H(0, 0),
          H(1, 1),
          H(2, 2),
          0.5 * (H(1, 2) + H(2, 1)),
          0.5 * (H(0, 2) + H(2, 0)),
          0.5 * (H(0, 1) + H(1, 0))};
}

// The element's strain at its corners (P2: the strain is linear, so its values at the edge nodes
// are the means of the corners'; P1: constant).
std::array<Strain, 4> corner_strains(const FemMesh& mesh, std::size_t e, const ElementGeometry& eg,
                                     const double* u) {
  const int npe = mesh.nodes_per_element();
  const uint32_t* nodes = &mesh.elements[e * npe];
  auto disp = [&](int a) {
    const double* p = u + 3 * std::size_t(nodes[a]);
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  std::array<Strain, 4> out;
  if (mesh.order == 1) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (int a = 0; a < 4; ++a) H += disp(a) * eg.g.row(a);
    out.fill(symmetric_part(H));
    return out;
  }
  Eigen::Vector3d ua[10];
  for (int a = 0; a < 10; ++a) ua[a] = disp(a);
  for (int c = 0; c < 4; ++c) {
    // Gradients of the P2 shape functions at corner c: N_a = L_a (2 L_a - 1) gives (4 L_a - 1)
    // g_a; N_ij = 4 L_i L_j gives 4 (L_i g_j + L_j g_i).
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (int a = 0; a < 4; ++a) H += ua[a] * ((a == c ? 3.0 : -1.0) * eg.g.row(a));
    for (int k = 0; k < 6; ++k) {
      const int i = detail::kEdges[k][0], j = detail::kEdges[k][1];
      if (i == c) H += ua[4 + k] * (4.0 * eg.g.row(j));
      if (j == c) H += ua[4 + k] * (4.0 * eg.g.row(i));
    }
    out[c] = symmetric_part(H);
  }
  return out;
}

// Superconvergent patch recovery (Zienkiewicz & Zhu 1992): per corner vertex, a least-squares
// polynomial (quadratic for P2, linear for P1) through the strains of the vertex's elements at
// their Gauss points (P2) or centroids (P1), where they are most accurate. A corner node takes
// its polynomial's value; a mid-edge node the mean of its two ends' polynomials there. (Plain
// nodal averaging underestimates P2 errors by up to 2.5 times: the element strains are least
// accurate at the nodes.)
//
// The fit is linear in the element strains and its geometry is the same for every mode, so the
// map from each patch element's corner strains to the vertex's coefficients (10 x 4) and the
// polynomial values at each mid-edge node are computed once; a mode then costs small products.
class PatchRecovery {
 public:
  PatchRecovery(const FemMesh& mesh, const std::vector<ElementGeometry>& geo)
      : mesh_(mesh), npe_(mesh.nodes_per_element()) {
    const std::size_t ne = geo.size();
    std::vector<uint32_t> count(mesh.nodes.size() + 1, 0);
    for (std::size_t e = 0; e < ne; ++e)
      for (int c = 0; c < 4; ++c) ++count[mesh.elements[e * npe_ + c] + 1];
    for (std::size_t n = 0; n < mesh.nodes.size(); ++n) count[n + 1] += count[n];
    offset_ = count;
    patch_.resize(offset_.back());
    for (std::size_t e = 0; e < ne; ++e)
      for (int c = 0; c < 4; ++c) patch_[count[mesh.elements[e * npe_ + c]]++] = uint32_t(e);
    fit_.resize(mesh.nodes.size());
    map_.resize(patch_.size());
    for (std::size_t v = 0; v < mesh.nodes.size(); ++v)
      if (offset_[v + 1] > offset_[v]) make_fit(v);
    if (npe_ == 10) make_edge_nodes();
  }

  // Corner strains of every element, then each corner's fit, then the nodal values.
  void recover(const double* u, const std::vector<ElementGeometry>& geo,
               std::vector<std::array<Strain, 4>>& corner, std::vector<Coefficients>& coef,
               std::vector<Strain>& recovered) const {
    using CornerMatrix = Eigen::Matrix<double, 4, 6, Eigen::RowMajor>;
    for (std::size_t e = 0; e < geo.size(); ++e) corner[e] = corner_strains(mesh_, e, geo[e], u);
    for (std::size_t v = 0; v < fit_.size(); ++v) {
      if (offset_[v + 1] == offset_[v]) continue;
      Coefficients c = Coefficients::Zero();
      for (uint32_t i = offset_[v]; i < offset_[v + 1]; ++i)
        c.noalias() += map_[i] * Eigen::Map<const CornerMatrix>(corner[patch_[i]][0].data());
      coef[v] = c;
      for (int k = 0; k < 6; ++k) recovered[v][k] = c(0, k);
    }
    for (const EdgeNode& m : edge_nodes_) {
      const Eigen::Matrix<double, 1, 6> val =
          0.5 * (m.phi_i.transpose() * coef[m.i] + m.phi_j.transpose() * coef[m.j]);
      for (int k = 0; k < 6; ++k) recovered[m.node][k] = val(k);
    }
  }

 private:
  struct Fit {
    Vec3 centre{};
    double scale = 1;
    int terms = 1;  // 10: quadratic, 4: linear, 1: constant
  };
  struct EdgeNode {
    uint32_t node = 0, i = 0, j = 0;            // the mid-edge node and its edge's ends
    Eigen::Matrix<double, 10, 1> phi_i, phi_j;  // the ends' polynomial bases at the node
  };

  template <class Fn>
  void for_each_sample(uint32_t e, Fn&& fn) const {
    Vec3 x[4];
    for (int c = 0; c < 4; ++c) x[c] = mesh_.nodes[mesh_.elements[std::size_t(e) * npe_ + c]];
    auto at = [&](const std::array<double, 4>& L) {
      Vec3 p{0, 0, 0};
      for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 3; ++k) p[k] += L[c] * x[c][k];
      fn(L, p);
    };
    if (npe_ == 4) return at({0.25, 0.25, 0.25, 0.25});
    constexpr double a = 0.5854101966249685, b = 0.1381966011250105;  // degree-2 Gauss points
    for (int q = 0; q < 4; ++q) {
      std::array<double, 4> L{b, b, b, b};
      L[q] = a;
      at(L);
    }
  }

  Eigen::Matrix<double, 10, 1> basis(std::size_t v, const Vec3& x) const {
    const Fit& f = fit_[v];
    const double X = (x[0] - f.centre[0]) / f.scale, Y = (x[1] - f.centre[1]) / f.scale,
                 Z = (x[2] - f.centre[2]) / f.scale;
    Eigen::Matrix<double, 10, 1> phi = Eigen::Matrix<double, 10, 1>::Zero();
    phi(0) = 1;
    if (f.terms >= 4) phi(1) = X, phi(2) = Y, phi(3) = Z;
    if (f.terms >= 10)
      phi(4) = X * X, phi(5) = Y * Y, phi(6) = Z * Z, phi(7) = X * Y, phi(8) = Y * Z,
      phi(9) = Z * X;
    return phi;
  }

  // The vertex's polynomial, then map_: (normal matrix)^+ sum over the element's samples of
  // phi(x_q) L_q^T, which takes the element's corner strains (4 x 6) to coefficients (10 x 6).
  void make_fit(std::size_t v) {
    Fit& f = fit_[v];
    f.centre = mesh_.nodes[v];
    double reach = 0;
    for (uint32_t i = offset_[v]; i < offset_[v + 1]; ++i)
      for (int c = 0; c < 4; ++c) {
        const Vec3 d =
            sub(mesh_.nodes[mesh_.elements[std::size_t(patch_[i]) * npe_ + c]], f.centre);
        reach = std::max(reach, std::sqrt(dot(d, d)));
      }
    const std::size_t samples = (offset_[v + 1] - offset_[v]) * (npe_ == 10 ? 4 : 1);
    f.scale = reach > 0 ? reach : 1;
    // The richest polynomial the samples determine: a flat patch (a thin wall's surface, four
    // coplanar centroids) leaves higher terms undetermined, and a rank-deficient fit would not
    // reproduce even a constant at the vertex.
    Eigen::Matrix<double, 10, 10> inverse = Eigen::Matrix<double, 10, 10>::Zero();
    for (int terms : {npe_ == 10 ? 10 : 4, 4, 1}) {
      if (samples < std::size_t(terms == 10 ? 20 : terms)) continue;  // quadratic: 2 per term
      f.terms = terms;
      Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(terms, terms);
      for (uint32_t i = offset_[v]; i < offset_[v + 1]; ++i)
        for_each_sample(patch_[i], [&](const std::array<double, 4>&, const Vec3& x) {
          const Eigen::Matrix<double, 10, 1> phi = basis(v, x);
          normal += phi.head(terms) * phi.head(terms).transpose();
        });
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(normal);
      cod.setThreshold(1e-9);
      if (cod.rank() < terms) continue;
      inverse.setZero();
      inverse.topLeftCorner(terms, terms) = cod.pseudoInverse();
      break;
    }
    for (uint32_t i = offset_[v]; i < offset_[v + 1]; ++i) {
      Eigen::Matrix<double, 10, 4> sum = Eigen::Matrix<double, 10, 4>::Zero();
      for_each_sample(patch_[i], [&](const std::array<double, 4>& L, const Vec3& x) {
        sum += basis(v, x) * Eigen::Map<const Eigen::Matrix<double, 1, 4>>(L.data());
      });
      map_[i] = inverse * sum;
    }
  }

  void make_edge_nodes() {
    std::vector<bool> seen(mesh_.nodes.size(), false);
    for (std::size_t e = 0; e < mesh_.element_count(); ++e)
      for (int a = 4; a < 10; ++a) {
        EdgeNode m;
        m.node = mesh_.elements[e * npe_ + a];
        if (seen[m.node]) continue;
        seen[m.node] = true;
        m.i = mesh_.elements[e * npe_ + detail::kEdges[a - 4][0]];
        m.j = mesh_.elements[e * npe_ + detail::kEdges[a - 4][1]];
        m.phi_i = basis(m.i, mesh_.nodes[m.node]);
        m.phi_j = basis(m.j, mesh_.nodes[m.node]);
        edge_nodes_.push_back(m);
      }
  }

  const FemMesh& mesh_;
  int npe_;
  std::vector<uint32_t> offset_, patch_;           // CSR: the elements at each node (as a corner)
  std::vector<Eigen::Matrix<double, 10, 4>> map_;  // per patch_ entry
  std::vector<Fit> fit_;
  std::vector<EdgeNode> edge_nodes_;
};

// integral over the element of (eps* - eps_h) : C : (eps* - eps_h), exactly: the difference is a
// P2 (P1) field, so the integral is the scalar mass matrix applied to its nodal values.
double element_error(const FemMesh& mesh, std::size_t e, const ElementGeometry& eg,
                     const std::array<Strain, 4>& eps, const std::vector<Strain>& recovered,
                     double lambda, double mu) {
  const int npe = mesh.nodes_per_element();
  const uint32_t* nodes = &mesh.elements[e * npe];
  Eigen::Matrix<double, 10, 7> D;  // per node: the six strain differences and the trace
  for (int a = 0; a < npe; ++a) {
    for (int c = 0; c < 6; ++c) {
      const double h =
          a < 4 ? eps[a][c]
                : 0.5 * (eps[detail::kEdges[a - 4][0]][c] + eps[detail::kEdges[a - 4][1]][c]);
      D(a, c) = recovered[nodes[a]][c] - h;
    }
    D(a, 6) = D(a, 0) + D(a, 1) + D(a, 2);
  }
  Eigen::Matrix<double, 10, 7> W;
  if (npe == 10) {
    W = detail::p2_unit_mass() * D;
  } else {
    // integral L_a L_b = V (1 + delta_ab) / 20
    const Eigen::Matrix<double, 1, 7> sum = D.topRows<4>().colwise().sum();
    W.topRows<4>() = D.topRows<4>() / 20.0;
    W.topRows<4>().rowwise() += sum / 20.0;
  }
  double normal = 0, shear = 0, trace = 0;
  for (int a = 0; a < npe; ++a) {
    for (int c = 0; c < 3; ++c) normal += D(a, c) * W(a, c);
    for (int c = 3; c < 6; ++c) shear += D(a, c) * W(a, c);
    trace += D(a, 6) * W(a, 6);
  }
  // eps : C : eps = lambda (tr eps)^2 + 2 mu eps : eps, with each shear component counted twice.
  return eg.volume * (lambda * trace + 2 * mu * (normal + 2 * shear));
}

}  // namespace

ModeErrors estimate_mode_errors(const FemMesh& mesh, const Material& material,
                                const std::vector<double>& omega2, const Eigen::MatrixXd& shapes,
                                int threads) {
  const std::size_t ne = mesh.element_count(), nn = mesh.nodes.size();
  const std::size_t nm = omega2.size();
  if (shapes.rows() != Eigen::Index(mesh.dofs()) || shapes.cols() != Eigen::Index(nm))
    throw InternalError("estimate_mode_errors: the modes do not belong to this mesh");
  const int npe = mesh.nodes_per_element();
  std::vector<ElementGeometry> geo(ne);
  for (std::size_t e = 0; e < ne; ++e) {
    Vec3 x[4];
    for (int c = 0; c < 4; ++c) x[c] = mesh.nodes[mesh.elements[e * npe + c]];
    geo[e].volume = detail::barycentric_gradients(x, geo[e].g);
  }
  const PatchRecovery recovery(mesh, geo);

  ModeErrors out;
  out.relative.assign(nm, 0.0);
  out.element.assign(ne, 0.0);
  const double lambda = material.lame_lambda(), mu = material.lame_mu();
  const std::size_t hw = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t nt =
      std::max<std::size_t>(1, std::min(threads > 0 ? std::size_t(threads) : hw, nm));
  std::vector<std::vector<double>> share(nt, std::vector<double>(ne, 0.0));

  // One worker per share, each taking every nt-th mode.
  parallel_for(nt, int(nt), [&](std::size_t first, std::size_t last) {
    for (std::size_t t = first; t < last; ++t) {
      std::vector<Strain> recovered(nn);
      std::vector<std::array<Strain, 4>> corner(ne);
      std::vector<Coefficients> coef(nn);
      for (std::size_t m = t; m < nm; m += nt) {
        const double* u = shapes.col(Eigen::Index(m)).data();
        recovery.recover(u, geo, corner, coef, recovered);
        // Relative to 2 lambda_h = 2 u^T K u: the frequency's error, not the eigenvalue's.
        const double scale = omega2[m] > 0 ? 0.5 / omega2[m] : 0.0;
        double total = 0;
        for (std::size_t e = 0; e < ne; ++e) {
          const double eta =
              scale * element_error(mesh, e, geo[e], corner[e], recovered, lambda, mu);
          total += eta;
          share[t][e] = std::max(share[t][e], eta);
        }
        out.relative[m] = total;
      }
    }
  });
  for (const auto& s : share)
    for (std::size_t e = 0; e < ne; ++e) out.element[e] = std::max(out.element[e], s[e]);
  return out;
}

}  // namespace chladni::precompute
