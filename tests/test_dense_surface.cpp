// A surface denser than the modes need is simplified before meshing, within an envelope that
// keeps its frequencies; a flat-faced solid keeps its exact shape, a curved one stays within the
// envelope, and the option turns it off.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../precompute/src/surface/simplify_surface.hpp"
#include "chladni/precompute.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "cli_support.hpp"
#include "fem_fixtures.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::precompute;

// Collapses on a curved surface: fewer triangles, still a valid solid, every vertex, edge
// midpoint and centroid within the envelope of the input (the input's own chords lie within
// 3e-5 m of the sphere at this density).
TEST(DenseSurface, SimplifiedSphereStaysWithinItsEnvelope) {
  const double r = 0.1, envelope = 5e-4;
  const SurfaceMesh dense = test::icosphere(r, 5);
  const SurfaceMesh s = simplify_surface(dense, 1500, envelope);
  EXPECT_LT(s.triangles.size(), dense.triangles.size() / 10);
  EXPECT_GE(s.triangles.size(), 1400u);
  EXPECT_TRUE(check_mesh(s).ok());
  const double chord = 3e-5;
  for (const auto& t : s.triangles) {
    const Vec3 &a = s.vertices[t[0]], &b = s.vertices[t[1]], &c = s.vertices[t[2]];
    for (const Vec3& p :
         {a, Vec3{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2},
          Vec3{(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3}})
      ASSERT_LT(std::abs(norm(p) - r), envelope + chord);
  }
}

// A box's faces are flat: collapses within them move nothing, so the volume is exact and the
// modes are the coarse box's. With --max-surface-triangles 0 the surface is kept as it is.
TEST(DenseSurface, BoxSimplifiedKeepsItsShapeAndModes) {
  const Vec3 size{0.1, 0.03, 0.02};
  const SurfaceMesh dense = test::box_surface(size, {60, 18, 12});
  ASSERT_EQ(dense.triangles.size(), 8064u);
  PrecomputeOptions o;
  o.transfer = false;
  o.max_modes = 5;
  o.max_surface_triangles = 2000;
  PrecomputeReport r;
  const Soundbank simplified = precompute_surface(dense, "dense box", o, r);
  EXPECT_EQ(r.simplified_from, 8064u);
  EXPECT_GT(r.simplify_envelope, 0.0);
  EXPECT_LE(simplified.triangles.size(), 2000u);
  SurfaceMesh kept;
  kept.vertices = simplified.vertices, kept.triangles = simplified.triangles;
  EXPECT_NEAR(test::enclosed_volume(kept), size[0] * size[1] * size[2], 1e-12);

  PrecomputeReport rc;
  const Soundbank coarse = precompute_surface(test::box_surface(size, {4, 2, 2}), "box", o, rc);
  ASSERT_EQ(rc.simplified_from, 0u);
  ASSERT_EQ(simplified.omega.size(), coarse.omega.size());
  for (std::size_t i = 0; i < coarse.omega.size(); ++i)
    EXPECT_NEAR(simplified.omega[i] / coarse.omega[i], 1.0, 2 * o.tolerance) << "mode " << i;

  o.max_surface_triangles = 0;
  o.max_passes = 1;
  PrecomputeReport rk;
  const Soundbank as_is = precompute_surface(test::box_surface(size, {20, 6, 4}), "box", o, rk);
  EXPECT_EQ(rk.simplified_from, 0u);
  EXPECT_EQ(as_is.triangles.size(), test::box_surface(size, {20, 6, 4}).triangles.size());
}

TEST(DenseSurface, CliSaysSimplifiedAndJsonCountsTheInput) {
  const std::string obj = test::temp_path("chladni_dense.obj");
  const std::string bank = test::temp_path("chladni_dense.chbank");
  const std::string json = test::temp_path("chladni_dense.json");
  write_obj(obj, test::box_surface({0.1, 0.03, 0.02}, {30, 9, 6}));
  const test::CliResult r =
      test::run_cli("precompute " + obj + " -o " + bank + " --json " + json +
                    " --max-modes 3 --no-transfer --max-surface-triangles 1000");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("(simplified from 2016 triangles, within"), std::string::npos)
      << r.output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_EQ(j["surface"]["simplified_from"], 2016);
  EXPECT_LE(j["surface"]["triangles"].get<int>(), 1000);
  // The soundbank says its surface is not the file's.
  const test::CliResult info = test::run_cli("info " + bank + " --json");
  ASSERT_EQ(info.code, 0) << info.output;
  const nlohmann::json meta = nlohmann::json::parse(info.output)["metadata"];
  EXPECT_EQ(meta["surface_simplified"]["from_triangles"], 2016);
  EXPECT_EQ(nlohmann::json::parse(info.output)["surface"]["triangles"], j["surface"]["triangles"]);
}
