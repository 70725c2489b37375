// TetGen wrapper: the only unit that includes tetgen.h (AGPL; precompute only, DESIGN.md).
#include <tetgen.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {
namespace {

const char* tetgen_reason(int code) {
  switch (code) {
    case 1:
      return "out of memory";
    case 2:
      return "internal error";
    case 3:
      return "the surface intersects itself";
    case 4:
      return "an input feature is smaller than TetGen's tolerance";
    case 5:
      return "two input facets are too close";
    case 10:
      return "invalid input";
    default:
      return "unknown failure";
  }
}

}  // namespace

TetMesh tetrahedralize(const SurfaceMesh& s, const TetOptions& o) {
  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(s.vertices.size());
  in.pointlist = new REAL[3 * s.vertices.size()];
  for (std::size_t v = 0; v < s.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) in.pointlist[3 * v + k] = s.vertices[v][k];
  in.numberoffacets = static_cast<int>(s.triangles.size());
  in.facetlist = new tetgenio::facet[s.triangles.size()];
  in.facetmarkerlist = nullptr;
  for (std::size_t f = 0; f < s.triangles.size(); ++f) {
    tetgenio::facet& fc = in.facetlist[f];
    tetgenio::init(&fc);
    fc.numberofpolygons = 1;
    fc.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&fc.polygonlist[0]);
    fc.polygonlist[0].numberofvertices = 3;
    fc.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k)
      fc.polygonlist[0].vertexlist[k] = static_cast<int>(s.triangles[f][k]);
  }
  // p: piecewise linear complex; Y: no Steiner points on the surface; q: quality bounds;
  // a: volume bound; z: zero-based; Q: quiet.
  std::string sw = "pzQY";
  char buf[64];
  std::snprintf(buf, sizeof buf, "q%.3g/%.3g", o.max_radius_edge, o.min_dihedral_deg);
  sw += buf;
  if (o.max_volume > 0) {
    std::snprintf(buf, sizeof buf, "a%.9g", o.max_volume);
    sw += buf;
  }
  std::vector<char> switches(sw.begin(), sw.end());
  switches.push_back('\0');
  try {
    ::tetrahedralize(switches.data(), &in, &out);
  } catch (int code) {
    throw InputError(std::string("TetGen could not mesh the volume: ") + tetgen_reason(code) +
                     " (code " + std::to_string(code) + ")");
  }
  if (out.numberoftetrahedra <= 0)
    throw InputError("TetGen produced no tetrahedra (is the surface closed and non-degenerate?)");

  const std::size_t np = static_cast<std::size_t>(out.numberofpoints);
  for (std::size_t v = 0; v < s.vertices.size(); ++v) {
    if (v >= np || Vec3{out.pointlist[3 * v], out.pointlist[3 * v + 1], out.pointlist[3 * v + 2]} !=
                       s.vertices[v])
      throw InternalError("TetGen moved or dropped surface vertex " + std::to_string(v));
  }
  std::vector<std::array<uint32_t, 4>> tets(out.numberoftetrahedra);
  for (int t = 0; t < out.numberoftetrahedra; ++t)
    for (int k = 0; k < 4; ++k) tets[t][k] = static_cast<uint32_t>(out.tetrahedronlist[4 * t + k]);

  // Boundary faces: those of exactly one tet.
  std::map<std::array<uint32_t, 3>, std::pair<int, std::array<uint32_t, 4>>> faces;
  for (const auto& t : tets) {
    for (int k = 0; k < 4; ++k) {
      std::array<uint32_t, 3> f{t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4]};
      std::array<uint32_t, 3> key = f;
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      ++e.first;
      e.second = {f[0], f[1], f[2], t[k]};
    }
  }
  // Node order: input vertices, other boundary nodes, interior nodes.
  std::vector<uint8_t> on_boundary(np, 0);
  for (const auto& [key, e] : faces)
    if (e.first == 1)
      for (uint32_t v : key) on_boundary[v] = 1;
  std::vector<uint32_t> order(np, UINT32_MAX);
  uint32_t next = 0;
  for (std::size_t v = 0; v < s.vertices.size(); ++v) order[v] = next++;
  for (std::size_t v = s.vertices.size(); v < np; ++v)
    if (on_boundary[v]) order[v] = next++;
  const uint32_t boundary_count = next;
  for (std::size_t v = s.vertices.size(); v < np; ++v)
    if (!on_boundary[v]) order[v] = next++;

  TetMesh m;
  m.nodes.resize(np);
  for (std::size_t v = 0; v < np; ++v)
    m.nodes[order[v]] = {out.pointlist[3 * v], out.pointlist[3 * v + 1], out.pointlist[3 * v + 2]};
  m.surface_vertices = boundary_count;
  m.tets.reserve(tets.size());
  for (const auto& t0 : tets) {
    std::array<uint32_t, 4> tet{order[t0[0]], order[t0[1]], order[t0[2]], order[t0[3]]};
    const Vec3 &a = m.nodes[tet[0]], &b = m.nodes[tet[1]], &c = m.nodes[tet[2]],
               &d = m.nodes[tet[3]];
    if (dot(cross(sub(b, a), sub(c, a)), sub(d, a)) < 0) std::swap(tet[2], tet[3]);
    m.tets.push_back(tet);
  }
  for (const auto& [key, e] : faces) {
    if (e.first != 1) continue;
    std::array<uint32_t, 3> f{order[e.second[0]], order[e.second[1]], order[e.second[2]]};
    const Vec3& opposite = m.nodes[order[e.second[3]]];
    const Vec3 &a = m.nodes[f[0]], &b = m.nodes[f[1]], &c = m.nodes[f[2]];
    if (dot(cross(sub(b, a), sub(c, a)), sub(opposite, a)) > 0) std::swap(f[1], f[2]);
    m.surface_triangles.push_back(f);
  }
  return m;
}

