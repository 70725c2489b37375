// Local refinement by longest-edge bisection: the mesher that cannot fail, for when TetGen's
// refinement aborts. Each round bisects the longest edge of every tetrahedron over its bound
// (Rivara 1991); conformity is kept by marking, closed over the mesh so that every tetrahedron
// holding a marked edge also has its own longest edge marked, and by splitting each tetrahedron
// at its marked edges in one global order (length, then node numbers), so the two sides of a face
// cut it the same way (Arnold, Mukherjee & Pouly 2000 use the same idea with their own order).
#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "../edge_key.hpp"
#include "chladni/core/error.hpp"
#include "chladni/precompute/tet_mesh.hpp"

namespace chladni::precompute {
namespace {

using Tet = std::array<uint32_t, 4>;
constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

struct Bisector {
  std::vector<Vec3> nodes;
  std::unordered_set<uint64_t> marked;
  std::unordered_map<uint64_t, uint32_t> midpoint;

  double volume(const Tet& t) const {
    const Vec3& a = nodes[t[0]];
    return dot(cross(sub(nodes[t[1]], a), sub(nodes[t[2]], a)), sub(nodes[t[3]], a)) / 6;
  }
  double length2(uint64_t key) const {
    const Vec3 d = sub(nodes[uint32_t(key >> 32)], nodes[uint32_t(key)]);
    return dot(d, d);
  }
  // The global order: longer first, ties by node numbers, so every tetrahedron ranks the edges
  // it shares with a neighbour the same way.
  bool before(uint64_t a, uint64_t b) const {
    const double la = length2(a), lb = length2(b);
    return la != lb ? la > lb : a > b;
  }
  // The tetrahedron's edge first in that order among those `pick` accepts; -1 if none.
  template <class Pick>
  int first_edge(const Tet& t, Pick pick) const {
    int best = -1;
    uint64_t best_key = 0;
    for (int e = 0; e < 6; ++e) {
      const uint64_t k = edge_key(t[kEdges[e][0]], t[kEdges[e][1]]);
      if (pick(k) && (best < 0 || before(k, best_key))) best = e, best_key = k;
    }
    return best;
  }
  int longest(const Tet& t) const {
    return first_edge(t, [](uint64_t) { return true; });
  }
  uint32_t middle(uint32_t a, uint32_t b) {
    const auto [it, fresh] = midpoint.try_emplace(edge_key(a, b), uint32_t(nodes.size()));
    if (fresh) {
      const Vec3 &p = nodes[a], &q = nodes[b];
      nodes.push_back({0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 0.5 * (p[2] + q[2])});
    }
    return it->second;
  }
  // Splits `t` at its marked edges, first in the global order first; replacing a corner by the
  // midpoint keeps the orientation.
  void split(const Tet& t, double bound, std::vector<Tet>& tets, std::vector<double>& bounds) {
    const int e = first_edge(t, [&](uint64_t k) { return marked.count(k) > 0; });
    if (e < 0) {
      tets.push_back(t);
      bounds.push_back(bound);
      return;
    }
    const int i = kEdges[e][0], j = kEdges[e][1];
    const uint32_t m = middle(t[i], t[j]);
    Tet a = t, b = t;
    a[i] = m;
    b[j] = m;
    split(a, bound, tets, bounds);
    split(b, bound, tets, bounds);
  }
};

}  // namespace

TetMesh bisect_tets(const TetMesh& mesh, const std::vector<double>& max_volume) {
  if (max_volume.size() != mesh.tets.size())
    throw InternalError("bisect_tets: one volume bound per tetrahedron expected");
  Bisector b{mesh.nodes, {}, {}};
  std::vector<Tet> tets = mesh.tets;
  std::vector<double> bounds = max_volume;
  for (int round = 0;; ++round) {
    b.marked.clear();
    b.midpoint.clear();
    for (std::size_t t = 0; t < tets.size(); ++t)
      if (bounds[t] > 0 && b.volume(tets[t]) > bounds[t]) {
        const int e = b.longest(tets[t]);
        b.marked.insert(edge_key(tets[t][kEdges[e][0]], tets[t][kEdges[e][1]]));
      }
    if (b.marked.empty()) break;
    if (round == 64) throw InputError("bisection did not meet the volume bounds in 64 rounds");
    // Closure: a tetrahedron to be cut at any edge is cut at its longest first.
    for (bool changed = true; changed;) {
      changed = false;
      for (const Tet& q : tets) {
        if (b.first_edge(q, [&](uint64_t k) { return b.marked.count(k) > 0; }) < 0) continue;
        const int e = b.longest(q);
        changed |= b.marked.insert(edge_key(q[kEdges[e][0]], q[kEdges[e][1]])).second;
      }
    }
    std::vector<Tet> next;
    std::vector<double> next_bounds;
    next.reserve(tets.size() + 2 * b.marked.size());
    next_bounds.reserve(next.capacity());
    for (std::size_t t = 0; t < tets.size(); ++t) b.split(tets[t], bounds[t], next, next_bounds);
    if (next.size() > kMaxTetrahedra)
      throw InputError("bisecting the mesh would make more than " + std::to_string(kMaxTetrahedra) +
                       " tetrahedra");
    tets.swap(next);
    bounds.swap(next_bounds);
  }
  TetMesh r;
  r.nodes = std::move(b.nodes);
  r.tets = std::move(tets);
  r.surface_vertices = mesh.surface_vertices;
  r.surface_triangles = boundary_faces(r);
  return r;
}

}  // namespace chladni::precompute
