#include "chladni/runtime/paper/paper_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "chladni/core/error.hpp"

namespace chladni::runtime {
namespace {

Vec3 unit_or(const Vec3& a, const Vec3& fallback) {
  const double n = norm(a);
  return n > 0 ? scale(a, 1.0 / n) : fallback;
}

}  // namespace

PaperTopology PaperTopology::build(std::uint32_t vertex_count,
                                   std::vector<std::array<std::uint32_t, 3>> triangles) {
  PaperTopology t;
  t.vertex_count = vertex_count;
  t.triangles = std::move(triangles);
  const auto nf = static_cast<std::uint32_t>(t.triangles.size());
  // Undirected edges keyed by (min, max).
  std::unordered_map<std::uint64_t, std::uint32_t> index;
  index.reserve(std::size_t(nf) * 2);
  t.face_edges.resize(nf);
  for (std::uint32_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t.triangles[f][k], b = t.triangles[f][(k + 1) % 3];
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      auto [it, inserted] = index.emplace(key, std::uint32_t(t.edges.size()));
      if (inserted) {
        t.edges.push_back({a, b});
        t.edge_faces.push_back({std::int32_t(f), -1});
      } else {
        auto& ef = t.edge_faces[it->second];
        if (ef[1] >= 0)
          throw InputError("paper mesh: edge (" + std::to_string(a) + ", " + std::to_string(b) +
                           ") is shared by more than two triangles (non-manifold)");
        ef[1] = std::int32_t(f);
      }
      t.face_edges[f][k] = it->second;
    }
  }
  // Orient faces consistently by a flood over each connected piece: a neighbour across an
  // edge must walk it the other way.
  std::vector<std::int8_t> state(nf, 0);  // 0 unvisited, 1 kept, -1 flipped
  std::vector<std::uint32_t> stack;
  auto walks = [&](std::uint32_t f, std::uint32_t a, std::uint32_t b) {
    const auto& tri = t.triangles[f];
    for (int k = 0; k < 3; ++k)
      if (tri[k] == a && tri[(k + 1) % 3] == b) return true;
    return false;
  };
  for (std::uint32_t seed = 0; seed < nf; ++seed) {
    if (state[seed]) continue;
    state[seed] = 1;
    stack.push_back(seed);
    while (!stack.empty()) {
      const std::uint32_t f = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t e = t.face_edges[f][k];
        const auto& ef = t.edge_faces[e];
        if (ef[1] < 0) continue;
        const auto g = std::uint32_t(ef[0] == std::int32_t(f) ? ef[1] : ef[0]);
        const std::uint32_t a = t.triangles[f][k], b = t.triangles[f][(k + 1) % 3];
        const bool consistent = !walks(g, a, b);
        if (!state[g]) {
          if (!consistent) {
            std::swap(t.triangles[g][1], t.triangles[g][2]);
            auto& fe = t.face_edges[g];  // edges follow the corners: (0,1),(1,2),(2,0)
            std::swap(fe[0], fe[2]);
            ++t.flipped_faces;
          }
          state[g] = 1;
          stack.push_back(g);
        } else if (!consistent) {
          throw InputError("paper mesh: the sheet is not orientable (edge (" + std::to_string(a) +
                           ", " + std::to_string(b) + "))");
        }
      }
    }
  }
  // Each edge records the direction its first face walks it (the dihedral's sign reference).
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    const auto f = std::uint32_t(t.edge_faces[e][0]);
    auto& ab = t.edges[e];
    if (!walks(f, ab[0], ab[1])) std::swap(ab[0], ab[1]);
  }
  t.vertex_edge_start.assign(std::size_t(vertex_count) + 1, 0);
  for (const auto& ab : t.edges) ++t.vertex_edge_start[ab[0] + 1], ++t.vertex_edge_start[ab[1] + 1];
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    t.vertex_edge_start[v + 1] += t.vertex_edge_start[v];
  t.vertex_edges.resize(t.vertex_edge_start.back());
  std::vector<std::uint32_t> fill(t.vertex_edge_start.begin(), t.vertex_edge_start.end() - 1);
  for (std::uint32_t e = 0; e < t.edges.size(); ++e) {
    t.vertex_edges[fill[t.edges[e][0]]++] = e;
    t.vertex_edges[fill[t.edges[e][1]]++] = e;
  }
  return t;
}

