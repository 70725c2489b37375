// The repair ladder: the mildest rung that leaves a valid solid, measured against the input.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "../surface/local_thickness.hpp"
#include "../surface/surface_pieces.hpp"
#include "../union_find.hpp"
#include "repair_steps.hpp"

namespace chladni::precompute {

const char* to_string(RepairRung rung) {
  switch (rung) {
    case RepairRung::None:
      return "none";
    case RepairRung::Local:
      return "local";
    case RepairRung::SelfIntersections:
      return "self-intersections";
    case RepairRung::Wrap:
      return "wrap";
  }
  return "?";
}

double RepairReport::volume_change() const {
  return volume_input != 0 ? (volume_repaired - volume_input) / std::abs(volume_input) : 0.0;
}

namespace repair {
namespace {

// A sheet thinner than this fraction of its size is flat: it bounds no volume.
constexpr double kFlat = 1e-6;
// A wrap bounding less than this many offsets times the input's area is a slab around a sheet
// (a wrapped open sheet bounds about 2 offsets times its area; a solid of wall t, t/2 times).
constexpr double kSlab = 4;
// A wall of the wrap under this many offsets is a slab round a sheet (it measures 2 offsets);
// more than this share of its area in slabs and the wrap is not a solid's surface.
constexpr double kSlabWall = 4, kSlabShare = 0.01;
// The fraction of the offset the wrap is pulled back by: all of it would collapse the wrap's
// rounding of convex edges onto the edges.
constexpr double kPullBack = 0.9;

std::string fmt(const char* f, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c, d);
  return buf;
}

double diagonal(const SurfaceMesh& m) {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const Vec3& v : m.vertices)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  return m.vertices.empty() ? 0.0 : norm(sub(hi, lo));
}

double area(const SurfaceMesh& m) {
  double a = 0;
  for (const auto& t : m.triangles)
    a += 0.5 * norm(triangle_normal(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
  return a;
}

// Extent of the vertices along their least principal axis: 0 for a flat sheet.
double thickness_across(const SurfaceMesh& m) {
  if (m.vertices.empty()) return 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Vec3& v : m.vertices) mean += Eigen::Vector3d(v[0], v[1], v[2]);
  mean /= double(m.vertices.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3& v : m.vertices) {
    const Eigen::Vector3d d = Eigen::Vector3d(v[0], v[1], v[2]) - mean;
    cov += d * d.transpose();
  }
  const Eigen::Vector3d axis =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  double lo = INFINITY, hi = -INFINITY;
  for (const Vec3& v : m.vertices) {
    const double x = axis.dot(Eigen::Vector3d(v[0], v[1], v[2]) - mean);
    lo = std::min(lo, x), hi = std::max(hi, x);
  }
  return hi - lo;
}

// The pieces of a surface that count: all but those under `fraction` of the largest volume,
// which are removed from `m` as debris when every piece is closed (otherwise nothing is).
std::vector<std::size_t> drop_debris(SurfaceMesh& m, double fraction, bool closed, const Say& say) {
  SurfacePieces s = surface_pieces(m);
  std::vector<std::size_t> parts(s.count());
  std::iota(parts.begin(), parts.end(), 0);
  if (!closed || s.count() < 2 || !s.nested()) return parts;
  double largest = 0;
  for (std::size_t p = 0; p < s.count(); ++p) largest = std::max(largest, std::abs(s.volume[p]));
  std::vector<bool> keep(s.count(), true);
  std::size_t dropped = 0, faces = 0;
  for (std::size_t p = 0; p < s.count(); ++p)
    if (!s.is_cavity(p) && std::abs(s.volume[p]) < fraction * largest)
      keep[p] = false, ++dropped, faces += s.triangles[p];
  if (dropped) {
    m = keep_pieces(m, s, keep);
    say("removed " + std::to_string(dropped) + " pieces of debris (" + std::to_string(faces) +
        " triangles, each under " + fmt("%g", fraction) + " of the largest piece's volume)");
    s = surface_pieces(m);
  }
  parts.clear();
  for (std::size_t p = 0; p < s.count(); ++p)
    if (!s.nested() || !s.is_cavity(p)) parts.push_back(p);
  return parts;
}

// "2 separate parts that do not touch: part 1 (the piece of face 0): 1200 triangles, volume
// 0.0012 m^3, about (x, y, z) m; ..." for the pieces `parts` of `m`.
std::string parts_list(const SurfaceMesh& m, const std::vector<std::size_t>& parts,
                       const std::string& why) {
  const SurfacePieces s = surface_pieces(m);
  std::string out = std::to_string(parts.size()) + " separate parts " + why + ":";
  for (std::size_t i = 0; i < parts.size() && i < 8; ++i) {
    const std::size_t p = parts[i];
    Vec3 c{0, 0, 0};
    std::size_t n = 0;
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
      if (s.of_triangle[f] == p)
        for (uint32_t v : m.triangles[f]) c = add(c, m.vertices[v]), ++n;
    c = scale(c, 1.0 / double(std::max<std::size_t>(n, 1)));
    out += "\n    part " + std::to_string(i + 1) + " (the piece of face " +
           std::to_string(s.first_triangle[p]) + "): " + std::to_string(s.triangles[p]) +
           " triangles, volume " +
           fmt("%.4g m^3, about (%.4g, %.4g, %.4g) m", std::abs(s.volume[p]), c[0], c[1], c[2]);
  }
  if (parts.size() > 8) out += "\n    ...";
  return out + "\n  make each part a separate asset, or join them in the model";
}

// Clusters of parts closer than `gap`; true when they all form one.
bool parts_touch(const SurfaceMesh& m, const std::vector<std::size_t>& parts, double gap) {
  const SurfacePieces s = surface_pieces(m);
  std::vector<SurfaceMesh> piece(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    std::vector<bool> keep(s.count(), false);
    keep[parts[i]] = true;
    piece[i] = keep_pieces(m, s, keep);
  }
  UnionFind clusters(parts.size());
  for (std::size_t i = 0; i < parts.size(); ++i)
    for (std::size_t j = i + 1; j < parts.size(); ++j)
      if (gap_between(piece[i], piece[j]) <= gap) clusters.unite(i, j);
  for (std::size_t i = 1; i < parts.size(); ++i)
    if (clusters.find(i) != clusters.find(0)) return false;
  return true;
}

// Rung 3's alpha and offset. Alpha is the thinnest wall, within a hundredth and a fiftieth of
// the object's size: gaps and holes narrower than the walls close, a ball that small rounds
// concave edges by less than it, and facets that size sag little on curved walls. The offset is
// a fiftieth of the wall, within 1/3000 and 1/500 of the size: small enough that pulling the
// wrap back onto the input (pull_back) leaves walls their thickness, large enough that the wrap
// needs no more triangles than the shape does.
// Values given on the command line are held to ranges where the wrap's triangles (about the
// area over alpha squared, more as the offset shrinks against alpha) stay within memory.
bool wrap_parameters(const SurfaceMesh& surface, double diag, const RepairOptions& o,
                     RepairReport& r) {
  r.thinnest = std::min(thinnest_wall(surface), diag);
  const double wall = r.thinnest > 0 ? r.thinnest : diag / 20;  // an open sheet: no wall
  r.offset = o.wrap_offset > 0 ? o.wrap_offset : std::clamp(wall / 50, diag / 3000, diag / 500);
  r.alpha = o.wrap_alpha > 0 ? o.wrap_alpha : std::clamp(wall, diag / 100, diag / 50);
  auto outside = [&](const char* name, double v, double lo, double hi) {
    r.refusal = std::string(name) + " " + fmt("%g", v) + " m lies outside [" + fmt("%g", lo) +
                ", " + fmt("%g", hi) + "] m for an object of " + fmt("%g", diag) + " m";
    return false;
  };
  if (!(r.alpha >= diag / 1000 && r.alpha <= diag))
    return outside("--repair-alpha", r.alpha, diag / 1000, diag);
  if (!(r.offset >= diag * 1e-5 && r.offset <= diag / 10))
    return outside("--repair-offset", r.offset, diag * 1e-5, diag / 10);
  return true;
}

// The wrap lies `offset` outside the input, which thickens a wall of thickness t by 2 offset / t.
// Each vertex moves back along its normal by most of the offset, undone if that leaves the
// surface invalid (where the wrap's rounding of a convex edge would fold).
void pull_back(SurfaceMesh& wrap, double offset, const Say& say) {
  std::vector<Vec3> normal(wrap.vertices.size(), Vec3{0, 0, 0});
  for (const auto& t : wrap.triangles) {
    const Vec3 n = triangle_normal(wrap.vertices[t[0]], wrap.vertices[t[1]], wrap.vertices[t[2]]);
    for (uint32_t v : t) normal[v] = add(normal[v], n);
  }
  SurfaceMesh pulled = wrap;
  for (std::size_t v = 0; v < pulled.vertices.size(); ++v) {
    const double len = norm(normal[v]);
    if (len > 0)
      pulled.vertices[v] = sub(pulled.vertices[v], scale(normal[v], kPullBack * offset / len));
  }
  if (!check_mesh(pulled).ok()) return;
  wrap = std::move(pulled);
  say("moved the wrap back toward the input by " + fmt("%.3g", kPullBack * offset * 1e3) + " mm");
}

// The share of the wrap's area that is a slab, a wall under kSlabWall offsets thick where the
// wrap went round both sides of an open sheet, and a point on it.
double slab_share(const SurfaceMesh& wrap, double offset, Vec3& where) {
  const std::vector<double> t = local_thickness(wrap);
  double slab = 0, total = 0, thinnest = INFINITY;
  for (std::size_t f = 0; f < t.size(); ++f) {
    const auto& tri = wrap.triangles[f];
    const Vec3 &a = wrap.vertices[tri[0]], &b = wrap.vertices[tri[1]], &c = wrap.vertices[tri[2]];
    const double area = 0.5 * norm(triangle_normal(a, b, c));
    total += area;
    if (t[f] > 0 && t[f] < kSlabWall * offset) {
      slab += area;
      if (t[f] < thinnest) thinnest = t[f], where = scale(add(add(a, b), c), 1.0 / 3);
    }
  }
  return total > 0 ? slab / total : 0.0;
}

// Rung 3: the wrap, its debris dropped; a refusal when its parts stay apart or it is a slab
// around a sheet. Where part of it is a slab (a spout or a sleeve modelled as one layer, open at
// its end), alpha doubles, up to D/10, so that the ball no longer enters the opening.
bool wrap_rung(const SurfaceMesh& soup, const SurfaceMesh& input, const RepairOptions& o,
               SurfaceMesh& out, RepairReport& r, const Say& say) {
  for (;;) {
    out = alpha_wrap(soup, r.alpha, r.offset);
    say("wrapped the surface (CGAL 3D Alpha Wrapping, alpha " + fmt("%.3g", r.alpha * 1e3) +
        " mm, offset " + fmt("%.3g", r.offset * 1e3) +
        " mm): " + std::to_string(out.triangles.size()) + " triangles");
    const std::vector<std::size_t> parts = drop_debris(out, o.debris_volume, true, say);
    if (parts.size() > 1) {
      r.refusal = parts_list(out, parts, "that do not touch (the wrap kept them apart)");
      return false;
    }
    if (check_mesh(out).volume < kSlab * r.offset * area(input)) {
      r.refusal = "encloses no volume: an open sheet (the wrap is a slab " +
                  fmt("%.3g", 2 * r.offset * 1e3) +
                  " mm thick around it), not a solid; model its thickness";
      return false;
    }
    Vec3 at{0, 0, 0};
    const double slab = slab_share(out, r.offset, at);
    if (!(slab > kSlabShare)) break;
    const std::string where =
        fmt("%.2f %% of the wrap, e.g. at (%.4g, %.4g, %.4g) m", 100 * slab, at[0], at[1], at[2]);
    if (o.wrap_alpha > 0 || 2 * r.alpha > r.size / 10) {
      r.refusal = "part of it is an open sheet with no thickness (" + where + ", wraps to a slab " +
                  fmt("%.3g", 2 * r.offset * 1e3) +
                  " mm thick): model its thickness, or close its opening (a --repair-alpha "
                  "wider than the opening)";
      return false;
    }
    say("an open sheet wrapped to a slab (" + where + "): wrapping again with twice the alpha");
    r.alpha *= 2;
  }
  pull_back(out, r.offset, say);
  return true;
}

// Distances and volumes between the input and what the ladder made of it, and the refusal when
// a wrap moved it further than the options allow. The distance from the input is measured from
// what the ladder kept of it (debris removed, small holes filled), the distance to it from the
// repaired surface to the input as given.
void measure(const SurfaceMesh& kept, const SurfaceMesh& input, const SurfaceMesh& repaired,
             const RepairOptions& o, RepairReport& r) {
  const double spacing = r.size / 500;
  r.to_repaired = one_sided_distance(kept, repaired, spacing, true);
  r.to_input = one_sided_distance(repaired, input, spacing);
  r.hausdorff = std::max(r.to_repaired, r.to_input);
  r.volume_repaired = check_mesh(repaired).volume;
  if (r.rung != RepairRung::Wrap) return;
  // Moved: how far the input's points are from the wrap. The other direction also counts the
  // patches over holes, which lie away from any input point by design; it is reported only.
  const double moved = r.to_repaired / r.size, change = std::abs(r.volume_change());
  if (moved > o.max_distance || change > o.max_volume_change)
    r.refusal = "the wrap would move the surface by up to " + fmt("%.3g", r.to_repaired * 1e3) +
                " mm (" + fmt("%.2f", 100 * moved) + " % of its size; the limit is " +
                fmt("%.2f", 100 * o.max_distance) + " %) and change its volume by " +
                fmt("%+.2f", 100 * r.volume_change()) + " % (the limit is " +
                fmt("%.0f", 100 * o.max_volume_change) + " %), with alpha " +
                fmt("%.3g", r.alpha * 1e3) + " mm and offset " + fmt("%.3g", r.offset * 1e3) +
                " mm: a smaller --repair-alpha keeps concave detail, a smaller --repair-offset "
                "hugs the surface closer";
}

}  // namespace
}  // namespace repair

