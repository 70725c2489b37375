// Mesh file input and output. The readers are our own (mesh_text.hpp and read_*.cpp) rather than
// CGAL's, which crash or allocate without bound on malformed headers and cannot say which line
// or element is wrong.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"
#include "chladni/core/output_file.hpp"
#include "mesh_text.hpp"

namespace chladni::precompute {

double unit_scale(const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "cm") return 0.01;
  if (unit == "mm") return 0.001;
  throw InputError("unit '" + unit + "': expected m, cm or mm");
}

SurfaceMesh read_mesh(const std::string& path, double scale) {
  if (!std::isfinite(scale) || !(scale > 0)) throw InputError("--scale must be finite and > 0");
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    throw InputError(path + ": unsupported mesh format '" + ext + "' (use OBJ, OFF, PLY or STL)");
  const std::vector<uint8_t> raw = read_input_file(path, "mesh", kMaxBinaryInputBytes);
  std::string_view bytes(reinterpret_cast<const char*>(raw.data()), raw.size());
  // A byte-order mark (Windows editors) would glue onto the first keyword. Not for STL, whose
  // binary header may begin with any bytes.
  if (ext != ".stl" && bytes.starts_with("\xEF\xBB\xBF")) bytes.remove_prefix(3);

  SurfaceMesh m = ext == ".obj"   ? mesh_io::read_obj(bytes, path)
                  : ext == ".off" ? mesh_io::read_off(bytes, path)
                  : ext == ".ply" ? mesh_io::read_ply(bytes, path)
                                  : mesh_io::read_stl(bytes, path);
  if (m.triangles.empty()) throw InputError(path + ": holds no faces");
  if (m.vertices.size() > std::size_t(UINT32_MAX))
    throw InputError(path + ": more than 2^32 - 1 vertices");
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    Vec3& p = m.vertices[v];
    for (double& c : p) c *= scale;
    if (!is_finite(p))
      throw InputError(path + ": vertex " + std::to_string(v) + " is not finite once scaled");
  }
  return m;
}

void write_obj(const std::string& path, const SurfaceMesh& mesh) {
  std::ostringstream f;
  f << std::setprecision(17);
  for (const Vec3& v : mesh.vertices) f << "v " << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (const auto& t : mesh.triangles)
    f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  write_file_atomic(path, f.str(), "mesh");
}

}  // namespace chladni::precompute
