// The repair ladder on meshes scaled to a given size: per mesh the rung used, its seconds, how
// far the surface moved, the volume change, or the refusal (docs/repair.md).
//   chladni_repair_bench [--size M] [--alpha M] [--offset M] MESH...
#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "chladni/precompute/mesh_repair.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

struct Args {
  double size = 0.2;  // bounding-box diagonal after scaling, m
  RepairOptions options;
  std::vector<std::string> meshes;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    auto value = [&] {
      if (i + 1 >= argc) throw std::runtime_error(std::string(argv[i]) + " needs a value");
      return std::stod(argv[++i]);
    };
    if (!std::strcmp(argv[i], "--size"))
      a.size = value();
    else if (!std::strcmp(argv[i], "--alpha"))
      a.options.wrap_alpha = value();
    else if (!std::strcmp(argv[i], "--offset"))
      a.options.wrap_offset = value();
    else
      a.meshes.push_back(argv[i]);
  }
  if (a.meshes.empty())
    throw std::runtime_error(
        "usage: chladni_repair_bench [--size M] [--alpha M] [--offset M] MESH...");
  return a;
}

// The mesh read and scaled so that its bounding-box diagonal is `size`.
SurfaceMesh scaled(const std::string& path, double size) {
  SurfaceMesh m = read_mesh(path);
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const Vec3& v : m.vertices)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  const double s = size / norm(sub(hi, lo));
  for (Vec3& v : m.vertices) v = scale(v, s);
  return m;
}

nlohmann::json run_one(const std::string& path, const Args& a) {
  SurfaceMesh m = scaled(path, a.size);
  const std::size_t triangles = m.triangles.size();
  const MeshReport before = check_mesh(m);
  const auto t0 = bench::clock_type::now();
  const RepairReport r = repair_mesh(m, a.options);
  const double seconds = bench::seconds_since(t0);
  nlohmann::json j = {{"mesh", path},
                      {"triangles", triangles},
                      {"valid_as_given", before.ok()},
                      {"seconds", seconds},
                      {"rung", to_string(r.rung)},
                      {"refusal", r.refusal},
                      {"hausdorff_m", r.hausdorff},
                      {"hausdorff_of_size", r.hausdorff / r.size},
                      {"input_to_repaired_m", r.to_repaired},
                      {"repaired_to_input_m", r.to_input},
                      {"volume_change", r.volume_change()},
                      {"alpha_m", r.alpha},
                      {"offset_m", r.offset},
                      {"thinnest_wall_m", r.thinnest},
                      {"triangles_after", m.triangles.size()},
                      {"valid_after", check_mesh(m).ok()},
                      {"log", r.log}};
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  const Args a = bench::parse_or_exit(parse, argc, argv);
  nlohmann::json out = nlohmann::json::array();
  for (const std::string& path : a.meshes) {
    nlohmann::json j;
    try {
      j = run_one(path, a);
    } catch (const std::exception& e) {
      j = {{"mesh", path}, {"error", e.what()}};
    }
    std::fprintf(stderr, "%s\n", j.dump().c_str());
    out.push_back(j);
  }
  std::printf("%s\n", out.dump(2).c_str());
}
