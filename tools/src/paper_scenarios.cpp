#include "chladni/tools/paper_scenarios.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "chladni/core/error.hpp"

namespace chladni::tools {
namespace {

struct Grid {
  std::uint32_t nx = 2, ny = 2;  // vertices along the width (x) and the length (y)
  double width = 0, length = 0;
  double u(std::uint32_t i) const { return width * i / (nx - 1); }
  double v(std::uint32_t j) const { return length * j / (ny - 1); }
  std::uint32_t id(std::uint32_t i, std::uint32_t j) const { return j * nx + i; }
};

// A width x length sheet with about `triangles` triangles, diagonals alternating so that no
// direction is preferred by the mesh.
Grid make_grid(PaperAnimation& anim, double width, double length, std::uint32_t triangles) {
  Grid g;
  g.width = width, g.length = length;
  const double cells = std::max(2.0, triangles / 2.0);
  const auto cx = std::uint32_t(std::max(1.0, std::round(std::sqrt(cells * width / length))));
  const auto cy = std::uint32_t(std::max(1.0, std::round(cells / cx)));
  g.nx = cx + 1, g.ny = cy + 1;
  anim.vertex_count = g.nx * g.ny;
  anim.triangles.clear();
  for (std::uint32_t j = 0; j + 1 < g.ny; ++j) {
    for (std::uint32_t i = 0; i + 1 < g.nx; ++i) {
      const std::uint32_t a = g.id(i, j), b = g.id(i + 1, j), c = g.id(i + 1, j + 1),
                          d = g.id(i, j + 1);
      if ((i + j) % 2 == 0) {
        anim.triangles.push_back({a, b, c});
        anim.triangles.push_back({a, c, d});
      } else {
        anim.triangles.push_back({a, b, d});
        anim.triangles.push_back({b, c, d});
      }
    }
  }
  return g;
}

// Fills the frames from a map (frame time, u, v) -> position.
void fill_frames(PaperAnimation& anim, const Grid& g, std::uint32_t frames,
                 const std::function<Vec3(double, double, double)>& at) {
  anim.positions.resize(std::size_t(frames) * anim.vertex_count * 3);
  for (std::uint32_t f = 0; f < frames; ++f) {
    const double t = f / anim.frame_rate;
    float* x = anim.positions.data() + std::size_t(f) * anim.vertex_count * 3;
    for (std::uint32_t j = 0; j < g.ny; ++j) {
      for (std::uint32_t i = 0; i < g.nx; ++i) {
        const Vec3 p = at(t, g.u(i), g.v(j));
        float* o = x + std::size_t(g.id(i, j)) * 3;
        o[0] = float(p[0]), o[1] = float(p[1]), o[2] = float(p[2]);
      }
    }
  }
}

// +1 before `t0`, -1 after: a snap-through completing within about two frames.
double snap(double t, double t0, double frame_rate) {
  return -std::tanh((t - t0) * frame_rate * 1.5);
}

// A cylindrical bend of curvature k along material length v (rulings along x): the bent
// point's (along, up) offsets.
std::pair<double, double> bend(double k, double v) {
  if (std::abs(k) < 1e-9) return {v, 0.0};
  return {std::sin(k * v) / k, (1.0 - std::cos(k * v)) / k};
}

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

// Portable uniform numbers (std::uniform_real_distribution differs between libraries).
struct Rng {
  std::mt19937 gen;
  explicit Rng(std::uint32_t seed) : gen(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * ((gen() >> 8) * 0x1p-24); }
};

PaperObstacle table() {
  return {"table", {0, 0, 0}, {0, 0, 1}, "wood"};
}

std::uint32_t frame_of(double t, double rate) {
  return std::uint32_t(std::lround(t * rate));
}

// The common end of a scenario: the hands, the table, the listener and what to expect.
void finish(PaperScenario& s, PaperAnchor held, std::uint32_t frames, const Vec3& listener,
            const std::vector<double>& event_times, double width, double length,
            const char* description) {
  PaperAnimation& a = s.animation;
  held.last_frame = frames - 1;
  a.anchors = {std::move(held)};
  a.obstacles = {table()};
  a.listener.position = listener;
  for (double t : event_times) s.event_frames.push_back(frame_of(t, a.frame_rate));
  std::sort(s.event_frames.begin(), s.event_frames.end());
  s.sheet_width = width, s.sheet_length = length;
  s.description = description;
}

void slide(PaperScenario& s, const PaperScenarioOptions& o) {
  PaperAnimation& a = s.animation;
  const double W = 0.21, L = 0.297, T = o.duration > 0 ? o.duration : 3.0;
  const Grid g = make_grid(a, W, L, o.triangles);
  const double speed = 0.05, arc_max = 0.12, angle_max = 2.2;
  const auto frames = std::max<std::uint32_t>(2, frame_of(T, a.frame_rate) + 1);
  // Flat on the table from the back edge, then a curl of growing length and fixed radius
  // tangent to the table: the front edge (held by the hand) is pushed back over the sheet.
  fill_frames(a, g, frames, [&](double t, double u, double v) -> Vec3 {
    const double p = 0.15 + 0.85 * smoothstep(t / T);
    const double arc = arc_max * p, radius = arc_max / angle_max;
    const double y0 = speed * t - 0.1, flat = L - arc;
    if (v <= flat) return {u - W / 2, y0 + v, 0.0};
    const double alpha = (v - flat) / radius;
    return {u - W / 2, y0 + flat + radius * std::sin(alpha), radius * (1 - std::cos(alpha))};
  });
  PaperAnchor hand;
  for (std::uint32_t i = 0; i < g.nx; ++i) hand.vertices.push_back(g.id(i, g.ny - 1));
  finish(s, hand, frames, {0.0, -0.5, 0.3}, {}, W, L,
         "a sheet slid on a table at 5 cm/s while its front edge curls up over it");
  s.event_frames = {1, frames - 1};
}

void flap(PaperScenario& s, const PaperScenarioOptions& o) {
  PaperAnimation& a = s.animation;
  const double W = 0.21, L = 0.15, T = o.duration > 0 ? o.duration : 2.4;
  const Grid g = make_grid(a, W, L, o.triangles);
  std::vector<double> snaps;
  for (double t = 0.4; t < T - 0.2; t += 0.5) snaps.push_back(t);
  const auto frames = std::max<std::uint32_t>(2, frame_of(T, a.frame_rate) + 1);
  const double k0 = 1.0 / 0.12;
  fill_frames(a, g, frames, [&](double t, double u, double v) -> Vec3 {
    double k = k0;
    for (double ts : snaps) k *= snap(t, ts, a.frame_rate);
    const auto [along, up] = bend(k, v);
    return {u - W / 2, along, 0.3 + up};
  });
  PaperAnchor edge;  // held along the edge y = 0, which lies along the rulings
  for (std::uint32_t i = 0; i < g.nx; ++i) edge.vertices.push_back(g.id(i, 0));
  finish(s, edge, frames, {0.0, -0.5, 0.3}, snaps, W, L,
         "a sheet held along one edge, 30 cm above a table, its bend snapping back and forth "
         "every 0.5 s");
}

void shake(PaperScenario& s, const PaperScenarioOptions& o) {
  PaperAnimation& a = s.animation;
  const double W = 0.21, L = 0.297, T = o.duration > 0 ? o.duration : 2.0;
  const Grid g = make_grid(a, W, L, o.triangles);
  const double f = 2.0, amp = 0.03, k0 = 1.0 / 0.15, top = 0.6;
  std::vector<double> snaps;  // the bend reverses at each turning point of the shake
  for (double t = 0.25 / f; t < T - 0.1; t += 0.5 / f) snaps.push_back(t);
  const auto frames = std::max<std::uint32_t>(2, frame_of(T, a.frame_rate) + 1);
  fill_frames(a, g, frames, [&](double t, double u, double v) -> Vec3 {
    double k = k0;
    for (double ts : snaps) k *= snap(t, ts, a.frame_rate);
    const auto [down, out] = bend(k, v);
    return {u - W / 2, amp * std::sin(2 * std::numbers::pi * f * t) + out, top - down};
  });
  PaperAnchor corners;
  corners.vertices = {g.id(0, 0), g.id(g.nx - 1, 0)};
  finish(s, corners, frames, {0.0, -0.6, 0.4}, snaps, W, L,
         "a sheet held by its two top corners, shaken at 2 Hz; its bend reverses at each turn");
}

void crumple(PaperScenario& s, const PaperScenarioOptions& o) {
  PaperAnimation& a = s.animation;
  const double W = 0.21, L = 0.297, T = o.duration > 0 ? o.duration : 3.0;
  const Grid g = make_grid(a, W, L, o.triangles);
  struct Bump {
    double x, y, radius, sign, t_snap;
  };
  Rng rng(o.seed);
  std::vector<Bump> bumps(12);
  for (auto& b : bumps) {
    b.x = rng.uniform(0.15, 0.85) * W, b.y = rng.uniform(0.15, 0.85) * L;
    b.radius = rng.uniform(0.025, 0.04);
    b.sign = rng.uniform(0, 1) < 0.5 ? -1.0 : 1.0;
    b.t_snap = rng.uniform(0.3, T - 0.2);
  }
  const auto frames = std::max<std::uint32_t>(2, frame_of(T, a.frame_rate) + 1);
  // Bumps grow with the progress of the crumpling and each snaps through once, while the
  // hands squeeze the sheet towards its centre.
  fill_frames(a, g, frames, [&](double t, double u, double v) -> Vec3 {
    const double p = 0.1 + 0.9 * (t / T), squeeze = 1.0 - 0.35 * (t / T);
    double z = 0;
    for (const Bump& b : bumps) {
      const double r2 = ((u - b.x) * (u - b.x) + (v - b.y) * (v - b.y)) / (b.radius * b.radius);
      z += 0.5 * b.radius * p * b.sign * snap(t, b.t_snap, a.frame_rate) * std::exp(-r2);
    }
    return {(u - W / 2) * squeeze, (v - L / 2) * squeeze, 0.3 + z};
  });
  PaperAnchor hands;  // the middles of the two long edges
  hands.vertices = {g.id(0, g.ny / 2), g.id(g.nx - 1, g.ny / 2)};
  std::vector<double> snaps;
  for (const Bump& b : bumps) snaps.push_back(b.t_snap);
  finish(s, hands, frames, {0.0, -0.5, 0.3}, snaps, W, L,
         "a sheet squeezed between two hands while 12 bumps grow and snap through");
}

}  // namespace

std::vector<std::string> paper_scenario_names() {
  return {"slide", "shake", "flap", "crumple"};
}

PaperScenario make_paper_scenario(const std::string& name, const PaperScenarioOptions& o) {
  if (o.triangles < 8 || o.triangles > 2000000)
    throw InputError("paper scenario: triangles must lie in [8, 2000000]");
  if (!(o.frame_rate >= 10 && o.frame_rate <= 1000))
    throw InputError("paper scenario: frame rate must lie in [10, 1000] frames/s");
  if (!(o.duration >= 0 && o.duration <= 600))
    throw InputError("paper scenario: duration must lie in [0, 600] s");
  PaperScenario s;
  s.animation.frame_rate = o.frame_rate;
  if (name == "slide") {
    slide(s, o);
  } else if (name == "flap") {
    flap(s, o);
  } else if (name == "shake") {
    shake(s, o);
  } else if (name == "crumple") {
    crumple(s, o);
  } else {
    throw InputError("unknown paper scenario '" + name + "' (slide, shake, flap, crumple)");
  }
  s.animation.description = s.description;
  s.animation.event_frames = s.event_frames;
  validate(s.animation, "paper scenario " + name);
  return s;
}

}  // namespace chladni::tools