TetQuality tet_quality(const TetMesh& m) {
  TetQuality q;
  q.min_dihedral_deg = 180;
  constexpr int edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (const auto& t : m.tets) {
    const Vec3 p[4] = {m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]};
    const Vec3 a = sub(p[1], p[0]), b = sub(p[2], p[0]), c = sub(p[3], p[0]);
    const double six_v = dot(a, cross(b, c));
    q.volume += six_v / 6;
    // Circumradius: |a^2 (b x c) + b^2 (c x a) + c^2 (a x b)| / (2 * 6V).
    Vec3 num{0, 0, 0};
    const Vec3 bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
    for (int k = 0; k < 3; ++k) num[k] = dot(a, a) * bc[k] + dot(b, b) * ca[k] + dot(c, c) * ab[k];
    const double R = std::sqrt(dot(num, num)) / (2 * std::abs(six_v));
    double lmin = INFINITY;
    for (const auto& e : edges) {
      const Vec3 d = sub(p[e[1]], p[e[0]]);
      lmin = std::min(lmin, std::sqrt(dot(d, d)));
    }
    const double re = R / lmin;
    q.max_radius_edge = std::max(q.max_radius_edge, re);
    q.mean_radius_edge += re;
    // Dihedral angle at edge (i, j): between the other two corners projected normal to the edge.
    for (const auto& e : edges) {
      int o[2], j = 0;
      for (int k = 0; k < 4; ++k)
        if (k != e[0] && k != e[1]) o[j++] = k;
      const Vec3 d = sub(p[e[1]], p[e[0]]);
      Vec3 u = sub(p[o[0]], p[e[0]]), w = sub(p[o[1]], p[e[0]]);
      const double du = dot(u, d) / dot(d, d), dw = dot(w, d) / dot(d, d);
      for (int k = 0; k < 3; ++k) u[k] -= du * d[k], w[k] -= dw * d[k];
      const double cosang = dot(u, w) / std::sqrt(dot(u, u) * dot(w, w));
      q.min_dihedral_deg = std::min(
          q.min_dihedral_deg, std::acos(std::clamp(cosang, -1.0, 1.0)) * 180 / std::numbers::pi);
    }
  }
  if (!m.tets.empty()) q.mean_radius_edge /= double(m.tets.size());
  return q;
}

double auto_max_volume(const Material& mat, double max_frequency, int order, const SurfaceMesh& s) {
  const double per_wavelength = order == 1 ? 12.0 : 6.0;
  const double h = mat.shear_speed() / max_frequency / per_wavelength;
  double v_wave = h * h * h / (6 * std::sqrt(2.0));
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const Vec3& v : s.vertices)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  const double box = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  return std::min(v_wave, box / 300.0);
}

}  // namespace chladni::precompute
