#include "chladni/runtime/paper/paper_analysis.hpp"

#include <algorithm>
#include <climits>
#include <cmath>

#include "chladni/core/error.hpp"

namespace chladni::runtime {
namespace {

std::uint32_t other_face(const PaperTopology& t, std::uint32_t e, std::uint32_t f) {
  const auto& ef = t.edge_faces[e];
  return std::uint32_t(ef[0] == std::int32_t(f) ? ef[1] : ef[0]);
}

}  // namespace

PaperAnalyzer::PaperAnalyzer(const PaperAnimation& anim, PaperAnalysisOptions options)
    : anim_(anim), opt_(options), topo_(PaperTopology::build(anim.vertex_count, anim.triangles)) {
  if (!(opt_.ridge_angle > 0) || !(opt_.flat_curvature >= 0) || !(opt_.crumple_curvature >= 0) ||
      !(opt_.min_friction_speed >= 0) || !(opt_.min_resonator_area >= 0) ||
      opt_.rulings_per_resonator < 1)
    throw InputError("paper analysis: thresholds must be finite and positive");
  const std::size_t nv = topo_.vertex_count, nf = topo_.triangles.size();
  constrained_.resize(nv);
  barrier_.resize(topo_.edges.size());
  region_.resize(nf);
  curved_.resize(nf);
  mark_.resize(std::max(nv, nf));
  flood_.resize(nf);
  comp_stamp_.assign(nf, 0);
  reach_stamp_.assign(nf, 0);
  piece_stamp_.assign(nf, 0);
  piece_of_.assign(nf, 0);
}

PaperFrameAnalysis PaperAnalyzer::analyze(std::uint32_t frame) {
  if (frame >= anim_.frame_count())
    throw InputError("paper analysis: frame " + std::to_string(frame) + " of " +
                     std::to_string(anim_.frame_count()));
  return analyze(frame, anim_.frame(frame), nullptr);
}

PaperFrameAnalysis PaperAnalyzer::analyze(std::uint32_t frame, std::span<const float> xyz,
                                          const std::vector<std::uint32_t>* held) {
  if (xyz.size() != std::size_t(topo_.vertex_count) * 3)
    throw InputError("paper analysis: frame " + std::to_string(frame) + " has " +
                     std::to_string(xyz.size() / 3) + " vertices, the sheet " +
                     std::to_string(topo_.vertex_count));
  if (held)
    for (std::uint32_t v : *held)
      if (v >= topo_.vertex_count)
        throw InputError("paper analysis: frame " + std::to_string(frame) + " holds vertex " +
                         std::to_string(v) + " of " + std::to_string(topo_.vertex_count));
  const bool continuing = frame != 0 && std::int64_t(frame) == last_frame_ + 1;
  if (frame != 0 && !continuing)
    throw InputError("paper analysis: frames must be analysed in order (got " +
                     std::to_string(frame) + " after " + std::to_string(last_frame_) + ")");
  PaperFrameAnalysis out;
  out.frame = frame;
  out.time = frame / anim_.frame_rate;
  geo_.update(topo_, xyz);
  partitioned_ = false;

  // Vertices held by fingers or lying on an obstacle: vibrations stop there.
  std::fill(constrained_.begin(), constrained_.end(), 0);
  if (held) {
    for (std::uint32_t v : *held) constrained_[v] = 1;
  } else {
    for (const PaperAnchor& a : anim_.anchors)
      if (frame >= a.first_frame && frame <= a.last_frame)
        for (std::uint32_t v : a.vertices) constrained_[v] = 1;
  }
  for (const PaperObstacle& o : anim_.obstacles)
    for (std::size_t v = 0; v < geo_.position.size(); ++v)
      if (dot(sub(geo_.position[v], o.point), o.normal) < anim_.contact_distance)
        constrained_[v] = 1;

  if (continuing) {
    detect_friction(frame, out.events);
    detect_crumpling(out.events);
    if (!out.events.empty()) out.regions = region_count_;
  }
  prev_position_ = geo_.position;
  if (!continuing) settled_curvature_.assign(geo_.mean_curvature.size(), 0.0);
  for (std::size_t v = 0; v < settled_curvature_.size(); ++v)
    if (std::abs(geo_.mean_curvature[v]) > opt_.crumple_curvature)
      settled_curvature_[v] = geo_.mean_curvature[v];
  last_frame_ = frame;
  return out;
}

template <class Pred>
void PaperAnalyzer::collect_vertices(std::uint32_t seed, Pred&& in_set) {
  members_.clear();
  stack_.assign(1, seed);
  mark_[seed] = 1;
  while (!stack_.empty()) {
    const std::uint32_t v = stack_.back();
    stack_.pop_back();
    members_.push_back(v);
    for (std::uint32_t e : topo_.edges_at(v)) {
      const std::uint32_t u = topo_.other(e, v);
      if (!mark_[u] && in_set(u)) mark_[u] = 1, stack_.push_back(u);
    }
  }
}

// Friction (§4): connected vertices within the contact distance of one obstacle; amplitude =
// their mean speed along the plane (sliding, not lifting, rubs).
void PaperAnalyzer::detect_friction(std::uint32_t frame, std::vector<PaperEvent>& out) {
  (void)frame;
  const std::size_t nv = geo_.position.size();
  for (std::size_t oi = 0; oi < anim_.obstacles.size(); ++oi) {
    const PaperObstacle& o = anim_.obstacles[oi];
    auto touching = [&](std::uint32_t v) {
      return dot(sub(geo_.position[v], o.point), o.normal) < anim_.contact_distance;
    };
    std::fill(mark_.begin(), mark_.begin() + std::ptrdiff_t(nv), 0);
    for (std::uint32_t seed = 0; seed < nv; ++seed) {
      if (mark_[seed] || !touching(seed)) continue;
      collect_vertices(seed, touching);
      double speed = 0;
      Vec3 c{0, 0, 0};
      for (std::uint32_t v : members_) {
        Vec3 d = sub(geo_.position[v], prev_position_[v]);
        d = sub(d, scale(o.normal, dot(d, o.normal)));
        speed += norm(d) * anim_.frame_rate;
        c = add(c, geo_.position[v]);
      }
      speed /= double(members_.size());
      if (speed < opt_.min_friction_speed) continue;
      PaperEvent ev;
      ev.type = PaperEventType::Friction;
      ev.amplitude = speed;
      ev.obstacle = std::int32_t(oi);
      ev.vertices = std::uint32_t(members_.size());
      ev.centroid = scale(c, 1.0 / double(members_.size()));
      const std::vector<std::uint32_t> verts = members_;
      find_resonators(verts, ev);
      out.push_back(std::move(ev));
    }
  }
}

// Crumpling (§4, after An et al. 2012): connected vertices whose mean curvature changed sign
// the same way; amplitude = the sum of their curvature changes. A vertex's sign is the sign
// of its last curvature beyond the threshold (hysteresis), so a smooth crossing through zero
// spread over several frames counts once, at the frame the new sign is established, and
// noise around zero never counts.
void PaperAnalyzer::detect_crumpling(std::vector<PaperEvent>& out) {
  const std::size_t nv = geo_.position.size();
  const double thr = opt_.crumple_curvature;
  auto change = [&](std::uint32_t v) -> int {
    const double a = settled_curvature_[v], b = geo_.mean_curvature[v];
    if (a == 0 || std::abs(b) <= thr) return 0;
    if (a > 0 && b < 0) return 1;
    if (a < 0 && b > 0) return 2;
    return 0;
  };
  std::fill(mark_.begin(), mark_.begin() + std::ptrdiff_t(nv), 0);
  for (std::uint32_t seed = 0; seed < nv; ++seed) {
    // Held vertices cannot snap, and counting them would seed the flood on both sides of
    // the finger or ruler that holds them.
    const int kind = mark_[seed] || constrained_[seed] ? 0 : change(seed);
    if (!kind) continue;
    collect_vertices(seed, [&](std::uint32_t u) { return !constrained_[u] && change(u) == kind; });
    PaperEvent ev;
    ev.type = PaperEventType::Crumple;
    Vec3 c{0, 0, 0};
    for (std::uint32_t v : members_) {
      ev.amplitude += std::abs(geo_.mean_curvature[v] - settled_curvature_[v]);
      c = add(c, geo_.position[v]);
    }
    ev.vertices = std::uint32_t(members_.size());
    ev.centroid = scale(c, 1.0 / double(members_.size()));
    const std::vector<std::uint32_t> verts = members_;
    find_resonators(verts, ev);
    out.push_back(std::move(ev));
  }
}

// Regions (§4): faces split into flat and curved by their principal curvature, and regions =
// connected faces of one kind not separated by a ridge. Propagation barriers: ridges
// (|dihedral| > a_max) and edges whose ends are both held (anchored or in contact).
void PaperAnalyzer::partition() {
  if (partitioned_) return;
  geo_.update_shape(topo_);
  const std::size_t nf = topo_.triangles.size();
  for (std::size_t e = 0; e < topo_.edges.size(); ++e) {
    const auto [a, b] = topo_.edges[e];
    barrier_[e] =
        std::abs(geo_.dihedral[e]) > opt_.ridge_angle || (constrained_[a] && constrained_[b]);
  }
  for (std::size_t f = 0; f < nf; ++f) curved_[f] = geo_.face_curvature[f] > opt_.flat_curvature;
  std::fill(region_.begin(), region_.end(), -1);
  region_count_ = 0;
  for (std::uint32_t seed = 0; seed < nf; ++seed) {
    if (region_[seed] >= 0) continue;
    const auto id = std::int32_t(region_count_++);
    region_[seed] = id;
    stack_.assign(1, seed);
    while (!stack_.empty()) {
      const std::uint32_t f = stack_.back();
      stack_.pop_back();
      for (std::uint32_t e : topo_.face_edges[f]) {
        if (topo_.border(e) || std::abs(geo_.dihedral[e]) > opt_.ridge_angle) continue;
        const std::uint32_t g = other_face(topo_, e, f);
        if (region_[g] < 0 && curved_[g] == curved_[f]) region_[g] = id, stack_.push_back(g);
      }
    }
  }
  // Flood components: faces joined by edges that let vibrations through.
  std::fill(flood_.begin(), flood_.end(), UINT32_MAX);
  std::uint32_t comps = 0;
  comp_start_.assign(1, 0);
  comp_faces_.clear();
  for (std::uint32_t seed = 0; seed < nf; ++seed) {
    if (flood_[seed] != UINT32_MAX) continue;
    flood_[seed] = comps;
    stack_.assign(1, seed);
    while (!stack_.empty()) {
      const std::uint32_t f = stack_.back();
      stack_.pop_back();
      comp_faces_.push_back(f);
      for (std::uint32_t e : topo_.face_edges[f]) {
        if (topo_.border(e) || barrier_[e]) continue;
        const std::uint32_t g = other_face(topo_, e, f);
        if (flood_[g] == UINT32_MAX) flood_[g] = comps, stack_.push_back(g);
      }
    }
    comp_start_.push_back(std::uint32_t(comp_faces_.size()));
    ++comps;
  }
  cache_.clear();
  partitioned_ = true;
}

// Resonators (§4, Fig. 7): flood from the event's faces across non-barrier edges; each
// connected piece of one region inside the flood is a resonator.
void PaperAnalyzer::find_resonators(const std::vector<std::uint32_t>& event_vertices,
                                    PaperEvent& ev) {
  partition();
  // The flood from the event's faces is the union of the flood components they touch.
  const std::uint32_t stamp = next_stamp();
  comps_.clear();
  for (std::uint32_t v : event_vertices)
    for (std::uint32_t e : topo_.edges_at(v))
      for (std::int32_t f : topo_.edge_faces[e]) {
        if (f < 0) continue;
        const std::uint32_t c = flood_[std::size_t(f)];
        if (comp_stamp_[c] != stamp) comp_stamp_[c] = stamp, comps_.push_back(c);
      }
  std::sort(comps_.begin(), comps_.end());
  // Events of one frame often shake the same part of the sheet: reuse its resonators.
  for (const auto& [key, res] : cache_) {
    if (key == comps_) {
      ev.resonators = res;
      return;
    }
  }
  reached_list_.clear();
  for (std::uint32_t c : comps_)
    for (std::uint32_t i = comp_start_[c]; i < comp_start_[c + 1]; ++i) {
      reached_list_.push_back(comp_faces_[i]);
      reach_stamp_[comp_faces_[i]] = stamp;
    }
  for (std::uint32_t seed : reached_list_) {
    if (piece_stamp_[seed] == stamp) continue;
    faces_.clear();
    stack_.assign(1, seed);
    piece_stamp_[seed] = stamp;
    while (!stack_.empty()) {
      const std::uint32_t f = stack_.back();
      stack_.pop_back();
      faces_.push_back(f);
      for (std::uint32_t e : topo_.face_edges[f]) {
        // Held edges stop the flood but do not split what it reached: a sheet lying on the
        // table is one constrained resonator, not one per triangle.
        if (topo_.border(e) || std::abs(geo_.dihedral[e]) > opt_.ridge_angle) continue;
        const std::uint32_t g = other_face(topo_, e, f);
        if (reach_stamp_[g] == stamp && piece_stamp_[g] != stamp && region_[g] == region_[f])
          piece_stamp_[g] = stamp, stack_.push_back(g);
      }
    }
    PaperResonator r;
    r.curved = curved_[seed] != 0;
    r.faces = std::uint32_t(faces_.size());
    Vec3 c{0, 0, 0}, n{0, 0, 0};
    for (std::uint32_t f : faces_) {
      const auto& t = topo_.triangles[f];
      const double a = geo_.face_area[f];
      r.area += a;
      c = add(c, scale(add(add(geo_.position[t[0]], geo_.position[t[1]]), geo_.position[t[2]]),
                       a / 3.0));
      n = add(n, scale(geo_.face_normal[f], a));
      if (!r.curved) continue;
      for (std::uint32_t e : topo_.face_edges[f]) {
        const auto [va, vb] = topo_.edges[e];
        if (!topo_.border(e) || constrained_[va] || constrained_[vb]) continue;
        // Only the curved part of a border is free to flap: a border along the ruling is a
        // straight line and counts nothing (the paper's l_c is the bent edges' length).
        const double len = geo_.edge_length[e];
        if (!(len > 0)) continue;
        const double along = dot(sub(geo_.position[vb], geo_.position[va]), geo_.ruling[f]) / len;
        r.free_border += len * std::sqrt(std::max(0.0, 1.0 - along * along));
      }
    }
    r.centroid = r.area > 0 ? scale(c, 1.0 / r.area) : geo_.position[topo_.triangles[seed][0]];
    const double nn = norm(n);
    r.normal = nn > 1e-9 * r.area ? scale(n, 1.0 / nn) : geo_.face_normal[seed];
    r.constrained = !(r.free_border > 0);
    if (r.curved) {
      // A fresh label restricts the trace to this piece without clearing the array.
      if (piece_label_ == INT32_MAX)
        std::fill(piece_of_.begin(), piece_of_.end(), 0), piece_label_ = 0;
      const std::int32_t label = ++piece_label_;
      for (std::uint32_t f : faces_) piece_of_[f] = label;
      const std::size_t k =
          std::min<std::size_t>(std::size_t(opt_.rulings_per_resonator), faces_.size());
      lengths_.clear();
      for (std::size_t i = 0; i < k; ++i) {
        // Evenly spread faces of the piece.
        const std::uint32_t f = faces_[(i * faces_.size()) / k + (faces_.size() / k) / 2];
        lengths_.push_back(trace_ruling(f));
      }
      // The median: a ruling started in a face at the piece's edge, where the flat/curved
      // classification frays, stops early and would drag a mean down.
      std::nth_element(lengths_.begin(), lengths_.begin() + std::ptrdiff_t(k / 2), lengths_.end());
      r.ruling_length = lengths_[k / 2];
    }
    if (r.area >= opt_.min_resonator_area) ev.resonators.push_back(r);
  }
  cache_.emplace_back(comps_, ev.resonators);
}

std::uint32_t PaperAnalyzer::next_stamp() {
  if (stamp_ == UINT32_MAX) {
    std::fill(comp_stamp_.begin(), comp_stamp_.end(), 0);
    std::fill(reach_stamp_.begin(), reach_stamp_.end(), 0);
    std::fill(piece_stamp_.begin(), piece_stamp_.end(), 0);
    stamp_ = 0;
  }
  return ++stamp_;
}

// Length of the straight line through face f's centroid along its ruling, walked across the
// triangles of the piece both ways until it leaves the piece, a barrier or the border.
double PaperAnalyzer::trace_ruling(std::uint32_t face) const {
  const std::int32_t label = piece_of_[face];
  const auto& t0 = topo_.triangles[face];
  const Vec3 start =
      scale(add(add(geo_.position[t0[0]], geo_.position[t0[1]]), geo_.position[t0[2]]), 1.0 / 3.0);
  const std::size_t max_steps = 4 * topo_.triangles.size() + 8;
  double total = 0;
  for (double sign : {1.0, -1.0}) {
    const Vec3 dir = scale(geo_.ruling[face], sign);
    Vec3 p = start;
    std::uint32_t cur = face;
    std::int32_t came_from = -1;  // the edge we entered by: never exit through it
    for (std::size_t step = 0; step < max_steps; ++step) {
      const Vec3& n = geo_.face_normal[cur];
      Vec3 d = sub(dir, scale(n, dot(dir, n)));
      const double dl = norm(d);
      if (!(dl > 1e-12)) break;
      d = scale(d, 1.0 / dl);
      const auto& t = topo_.triangles[cur];
      double best = INFINITY;
      int exit_k = -1;
      for (int k = 0; k < 3; ++k) {
        if (std::int32_t(topo_.face_edges[cur][k]) == came_from) continue;
        const Vec3& a = geo_.position[t[k]];
        const Vec3& b = geo_.position[t[(k + 1) % 3]];
        const Vec3 m = cross(n, sub(b, a));  // points into the triangle
        const double rate = dot(d, m);
        if (rate >= 0) continue;
        const double tt = std::max(0.0, dot(sub(p, a), m) / -rate);
        if (tt < best) best = tt, exit_k = k;
      }
      if (exit_k < 0) break;
      p = add(p, scale(d, best));
      total += best;
      const std::uint32_t e = topo_.face_edges[cur][exit_k];
      if (topo_.border(e) || barrier_[e]) break;
      const std::uint32_t g = other_face(topo_, e, cur);
      if (piece_of_[g] != label) break;
      came_from = std::int32_t(e);
      cur = g;
    }
  }
  return total;
}

}  // namespace chladni::runtime