void PaperGeometry::update(const PaperTopology& topo, std::span<const float> xyz) {
  const std::size_t nv = topo.vertex_count, nf = topo.triangles.size(), ne = topo.edges.size();
  position.resize(nv);
  face_normal.resize(nf);
  face_area.resize(nf);
  vertex_area.assign(nv, 0.0);
  dihedral.resize(ne);
  edge_length.resize(ne);
  mean_curvature.assign(nv, 0.0);
  for (std::size_t v = 0; v < nv; ++v)
    position[v] = {double(xyz[3 * v]), double(xyz[3 * v + 1]), double(xyz[3 * v + 2])};
  for (std::size_t f = 0; f < nf; ++f) {
    const auto& t = topo.triangles[f];
    const Vec3 n = triangle_normal(position[t[0]], position[t[1]], position[t[2]]);
    const double twice = norm(n);
    face_area[f] = 0.5 * twice;
    face_normal[f] = unit_or(n, Vec3{0, 0, 1});
    for (std::uint32_t v : t) vertex_area[v] += face_area[f] / 3.0;
  }
  for (std::size_t e = 0; e < ne; ++e) {
    const auto [a, b] = topo.edges[e];
    const Vec3 d = sub(position[b], position[a]);
    const double len = norm(d);
    edge_length[e] = len;
    const auto& ef = topo.edge_faces[e];
    if (ef[1] < 0 || !(len > 0)) {
      dihedral[e] = 0;
      continue;
    }
    const Vec3& n0 = face_normal[std::size_t(ef[0])];
    const Vec3& n1 = face_normal[std::size_t(ef[1])];
    // Signed angle from n0 to n1 about the edge as face 0 walks it.
    const double theta = std::atan2(dot(cross(n0, n1), d) / len, dot(n0, n1));
    dihedral[e] = theta;
    const double c = theta * len;
    mean_curvature[a] += c;
    mean_curvature[b] += c;
  }
  for (std::size_t v = 0; v < nv; ++v)
    mean_curvature[v] = vertex_area[v] > 0 ? mean_curvature[v] / (4.0 * vertex_area[v]) : 0.0;
}

void PaperGeometry::update_shape(const PaperTopology& topo) {
  const std::size_t nf = topo.triangles.size();
  face_curvature.resize(nf);
  ruling.resize(nf);
  vertex_normal.assign(position.size(), Vec3{0, 0, 0});
  for (std::size_t f = 0; f < nf; ++f)
    for (std::uint32_t v : topo.triangles[f])
      vertex_normal[v] = add(vertex_normal[v], scale(face_normal[f], face_area[f]));
  for (auto& n : vertex_normal) n = unit_or(n, Vec3{0, 0, 1});
  // Face shape operator S (dn = S dx in the face's tangent plane) fitted to the vertex normals
  // along the three edges by least squares (after Rusinkiewicz 2004); its eigenvector of the
  // smaller |eigenvalue| is the ruling (zero normal curvature on a developable sheet).
  for (std::size_t f = 0; f < nf; ++f) {
    const auto& t = topo.triangles[f];
    const Vec3& n = face_normal[f];
    const Vec3 u = unit_or(sub(position[t[1]], position[t[0]]), Vec3{1, 0, 0});
    const Vec3 w = cross(n, u);
    double m00 = 0, m01 = 0, m02 = 0, m11 = 0, m12 = 0, m22 = 0, r0 = 0, r1 = 0, r2 = 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = t[k], q = t[(k + 1) % 3];
      const Vec3 dx = sub(position[q], position[p]);
      const Vec3 dn = sub(vertex_normal[q], vertex_normal[p]);
      const double x = dot(dx, u), y = dot(dx, w), nu = dot(dn, u), nw = dot(dn, w);
      // Unknowns (s00, s01, s11): nu = s00 x + s01 y, nw = s01 x + s11 y.
      m00 += x * x, m01 += x * y, m11 += x * x + y * y, m12 += x * y, m22 += y * y;
      r0 += x * nu, r1 += y * nu + x * nw, r2 += y * nw;
    }
    m02 = 0;
    // Solve the symmetric 3x3 [m00 m01 0; m01 m11 m12; 0 m12 m22] s = r by Cramer's rule.
    const double det = m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02);
    double s00 = 0, s01 = 0, s11 = 0;
    if (std::abs(det) > 1e-300) {
      s00 = (r0 * (m11 * m22 - m12 * m12) - m01 * (r1 * m22 - m12 * r2)) / det;
      s01 = (m00 * (r1 * m22 - m12 * r2) - r0 * (m01 * m22)) / det;
      s11 = (m00 * (m11 * r2 - r1 * m12) - m01 * (m01 * r2) + r0 * (m01 * m12)) / det;
    }
    const double tr = 0.5 * (s00 + s11), diff = 0.5 * (s00 - s11);
    const double rad = std::sqrt(diff * diff + s01 * s01);
    const double k1 = tr + rad, k2 = tr - rad;  // eigenvalues
    face_curvature[f] = std::max(std::abs(k1), std::abs(k2));
    const double small = std::abs(k1) < std::abs(k2) ? k1 : k2;
    // Eigenvector of `small`: (s01, small - s00) or (small - s11, s01), whichever is longer
    // (the other may be pure round-off, e.g. on a cylinder face aligned with the axis).
    double ex = s01, ey = small - s00;
    const double fx = small - s11, fy = s01;
    if (fx * fx + fy * fy > ex * ex + ey * ey) ex = fx, ey = fy;
    if (!(ex * ex + ey * ey > 0)) ex = 1, ey = 0;  // umbilic: any direction
    ruling[f] = unit_or(add(scale(u, ex), scale(w, ey)), u);
  }
}

}  // namespace chladni::runtime
