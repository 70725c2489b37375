#include "split_long_edges.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../edge_key.hpp"

namespace chladni::precompute {
namespace {

using Tri = std::array<uint32_t, 3>;

struct Sides {
  std::array<uint32_t, 2> tri{};
  int count = 0;
};

// Same plane and side, to rounding: flipping or splitting their shared edge leaves the surface
// as it was.
bool coplanar(const Vec3& n1, const Vec3& n2) {
  const Vec3 c = cross(n1, n2);
  return dot(n1, n2) > 0 && dot(c, c) <= 1e-18 * dot(n1, n1) * dot(n2, n2);
}

// The surface with its edges' triangles. A crease is an edge not between two triangles of one
// plane: where planes meet, on a curved surface, or at a non-manifold edge.
class Refiner {
 public:
  Refiner(SurfaceMesh& m, double max_edge) : m_(m), max2_(max_edge * max_edge) { index(); }

  // Every crease longer than the bound split at its midpoint; a triangle with one such edge is
  // bisected, with two cut into three (the quadrilateral by its shorter diagonal), with three
  // into four. Two split creases of a triangle split its third edge too if that is a crease,
  // so a curved surface's triangles are cut into four alike; an edge within a plane is never
  // split to keep others company, as that would cut a needle into needles.
  bool split_creases();
  // Lawson's flips within planes until each plane's triangulation is Delaunay.
  void flip_all();
  // The longest edge within a plane split at its midpoint, then flips around it, until every
  // edge is within the bound.
  void refine_planes();

 private:
  void index();
  double length2(uint32_t a, uint32_t b) const {
    const Vec3 d = sub(m_.vertices[b], m_.vertices[a]);
    return dot(d, d);
  }
  Vec3 normal(uint32_t f) const {
    const Tri& t = m_.triangles[f];
    return cross(sub(m_.vertices[t[1]], m_.vertices[t[0]]),
                 sub(m_.vertices[t[2]], m_.vertices[t[0]]));
  }
  bool crease(uint64_t key) const {
    const auto it = edges_.find(key);
    return it == edges_.end() || it->second.count != 2 ||
           !coplanar(normal(it->second.tri[0]), normal(it->second.tri[1]));
  }
  // p, q, r with (p, q) the edge in the first triangle, s opposite it in the second; false
  // where the two disagree on orientation.
  bool quad(uint64_t key, uint32_t& p, uint32_t& q, uint32_t& r, uint32_t& s) const;
  uint32_t midpoint(uint32_t a, uint32_t b) {
    m_.vertices.push_back(scale(add(m_.vertices[a], m_.vertices[b]), 0.5));
    return uint32_t(m_.vertices.size() - 1);
  }
  void replace(uint64_t key, uint32_t from, uint32_t to) {
    for (uint32_t& f : edges_[key].tri) f = f == from ? to : f;
  }
  void flip(std::vector<uint64_t> stack);
  void queue_if_long(uint32_t a, uint32_t b) {
    if (length2(a, b) > max2_) long_.push({length2(a, b), edge_key(a, b)});
  }

