// TetGen wrapper: the only unit that includes tetgen.h (AGPL; precompute only, DESIGN.md).
#include <tetgen.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <numbers>
#include <optional>
#include <string>

#include "../surface/split_long_edges.hpp"
#include "../surface/surface_pieces.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/tet_mesh.hpp"
#include "tetgen_child.hpp"

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

double enclosed_volume(const SurfaceMesh& s) {
  double v = 0;
  for (const auto& t : s.triangles)
    v += dot(s.vertices[t[0]], cross(s.vertices[t[1]], s.vertices[t[2]])) / 6;
  return std::abs(v);
}

// Zero-based input points; tetgenio frees them.
void set_points(tetgenio& in, const std::vector<Vec3>& points) {
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(points.size());
  in.pointlist = new REAL[3 * points.size()];
  for (std::size_t v = 0; v < points.size(); ++v)
    for (int k = 0; k < 3; ++k) in.pointlist[3 * v + k] = points[v][k];
}

// TetGen fills every region the facets enclose unless told which are holes: one point inside
// each cavity of a hollow body.
void set_cavities(tetgenio& in, const SurfaceMesh& s) {
  const SurfacePieces pieces = surface_pieces(s);
  std::vector<Vec3> holes;
  for (std::size_t p = 0; p < pieces.count(); ++p)
    if (pieces.is_cavity(p)) holes.push_back(point_in_cavity(s, pieces, p));
  if (holes.empty()) return;
  in.numberofholes = static_cast<int>(holes.size());
  in.holelist = new REAL[3 * holes.size()];
  for (std::size_t h = 0; h < holes.size(); ++h)
    for (int k = 0; k < 3; ++k) in.holelist[3 * h + k] = holes[h][k];
}

// TetGen's points and tetrahedra, each tetrahedron positively oriented.
TetMesh mesh_from_output(const tetgenio& out) {
  TetMesh m;
  m.nodes.resize(static_cast<std::size_t>(out.numberofpoints));
  for (std::size_t v = 0; v < m.nodes.size(); ++v)
    m.nodes[v] = {out.pointlist[3 * v], out.pointlist[3 * v + 1], out.pointlist[3 * v + 2]};
  m.tets.resize(static_cast<std::size_t>(out.numberoftetrahedra));
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    auto& tet = m.tets[t];
    for (int k = 0; k < 4; ++k) tet[k] = static_cast<uint32_t>(out.tetrahedronlist[4 * t + k]);
    if (tet_volume(m, t) < 0) std::swap(tet[2], tet[3]);
  }
  return m;
}

// Renumbers `m` so its boundary's nodes come first (the input's vertices, which TetGen keeps
// first and in order, then the points it added on the surface) and takes the boundary as the
// mesh's surface.
void surface_nodes_first(TetMesh& m, std::size_t input_vertices) {
  std::vector<std::array<uint32_t, 3>> faces = boundary_faces(m);
  constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> to(m.nodes.size(), kNone);
  uint32_t next = 0;
  for (std::size_t v = 0; v < input_vertices; ++v) to[v] = next++;
  for (const auto& f : faces)
    for (uint32_t v : f)
      if (to[v] == kNone) to[v] = next++;
  const std::size_t surface = next;
  for (uint32_t& t : to)
    if (t == kNone) t = next++;
  std::vector<Vec3> nodes(m.nodes.size());
  for (std::size_t v = 0; v < nodes.size(); ++v) nodes[to[v]] = m.nodes[v];
  m.nodes = std::move(nodes);
  for (auto& t : m.tets)
    for (uint32_t& v : t) v = to[v];
  for (auto& f : faces)
    for (uint32_t& v : f) v = to[v];
  m.surface_vertices = surface;
  m.surface_triangles = std::move(faces);
}

// keep_surface: -Y, the input triangles are the mesh's boundary; else TetGen may add points on
// the surface (and split its triangles) where that is the only way to well-shaped tetrahedra.
TetMesh run_tetgen(const SurfaceMesh& s, const TetOptions& o, bool keep_surface) {
  tetgenio in, out;
  set_points(in, s.vertices);
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
  set_cavities(in, s);
  // p: piecewise linear complex; Y: no Steiner points on the surface; q: quality bounds;
  // a: volume bound; z: zero-based; Q: quiet.
  std::string sw = keep_surface ? "pzQY" : "pzQ";
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
  // With -Y TetGen keeps the input points first, in order, and adds none on the surface: the
  // input triangles are the mesh's boundary (tests check this).
  TetMesh m = mesh_from_output(out);
  m.surface_vertices = s.vertices.size();
  m.surface_triangles = s.triangles;
  if (!keep_surface) surface_nodes_first(m, s.vertices.size());
  return m;
}

