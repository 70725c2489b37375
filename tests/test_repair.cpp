// The repair ladder on inputs made to fail each check: every result is a valid solid within the
// distance it reports, or a refusal that names the reason.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chladni/precompute.hpp"
#include "chladni/precompute/mesh_repair.hpp"
#include "cli_support.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

SurfaceMesh moved(SurfaceMesh m, const Vec3& by) {
  for (Vec3& v : m.vertices) v = add(v, by);
  return m;
}

double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Closest point by projection onto the plane when inside, else onto the nearest edge.
  const Vec3 n = triangle_normal(a, b, c);
  const double nn = dot(n, n);
  const Vec3 q = sub(p, scale(n, dot(sub(p, a), n) / nn));
  const bool inside = dot(cross(sub(b, a), sub(q, a)), n) >= 0 &&
                      dot(cross(sub(c, b), sub(q, b)), n) >= 0 &&
                      dot(cross(sub(a, c), sub(q, c)), n) >= 0;
  if (inside) return norm(sub(p, q));
  auto seg = [&](const Vec3& u, const Vec3& v) {
    const Vec3 d = sub(v, u);
    const double t = std::clamp(dot(sub(p, u), d) / dot(d, d), 0.0, 1.0);
    return norm(sub(p, add(u, scale(d, t))));
  };
  return std::min({seg(a, b), seg(b, c), seg(c, a)});
}

// Brute force: the farthest vertex of `from` from the surface `to`.
double farthest_vertex(const SurfaceMesh& from, const SurfaceMesh& to) {
  double worst = 0;
  for (const Vec3& p : from.vertices) {
    double best = INFINITY;
    for (const auto& t : to.triangles)
      best = std::min(best, point_triangle_distance(p, to.vertices[t[0]], to.vertices[t[1]],
                                                    to.vertices[t[2]]));
    worst = std::max(worst, best);
  }
  return worst;
}

// A repaired result is a valid solid whose every vertex lies within the reported distance of
// the input; the reported distance is small against the object.
void expect_solid_within_report(const SurfaceMesh& input, const SurfaceMesh& out,
                                const RepairReport& r, double max_fraction) {
  ASSERT_TRUE(r.refusal.empty()) << r.refusal;
  const MeshReport c = check_mesh(out);
  EXPECT_TRUE(c.ok()) << (c.problems().empty() ? "" : c.problems().front());
  EXPECT_LE(farthest_vertex(out, input), r.to_input * 1.0001 + 1e-12);
  EXPECT_LE(r.hausdorff, max_fraction * r.size);
  EXPECT_NEAR(r.volume_repaired, c.volume, 1e-12);
}

const SurfaceMesh kCube = test::box_surface({0.1, 0.1, 0.1}, {4, 4, 4});

}  // namespace

TEST(RepairLadder, ValidSolidIsLeftAlone) {
  SurfaceMesh m = kCube;
  const RepairReport r = repair_mesh(m);
  EXPECT_EQ(r.rung, RepairRung::None);
  EXPECT_TRUE(r.log.empty());
  EXPECT_EQ(m.triangles, kCube.triangles);
}

// A box pushed through a box (a teapot's spout through its body): the union, wrapped as one.
TEST(RepairLadder, OverlappingPartsBecomeTheirUnion) {
  const SurfaceMesh bar =
      moved(test::box_surface({0.04, 0.04, 0.2}, {2, 2, 8}), {0.03, 0.03, -0.05});
  const SurfaceMesh input = test::with_piece(kCube, bar, false);
  SurfaceMesh m = input;
  const RepairReport r = repair_mesh(m);
  const double cube = 1e-3, rod = 0.04 * 0.04 * 0.2, shared = 0.04 * 0.04 * 0.1;
  EXPECT_NEAR(r.volume_input, cube + rod - shared, 0.01 * cube);  // the union, not the sum
  expect_solid_within_report(input, m, r, 0.03);
  EXPECT_LE(r.hausdorff, r.alpha);  // the ball rounds the concave edges where they meet
  EXPECT_EQ(check_mesh(m).components, 1u);
  EXPECT_NEAR(r.volume_repaired, cube + rod - shared, 0.03 * cube);
}

// Two cubes sharing an edge: non-manifold once their vertices merge, each part a solid, joined
// by the wrap, whose ball fills the notch along the edge by about alpha.
TEST(RepairLadder, NonManifoldEdgeBecomesOneBody) {
  SurfaceMesh input = test::with_piece(kCube, moved(kCube, {0.1, 0.1, 0}), false);
  SurfaceMesh m = input;
  const RepairReport r = repair_mesh(m);
  expect_solid_within_report(input, m, r, 0.05);
  EXPECT_EQ(r.rung, RepairRung::Wrap);
  EXPECT_LE(r.to_input, 1.5 * r.alpha);
  EXPECT_NEAR(r.volume_repaired, 2e-3, 0.05 * 2e-3);
}