  SurfaceMesh& m_;
  double max2_;
  std::unordered_map<uint64_t, Sides> edges_;
  std::priority_queue<std::pair<double, uint64_t>> long_;
};

void Refiner::index() {
  edges_.clear();
  edges_.reserve(2 * m_.triangles.size());
  for (uint32_t f = 0; f < m_.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      Sides& s = edges_[edge_key(m_.triangles[f][k], m_.triangles[f][(k + 1) % 3])];
      if (s.count < 2) s.tri[std::size_t(s.count)] = f;
      ++s.count;
    }
}

bool Refiner::split_creases() {
  std::unordered_map<uint64_t, uint32_t> mid;
  const auto mark = [&](uint32_t a, uint32_t b) {
    if (mid.contains(edge_key(a, b))) return false;
    mid.emplace(edge_key(a, b), midpoint(a, b));
    return true;
  };
  for (const Tri& t : m_.triangles)
    for (int k = 0; k < 3; ++k)
      if (length2(t[k], t[(k + 1) % 3]) > max2_ && crease(edge_key(t[k], t[(k + 1) % 3])))
        mark(t[k], t[(k + 1) % 3]);
  if (mid.empty()) return false;
  for (bool grew = true; grew;) {
    grew = false;
    for (const Tri& t : m_.triangles) {
      int marked = 0;
      for (int k = 0; k < 3; ++k) marked += mid.contains(edge_key(t[k], t[(k + 1) % 3])) ? 1 : 0;
      if (marked == 2)
        for (int k = 0; k < 3; ++k)
          if (crease(edge_key(t[k], t[(k + 1) % 3]))) grew |= mark(t[k], t[(k + 1) % 3]);
    }
  }
  std::vector<Tri> next;
  next.reserve(2 * m_.triangles.size());
  for (const Tri& t : m_.triangles) {
    std::array<int64_t, 3> at{-1, -1, -1};  // midpoint of edge k, (t[k], t[k+1])
    int marked = 0, whole = 0;
    for (int k = 0; k < 3; ++k) {
      if (auto it = mid.find(edge_key(t[k], t[(k + 1) % 3])); it != mid.end())
        at[k] = it->second, ++marked;
      else
        whole = k;
    }
    const auto v = [&](int k) { return t[k % 3]; };
    const auto md = [&](int k) { return uint32_t(at[k % 3]); };
    if (marked == 0) {
      next.push_back(t);
    } else if (marked == 1) {
      const int k = at[0] >= 0 ? 0 : at[1] >= 0 ? 1 : 2;
      next.insert(next.end(), {{v(k), md(k), v(k + 2)}, {md(k), v(k + 1), v(k + 2)}});
    } else if (marked == 2) {
      // (a, b, c) with (c, a) whole, mm on (a, b) and n on (b, c).
      const uint32_t c = v(whole), a = v(whole + 1), b = v(whole + 2), mm = md(whole + 1),
                     n = md(whole + 2);
      next.push_back({mm, b, n});
      if (length2(a, n) <= length2(mm, c))
        next.insert(next.end(), {{a, mm, n}, {a, n, c}});
      else
        next.insert(next.end(), {{a, mm, c}, {mm, n, c}});
    } else {
      next.insert(next.end(), {{v(0), md(0), md(2)},
                               {md(0), v(1), md(1)},
                               {md(2), md(1), v(2)},
                               {md(0), md(1), md(2)}});
    }
  }
  m_.triangles = std::move(next);
  index();
  return true;
}

bool Refiner::quad(uint64_t key, uint32_t& p, uint32_t& q, uint32_t& r, uint32_t& s) const {
  const Sides& e = edges_.at(key);
  const Tri &t1 = m_.triangles[e.tri[0]], &t2 = m_.triangles[e.tri[1]];
  int i = 0;
  while (edge_key(t1[i], t1[(i + 1) % 3]) != key) ++i;
  p = t1[i], q = t1[(i + 1) % 3], r = t1[(i + 2) % 3];
  int j = 0;
  while (t2[j] != q) ++j;
  s = t2[(j + 2) % 3];
  return t2[(j + 1) % 3] == p;
}

double angle_at(const SurfaceMesh& m, uint32_t apex, uint32_t a, uint32_t b) {
  const Vec3 u = sub(m.vertices[a], m.vertices[apex]), w = sub(m.vertices[b], m.vertices[apex]);
  const Vec3 c = cross(u, w);
  return std::atan2(std::sqrt(dot(c, c)), dot(u, w));
}

// An edge whose opposite angles sum to more than pi is replaced by the other diagonal of its
// quadrilateral (always convex then), and its four sides are checked in turn.
void Refiner::flip(std::vector<uint64_t> stack) {
  // Lawson's algorithm ends; the cap only guards against rounding on near-cocircular points.
  for (std::size_t flips = 0; !stack.empty() && flips < 64 * m_.triangles.size();) {
    const uint64_t key = stack.back();
    stack.pop_back();
    const auto it = edges_.find(key);
    if (it == edges_.end() || it->second.count != 2) continue;
    const uint32_t f1 = it->second.tri[0], f2 = it->second.tri[1];
    uint32_t p, q, r, s;
    if (!quad(key, p, q, r, s) || !coplanar(normal(f1), normal(f2))) continue;
    if (angle_at(m_, r, p, q) + angle_at(m_, s, q, p) <= std::numbers::pi + 1e-9) continue;
    if (edges_.contains(edge_key(r, s))) continue;
    m_.triangles[f1] = {p, s, r}, m_.triangles[f2] = {s, q, r};
    edges_.erase(it);
    edges_[edge_key(r, s)] = Sides{{f1, f2}, 2};
    replace(edge_key(p, s), f2, f1);
    replace(edge_key(q, r), f1, f2);
    queue_if_long(r, s);
    stack.insert(stack.end(), {edge_key(p, s), edge_key(s, q), edge_key(q, r), edge_key(r, p)});
    ++flips;
  }
}

void Refiner::flip_all() {
  std::vector<uint64_t> stack;
  stack.reserve(edges_.size());
  for (const auto& [key, s] : edges_)
    if (s.count == 2) stack.push_back(key);
  flip(std::move(stack));
}

void Refiner::refine_planes() {
  for (const auto& [key, s] : edges_)
    if (s.count == 2) queue_if_long(uint32_t(key >> 32), uint32_t(key));
  // About area / max_edge^2 points suffice; the cap only guards against rounding.
  double area = 0;
  for (uint32_t f = 0; f < m_.triangles.size(); ++f) {
    const Vec3 n = normal(f);
    area += 0.5 * std::sqrt(dot(n, n));
  }
  const double cap = 16 * (double(m_.vertices.size()) + area / max2_);
  while (!long_.empty() && double(m_.vertices.size()) < cap) {
    const uint64_t key = long_.top().second;
    long_.pop();
    const auto it = edges_.find(key);
    uint32_t p, q, r, s;
    if (it == edges_.end() || it->second.count != 2 || !quad(key, p, q, r, s) ||
        length2(p, q) <= max2_ || crease(key))
      continue;
    const uint32_t f1 = it->second.tri[0], f2 = it->second.tri[1];
    const auto f3 = uint32_t(m_.triangles.size()), f4 = f3 + 1;
    const uint32_t mm = midpoint(p, q);
    m_.triangles[f1] = {p, mm, r}, m_.triangles[f2] = {q, mm, s};
    m_.triangles.push_back({mm, q, r});
    m_.triangles.push_back({mm, p, s});
    edges_.erase(it);
    edges_[edge_key(p, mm)] = Sides{{f1, f4}, 2};
    edges_[edge_key(mm, q)] = Sides{{f3, f2}, 2};
    edges_[edge_key(mm, r)] = Sides{{f1, f3}, 2};
    edges_[edge_key(mm, s)] = Sides{{f2, f4}, 2};
    replace(edge_key(q, r), f1, f3);
    replace(edge_key(p, s), f2, f4);
    for (auto [a, b] : {std::pair{p, mm}, {mm, q}, {mm, r}, {mm, s}}) queue_if_long(a, b);
    flip({edge_key(q, r), edge_key(r, p), edge_key(p, s), edge_key(s, q)});
  }
}

}  // namespace

SurfaceMesh split_long_edges(SurfaceMesh m, double max_edge) {
  Refiner r(m, max_edge);
  bool split = false;
  // The creases first: a plane's inner edges are split only where they are still long once its
  // outline is and it is Delaunay, so a strip narrower than the bound gets no point inside.
  for (int pass = 0; pass < 64 && r.split_creases(); ++pass) split = true;
  if (split) r.flip_all();
  r.refine_planes();
  return m;
}

}  // namespace chladni::precompute