// TetGen -r: refines an existing mesh under per-tetrahedron volume bounds (-a with no number
// reads them from tetrahedronvolumelist; -1 leaves a tetrahedron unbounded). Without -Y the
// boundary faces may be split, so a thin wall gets interior points near it.
TetMesh run_tetgen_refine(const TetMesh& m, const std::vector<double>& bound, const TetOptions& o) {
  tetgenio in, out;
  set_points(in, m.nodes);
  in.numberoftetrahedra = static_cast<int>(m.tets.size());
  in.numberofcorners = 4;
  in.tetrahedronlist = new int[4 * m.tets.size()];
  in.tetrahedronvolumelist = new REAL[m.tets.size()];
  for (std::size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) in.tetrahedronlist[4 * t + k] = static_cast<int>(m.tets[t][k]);
    in.tetrahedronvolumelist[t] = bound[t] > 0 ? bound[t] : -1.0;
  }
  in.numberoftrifaces = static_cast<int>(m.surface_triangles.size());
  in.trifacelist = new int[3 * m.surface_triangles.size()];
  in.trifacemarkerlist = new int[m.surface_triangles.size()];
  for (std::size_t f = 0; f < m.surface_triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      in.trifacelist[3 * f + k] = static_cast<int>(m.surface_triangles[f][k]);
    in.trifacemarkerlist[f] = 1;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "rzQaq%.3g/%.3g", o.max_radius_edge, o.min_dihedral_deg);
  std::vector<char> switches(buf, buf + std::strlen(buf) + 1);
  try {
    ::tetrahedralize(switches.data(), &in, &out);
  } catch (int code) {
    throw InputError(std::string("TetGen could not refine the mesh: ") + tetgen_reason(code) +
                     " (code " + std::to_string(code) + ")");
  }
  const std::size_t np = static_cast<std::size_t>(out.numberofpoints);
  if (out.numberoftetrahedra <= 0 || np < m.nodes.size())
    throw InputError("TetGen's refinement returned fewer points or no tetrahedra");
  TetMesh r = mesh_from_output(out);
  for (std::size_t v = 0; v < m.nodes.size(); ++v)
    if (r.nodes[v] != m.nodes[v])
      throw InputError("TetGen's refinement moved node " + std::to_string(v));
  r.surface_vertices = m.surface_vertices;
  r.surface_triangles = boundary_faces(r);
  return r;
}

// Without -Y TetGen's quality refinement can loop on some fine surfaces (a scanned figure ran
// 6 minutes without end), so it runs under a CPU limit.
constexpr double kSurfacePointsCpuSeconds = 60;

// The mesh with points added on the surface: nullopt where TetGen failed or ran past its limit
// (the reason in `crash`).
std::optional<TetMesh> with_surface_points(const SurfaceMesh& s, const TetOptions& o,
                                           std::string& crash) {
  return tetgen_isolated([&] { return run_tetgen(s, o, false); }, crash, 0,
                         kSurfacePointsCpuSeconds);
}

// The -Y mesh `m`, or where it is flat, the mesh with points added on the surface if its worst
// angle is better.
TetMesh remesh_if_flat(const SurfaceMesh& s, const TetOptions& tries, const TetOptions& o,
                       TetMesh m) {
  const TetQuality q = tet_quality(m);
  if (!(q.min_dihedral_deg < o.flat_dihedral_deg)) return m;
  if (o.before_remesh) o.before_remesh(m);
  std::string ignored;
  std::optional<TetMesh> steiner;
  try {
    steiner = with_surface_points(s, tries, ignored);
  } catch (const InputError&) {
    // the -Y mesh stands
  }
  if (!steiner || !(tet_quality(*steiner).min_dihedral_deg > q.min_dihedral_deg)) return m;
  return std::move(*steiner);
}

}  // namespace

std::vector<std::array<uint32_t, 3>> boundary_faces(const TetMesh& m) {
  std::map<std::array<uint32_t, 3>, std::pair<int, std::array<uint32_t, 4>>> faces;
  for (const auto& t : m.tets)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<uint32_t, 4> f{t[(skip + 1) % 4], t[(skip + 2) % 4], t[(skip + 3) % 4], t[skip]};
      std::array<uint32_t, 3> key{f[0], f[1], f[2]};
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      e.first++, e.second = f;
    }
  std::vector<std::array<uint32_t, 3>> out;
  for (const auto& [key, e] : faces) {
    if (e.first != 1) continue;
    const auto& f = e.second;
    const Vec3 &a = m.nodes[f[0]], &b = m.nodes[f[1]], &c = m.nodes[f[2]], &d = m.nodes[f[3]];
    if (dot(cross(sub(b, a), sub(c, a)), sub(d, a)) > 0)
      out.push_back({f[0], f[2], f[1]});
    else
      out.push_back({f[0], f[1], f[2]});
  }
  return out;
}