// A ball with a hole too large for rung 1: closed by the wrap when alpha spans it, refused as
// an open sheet when it does not.
TEST(RepairLadder, OpenSurfaceIsClosedOrRefusedAsASheet) {
  const SurfaceMesh ball = test::icosphere(0.05, 3);
  const auto cut = [&](double z) {
    SurfaceMesh out = ball;
    out.triangles.clear();
    for (const auto& t : ball.triangles)
      if (std::max({ball.vertices[t[0]][2], ball.vertices[t[1]][2], ball.vertices[t[2]][2]}) < z)
        out.triangles.push_back(t);
    return out;
  };
  RepairOptions o;
  o.max_hole_edges = 3;                   // leave the holes to the wrap
  const SurfaceMesh holed = cut(0.0495);  // a cap of about 14 mm across
  ASSERT_GT(check_mesh(holed).boundary_edges, 3u);
  SurfaceMesh m = holed;
  o.wrap_alpha = 0.008;  // a ball wider than the hole
  RepairReport r = repair_mesh(m, o);
  expect_solid_within_report(holed, m, r, 0.2);
  EXPECT_EQ(r.rung, RepairRung::Wrap);
  EXPECT_FALSE(r.input_closed);
  EXPECT_NEAR(r.volume_repaired, 4.0 / 3 * M_PI * std::pow(0.05, 3), 0.05 * 5.2e-4);

  m = cut(0.0);  // a hemispherical cup of no thickness, its rim left open
  o.wrap_alpha = 0;
  r = repair_mesh(m, o);
  EXPECT_NE(r.refusal.find("encloses no volume: an open sheet"), std::string::npos) << r.refusal;
}

// Parameters that would make a wrap of millions of triangles are refused before it is made.
TEST(RepairLadder, WrapParametersOutOfRangeAreRefused) {
  SurfaceMesh m = test::with_piece(kCube, moved(kCube, {0.1, 0.1, 0}), false);
  RepairOptions o;
  o.wrap_alpha = 1e-5;
  RepairReport r = repair_mesh(m, o);
  EXPECT_NE(r.refusal.find("--repair-alpha 1e-05 m lies outside ["), std::string::npos)
      << r.refusal;
  o.wrap_alpha = 0, o.wrap_offset = 1e-9;
  r = repair_mesh(m, o);
  EXPECT_NE(r.refusal.find("--repair-offset 1e-09 m lies outside ["), std::string::npos)
      << r.refusal;
}

TEST(RepairLadder, FlatSheetIsRefusedAsFlat) {
  SurfaceMesh card;
  card.vertices = {{0, 0, 0}, {0.1, 0, 0}, {0.1, 0.1, 0}, {0, 0.1, 0}};
  card.triangles = {{0, 1, 2}, {0, 2, 3}};
  SurfaceMesh m = card;
  RepairReport r = repair_mesh(m);
  EXPECT_NE(r.refusal.find("encloses no volume: all 4 vertices lie in one plane"),
            std::string::npos)
      << r.refusal;
  // A closed, manifold pillow of no thickness: still flat. The check says so, not "inward".
  card.vertices.push_back({0.05, 0.05, 0});  // 4: the top's centre
  card.vertices.push_back({0.05, 0.05, 0});  // 5: the bottom's
  card.triangles.clear();
  for (uint32_t k = 0; k < 4; ++k) {
    card.triangles.push_back({4, k, (k + 1) % 4});
    card.triangles.push_back({5, (k + 1) % 4, k});
  }
  const auto problems = check_mesh(card).problems();
  EXPECT_TRUE(std::any_of(problems.begin(), problems.end(), [](const std::string& p) {
    return p.find("encloses no volume") != std::string::npos;
  })) << (problems.empty() ? "" : problems.front());
  m = card;
  r = repair_mesh(m);
  EXPECT_NE(r.refusal.find("lie in one plane"), std::string::npos) << r.refusal;
}

TEST(RepairLadder, DisjointPartsAreRefusedWithTheirVolumes) {
  SurfaceMesh m = test::with_piece(kCube, moved(kCube, {0.5, 0, 0}), false);
  const RepairReport r = repair_mesh(m);
  EXPECT_NE(r.refusal.find("2 separate parts that do not touch"), std::string::npos) << r.refusal;
  EXPECT_NE(r.refusal.find("volume 0.001 m^3"), std::string::npos) << r.refusal;
  // Debris far under the largest part's volume is dropped, not refused.
  m = test::with_piece(
      kCube, moved(test::box_surface({0.005, 0.005, 0.005}, {1, 1, 1}), {0.5, 0, 0}), false);
  const RepairReport d = repair_mesh(m);
  EXPECT_TRUE(d.refusal.empty()) << d.refusal;
  EXPECT_EQ(m.triangles.size(), kCube.triangles.size());
}

