// Wavefront OBJ: 'v x y z' vertices and 'f' polygons (a, a/t, a/t/n, a//n; negative indices
// count back from the last vertex). Other statements (vt, vn, g, o, s, usemtl, ...) are ignored.
#include <algorithm>
#include <limits>

#include "mesh_text.hpp"

namespace chladni::precompute::mesh_io {

SurfaceMesh read_obj(std::string_view text, const std::string& path) {
  constexpr long long kMaxIndex = std::numeric_limits<uint32_t>::max();
  SurfaceMesh m;
  // Indices may refer forward, so they are checked at the end; each face keeps its line.
  std::vector<std::pair<std::size_t, std::size_t>> face_lines;  // (first triangle, line)
  std::vector<uint32_t> corners;
  Tokens t(text, path);
  std::string_view tag;
  while (t.next(tag)) {
    if (tag == "v") {
      Vec3 p{};
      for (double& c : p) c = t.number(t.expect_on_line("3 vertex coordinates"), "coordinate");
      m.vertices.push_back(p);
    } else if (tag == "f") {
      corners.clear();
      std::string_view tok;
      while (t.next_on_line(tok)) {
        const std::string_view head = tok.substr(0, tok.find('/'));
        const long long idx = t.integer(head, "vertex index", -kMaxIndex, kMaxIndex);
        if (idx == 0) t.fail("vertex index 0 (OBJ counts from 1)");
        const long long resolved = idx < 0 ? (long long)m.vertices.size() + idx : idx - 1;
        if (resolved < 0)
          t.fail("relative vertex index " + std::to_string(idx) + " reaches before the first of " +
                 std::to_string(m.vertices.size()) + " vertices");
        corners.push_back(uint32_t(resolved));
      }
      face_lines.emplace_back(m.triangles.size(), t.line());
      add_polygon(m, corners, path + ":" + std::to_string(t.line()));
    }
    t.skip_line();
  }
  for (std::size_t k = 0; k < m.triangles.size(); ++k) {
    const auto bad = std::find_if(m.triangles[k].begin(), m.triangles[k].end(),
                                  [&](uint32_t v) { return v >= m.vertices.size(); });
    if (bad == m.triangles[k].end()) continue;
    const auto face =
        std::upper_bound(face_lines.begin(), face_lines.end(), std::make_pair(k, ~std::size_t(0)));
    throw InputError(path + ":" + std::to_string(std::prev(face)->second) +
                     ": face refers to vertex " + std::to_string(std::size_t(*bad) + 1) +
                     " but the file has " + std::to_string(m.vertices.size()));
  }
  return m;
}

}  // namespace chladni::precompute::mesh_io