TetMesh tetrahedralize(const SurfaceMesh& input, const TetOptions& o) {
  // A regular tetrahedron of volume V has edges (6 sqrt(2) V)^(1/3).
  const double volume = enclosed_volume(input);
  if (o.max_volume > 0 && volume / o.max_volume > double(kMaxTetrahedra)) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "tetrahedra of at most %.3g m^3 would fill this %.3g m^3 solid "
                  "with about %.3g of them",
                  o.max_volume, volume, volume / o.max_volume);
    throw InputError(std::string(buf) +
                     ", more than the 20 million this tool meshes: raise "
                     "--max-tet-volume or lower --max-freq/--max-modes");
  }
  // With -Y TetGen may not split surface triangles, and it then skips every interior point that
  // would encroach on a large one: a cube of 12 triangles stays 12 tetrahedra whatever the
  // volume bound. So long surface edges are split first.
  const SurfaceMesh s =
      o.max_volume > 0
          ? split_long_edges(input, 1.5 * std::cbrt(6 * std::numbers::sqrt2 * o.max_volume))
          : input;
  // TetGen 1.5 fails internal assertions (abort) on some surfaces at some volume bounds; in a
  // child process that is an error to report, and a slightly smaller bound usually avoids it.
  TetOptions tries = o;
  if (!o.keep_surface) {  // no retries: a minute past its CPU limit would only repeat
    std::string crash;
    if (auto m = with_surface_points(s, o, crash)) return std::move(*m);
    throw InputError("TetGen failed to mesh with points on the surface (" + crash + ")");
  }
  for (int attempt = 0;; ++attempt) {
    std::string crash;
    if (auto m = tetgen_isolated([&] { return run_tetgen(s, tries, true); }, crash))
      return remesh_if_flat(s, tries, o, std::move(*m));
    if (attempt == 2 || tries.max_volume <= 0)
      throw InputError("TetGen failed on this surface (" + crash +
                       "); try another --max-tet-volume or --tolerance, or --repair");
    tries.max_volume *= 0.9;
  }
}

double tetrahedra_asked(const TetMesh& mesh, const std::vector<double>& max_volume) {
  double asked = 0;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e)
    asked += max_volume[e] > 0 ? std::max(1.0, std::abs(tet_volume(mesh, e)) / max_volume[e]) : 1.0;
  return asked;
}

TetMesh refine_tets(const TetMesh& mesh, const std::vector<double>& max_volume,
                    const TetOptions& o) {
  if (max_volume.size() != mesh.tets.size())
    throw InternalError("refine_tets: one volume bound per tetrahedron expected");
  // As for meshing: an assertion TetGen fails at some bounds is usually passed at slightly
  // smaller ones.
  std::vector<double> bounds = max_volume;
  // A refinement that runs away (coupling.obj: 17 GB in 17 minutes) fails once it far exceeds
  // what was asked: 16 KB per tetrahedron the bounds call for (TetGen takes about 4 KB while
  // refining), at least 2 GB. Bisection then takes over.
  const double allowance = std::max(2e9, 16e3 * tetrahedra_asked(mesh, bounds));
  for (int attempt = 0;; ++attempt) {
    std::string crash;
    auto job = [&] {
      if (std::getenv("CHLADNI_TEST_TETGEN_ABORT_REFINE")) std::abort();  // tests: the fallback
      return run_tetgen_refine(mesh, bounds, o);
    };
    if (auto m = tetgen_isolated(job, crash, allowance)) {
      // TetGen's refinement has left a tetrahedron of volume -0.0 (spot.obj simplified from
      // 94k triangles, refined toward 0.2 %), which assembly refuses: retried like a crash.
      std::size_t e = 0;
      while (e < m->tets.size() && tet_volume(*m, e) > 0) ++e;
      if (e == m->tets.size()) return std::move(*m);
      crash = "tetrahedron " + std::to_string(e) + " of its mesh is flat or inverted";
    }
    if (attempt == 2) throw InputError("TetGen failed refining the mesh (" + crash + ")");
    for (double& b : bounds) b *= 0.9;
  }
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
      const double deg = std::acos(std::clamp(cosang, -1.0, 1.0)) * 180 / std::numbers::pi;
      q.min_dihedral_deg = std::min(q.min_dihedral_deg, deg);
      q.max_dihedral_deg = std::max(q.max_dihedral_deg, deg);
    }
  }
  if (!m.tets.empty()) q.mean_radius_edge /= double(m.tets.size());
  return q;
}

double coarse_max_volume(const SurfaceMesh& s) {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const Vec3& v : s.vertices)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / 300.0;
}

double auto_max_volume(const Material& mat, double max_frequency, int order, const SurfaceMesh& s) {
  const double per_wavelength = order == 1 ? 12.0 : 6.0;
  const double h = mat.shear_speed() / max_frequency / per_wavelength;
  const double v_wave = h * h * h / (6 * std::sqrt(2.0));
  return std::min(v_wave, coarse_max_volume(s));
}

}  // namespace chladni::precompute