// Self-intersecting: a box whose top is pushed below its bottom, folding the sides through it.
TEST(RepairLadder, SelfIntersectingSoupBecomesASolidOrIsRefused) {
  SurfaceMesh input = test::box_surface({0.1, 0.1, 0.1}, {2, 2, 2});
  for (Vec3& v : input.vertices)
    if (v[2] > 0.099 && v[0] > 0.01 && v[0] < 0.09) v[2] = -0.03;  // the top's middle row
  ASSERT_GT(check_mesh(input).self_intersections, 0u);
  SurfaceMesh m = input;
  const RepairReport r = repair_mesh(m);
  // The fold leaves faces crossing and sheets doubled on themselves: which reading holds is
  // the ladder's to say, but a result must be a solid within its report and a refusal must
  // give one of the reasons the ladder measures.
  if (r.refusal.empty())
    expect_solid_within_report(input, m, r, 0.1);
  else
    EXPECT_TRUE(r.refusal.find("the wrap would move the surface") != std::string::npos ||
                r.refusal.find("open sheet with no thickness") != std::string::npos)
        << r.refusal;
}

// The wrapped solid rings like the clean one: a bar made of two overlapping halves against the
// bar meshed directly, first elastic modes within 2 %.
TEST(RepairLadder, WrappedBarRingsLikeTheCleanBar) {
  const SurfaceMesh clean = test::box_surface({0.3, 0.03, 0.02}, {30, 3, 2});
  const SurfaceMesh half = test::box_surface({0.17, 0.03, 0.02}, {17, 3, 2});
  const SurfaceMesh broken = test::with_piece(half, moved(half, {0.13, 0, 0}), false);
  PrecomputeOptions o;
  o.max_modes = 6;
  o.transfer = false;
  o.repair = true;
  PrecomputeReport rc, rb;
  const Soundbank a = precompute_surface(clean, "clean", o, rc);
  const Soundbank b = precompute_surface(broken, "broken", o, rb);
  EXPECT_EQ(rb.repair.rung, RepairRung::Wrap);
  ASSERT_EQ(a.mode_count(), 6u);
  ASSERT_EQ(b.mode_count(), 6u);
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(b.omega[i] / a.omega[i], 1.0, 0.02) << i;
}

// The command line: a refusal names the file and the reason, exits 2 and writes nothing; a wrap
// is reported in the summary, the JSON and `chladni info`.
TEST(RepairLadder, CliRefusesWithTheReasonAndReportsTheWrap) {
  const std::string bank =
      test::temp_path("chladni_repair_" + std::to_string(::getpid()) + ".chbank");
  std::remove(bank.c_str());
  SurfaceMesh card;
  card.vertices = {{0, 0, 0}, {0.1, 0, 0}, {0.1, 0.1, 0}, {0, 0.1, 0}};
  card.triangles = {{0, 1, 2}, {0, 2, 3}};
  const std::string flat = test::temp_path("chladni_card_" + std::to_string(::getpid()) + ".obj");
  write_obj(flat, card);
  test::CliResult r = test::run_cli("precompute " + flat + " -o " + bank + " --repair");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(flat + ": --repair cannot make a valid solid of it: encloses no volume"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::ifstream(bank).good());

  const SurfaceMesh bar =
      moved(test::box_surface({0.04, 0.04, 0.2}, {2, 2, 8}), {0.03, 0.03, -0.05});
  const std::string cross = test::temp_path("chladni_cross_" + std::to_string(::getpid()) + ".obj");
  write_obj(cross, test::with_piece(kCube, bar, false));
  const std::string json = test::temp_path("chladni_cross_" + std::to_string(::getpid()) + ".json");
  r = test::run_cli("precompute " + cross + " -o " + bank + " --json " + json +
                    " --repair --order 1 --max-modes 4 --max-tet-volume 2e-6 --no-transfer");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("  repair (wrap): the surface moved up to"), std::string::npos)
      << r.output;
  const auto j = nlohmann::json::parse(test::read_file(json));
  EXPECT_EQ(j["repair"]["rung"], "wrap");
  EXPECT_GT(j["repair"]["hausdorff_m"].get<double>(), 0.0);
  EXPECT_LT(j["repair"]["hausdorff_m"].get<double>(), 0.01);
  EXPECT_GT(j["repair"]["wrap"]["alpha_m"].get<double>(), 0.0);
  r = test::run_cli("info " + bank);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("repair    wrap (alpha "), std::string::npos) << r.output;
}