RepairReport repair_mesh(SurfaceMesh& m, const RepairOptions& o) {
  using namespace repair;
  RepairReport r;
  const Say say = [&](const std::string& s) { r.log.push_back(s); };
  const SurfaceMesh input = m;
  r.size = diagonal(input);
  if (thickness_across(input) <= kFlat * r.size) {
    r.refusal = "encloses no volume: all " + std::to_string(input.vertices.size()) +
                " vertices lie in one plane (a flat sheet, not a solid); model its thickness";
    return r;
  }
  if (const MeshReport given = check_mesh(input); given.ok()) {
    r.volume_input = r.volume_repaired = given.volume;
    return r;
  }
  LocalFixes fixed = local_fixes(input, o.max_hole_edges, say);
  r.input_closed = fixed.closed && fixed.holes_filled == 0;
  r.volume_input = union_volume(fixed.surface);
  SurfaceMesh cur = fixed.surface;
  const std::vector<std::size_t> parts = drop_debris(cur, o.debris_volume, fixed.closed, say);
  orient_pieces(cur, say);
  SurfaceMesh kept = cur;  // the input as the ladder reads it: what distances are measured from
  std::size_t remaining = 0;
  const bool had_intersections = remove_self_intersections(cur, say, remaining) > 0;
  remesh_needles(cur, o.min_angle_deg, say);
  orient_pieces(cur, [](const std::string&) {});
  const MeshReport checked = check_mesh(cur);
  r.rung = !checked.ok()       ? RepairRung::Wrap
           : had_intersections ? RepairRung::SelfIntersections
                               : RepairRung::Local;
  if (r.rung == RepairRung::Wrap) {
    if (!wrap_parameters(kept, r.size, o, r)) return r;
    if (parts.size() > 1 && !had_intersections && !parts_touch(kept, parts, r.alpha)) {
      r.refusal = parts_list(kept, parts, "that do not touch");
      return r;
    }
    if (!wrap_rung(kept, input, o, cur, r, say)) return r;
  }
  measure(kept, input, cur, o, r);
  if (r.refusal.empty()) m = std::move(cur);
  return r;
}

}  // namespace chladni::precompute
