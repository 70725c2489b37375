// Mesh file input and output through CGAL's polygon-soup readers (one of the two CGAL units).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "chladni/core/error.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute {

namespace {

// CGAL's OBJ reader only says yes or no; this pass names the first bad line instead.
void check_obj_lines(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::size_t lineno = 0, vertices = 0;
  std::vector<std::pair<std::size_t, long>> refs;  // (line, index) of face corners
  auto fail = [&](const std::string& what) {
    throw InputError(path + ":" + std::to_string(lineno) + ": " + what);
  };
  while (std::getline(f, line)) {
    ++lineno;
    std::istringstream in(line);
    std::string tag;
    if (!(in >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      for (int k = 0; k < 3; ++k) {
        std::string tok;
        if (!(in >> tok)) fail("vertex has fewer than 3 coordinates");
        char* end = nullptr;
        const double x = std::strtod(tok.c_str(), &end);
        if (end != tok.c_str() + tok.size()) fail("'" + tok + "' is not a number");
        if (!std::isfinite(x)) fail("vertex coordinate '" + tok + "' is not finite");
      }
      ++vertices;
    } else if (tag == "f") {
      std::string tok;
      int corners = 0;
      while (in >> tok) {
        char* end = nullptr;
        const long idx = std::strtol(tok.c_str(), &end, 10);
        if (end == tok.c_str() || (*end != '\0' && *end != '/'))
          fail("'" + tok + "' is not a vertex index");
        if (idx == 0) fail("vertex index 0 (OBJ counts from 1)");
        refs.emplace_back(lineno, idx < 0 ? long(vertices) + idx + 1 : idx);
        ++corners;
      }
      if (corners < 3) fail("face has fewer than 3 corners");
    }
  }
  for (const auto& [l, idx] : refs) {
    if (idx < 1 || std::size_t(idx) > vertices) {
      lineno = l;
      fail("face refers to vertex " + std::to_string(idx) + " but the file has " +
           std::to_string(vertices));
    }
  }
}

}  // namespace

double unit_scale(const std::string& unit) {
  if (unit == "m") return 1.0;
  if (unit == "cm") return 0.01;
  if (unit == "mm") return 0.001;
  throw InputError("unit '" + unit + "': expected m, cm or mm");
}

SurfaceMesh read_mesh(const std::string& path, double scale) {
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  if (!std::isfinite(scale) || !(scale > 0)) throw InputError("--scale must be finite and > 0");
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": no such mesh file");
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    throw InputError(path + ": unsupported mesh format '" + ext + "' (use OBJ, OFF, PLY or STL)");

  if (ext == ".obj") check_obj_lines(path);
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  bool ok = false;
  try {
    ok = CGAL::IO::read_polygon_soup(path, points, polygons, CGAL::parameters::verbose(false));
  } catch (const std::exception& e) {
    throw InputError(path + ": cannot parse as " + ext.substr(1) + " (" + e.what() + ")");
  }
  if (!ok)
    throw InputError(path + ": cannot parse as " + ext.substr(1) + " (CGAL's reader rejected it)");
  if (polygons.empty()) throw InputError(path + ": holds no faces");

  SurfaceMesh m;
  m.vertices.reserve(points.size());
  for (std::size_t v = 0; v < points.size(); ++v) {
    const Point& p = points[v];
    const Vec3 q{p.x() * scale, p.y() * scale, p.z() * scale};
    if (!is_finite(q))
      throw InputError(path + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
    m.vertices.push_back(q);
  }
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    const auto& poly = polygons[f];
    if (poly.size() < 3)
      throw InputError(path + ": face " + std::to_string(f) + " has " +
                       std::to_string(poly.size()) + " corners");
    for (std::size_t idx : poly)
      if (idx >= points.size())
        throw InputError(path + ": face " + std::to_string(f) + " refers to vertex " +
                         std::to_string(idx) + " but the file has " +
                         std::to_string(points.size()));
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)  // fan triangulation
      m.triangles.push_back({uint32_t(poly[0]), uint32_t(poly[k]), uint32_t(poly[k + 1])});
  }
  return m;
}

void write_obj(const std::string& path, const SurfaceMesh& mesh) {
  std::ofstream f(path);
  if (!f) throw InputError("cannot write " + path);
  f << std::setprecision(17);
  for (const Vec3& v : mesh.vertices) f << "v " << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (const auto& t : mesh.triangles)
    f << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  if (!f.flush()) throw InputError("cannot write " + path);
}

}  // namespace chladni::precompute
