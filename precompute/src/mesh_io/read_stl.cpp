// STL, binary (80-byte header, triangle count, 50 bytes per triangle) or ASCII ("solid ...
// facet normal ... outer loop vertex x y z ... endloop endfacet ... endsolid"). STL stores each
// triangle's corners separately; corners with identical coordinates become one vertex, as the
// solid's connectivity requires.
#include <bit>
#include <cstring>
#include <unordered_map>

#include "mesh_text.hpp"

namespace chladni::precompute::mesh_io {

namespace {

struct Welder {
  struct Hash {
    std::size_t operator()(const Vec3& p) const {
      std::size_t h = 0;
      for (double c : p) h = h * 1000003u ^ std::hash<double>()(c + 0.0);  // +0.0: -0 == 0
      return h;
    }
  };
  SurfaceMesh mesh;
  std::unordered_map<Vec3, uint32_t, Hash> index;
  uint32_t vertex(const Vec3& p) {
    const Vec3 q{p[0] + 0.0, p[1] + 0.0, p[2] + 0.0};
    const auto [it, added] = index.try_emplace(q, uint32_t(mesh.vertices.size()));
    if (added) mesh.vertices.push_back(q);
    return it->second;
  }
};

float le_float(const char* p) {
  uint32_t u = 0;
  for (int k = 0; k < 4; ++k) u |= uint32_t(uint8_t(p[k])) << (8 * k);
  return std::bit_cast<float>(u);
}

SurfaceMesh read_binary(std::string_view bytes, const std::string& path, uint32_t count) {
  Welder w;
  for (uint32_t t = 0; t < count; ++t) {
    const char* rec = bytes.data() + 84 + std::size_t(t) * 50 + 12;  // skip the normal
    std::vector<uint32_t> corners(3);
    for (int c = 0; c < 3; ++c) {
      const Vec3 p{le_float(rec + 12 * c), le_float(rec + 12 * c + 4), le_float(rec + 12 * c + 8)};
      if (!is_finite(p))
        throw InputError(path + ": triangle " + std::to_string(t) + " has a non-finite corner");
      corners[std::size_t(c)] = w.vertex(p);
    }
    add_polygon(w.mesh, corners, path + ": triangle " + std::to_string(t));
  }
  return std::move(w.mesh);
}

SurfaceMesh read_ascii(std::string_view text, const std::string& path) {
  Tokens t(text, path);
  auto expect_word = [&](std::string_view word) {
    const std::string_view tok = t.expect(word.data());
    if (tok != word)
      t.fail("expected '" + std::string(word) + "', found '" + std::string(tok) + "'");
  };
  expect_word("solid");
  t.skip_line();  // the solid's name
  Welder w;
  std::vector<uint32_t> corners;
  for (;;) {
    const std::string_view tok = t.expect("'facet' or 'endsolid'");
    if (tok == "endsolid") break;
    if (tok != "facet") t.fail("expected 'facet' or 'endsolid', found '" + std::string(tok) + "'");
    expect_word("normal");
    for (int k = 0; k < 3; ++k) t.number(t.expect("a normal component"), "normal component");
    expect_word("outer");
    expect_word("loop");
    corners.clear();
    for (std::string_view v = t.expect("'vertex'"); v != "endloop"; v = t.expect("'vertex'")) {
      if (v != "vertex") t.fail("expected 'vertex' or 'endloop', found '" + std::string(v) + "'");
      Vec3 p{};
      for (double& c : p) c = t.number(t.expect("a coordinate"), "coordinate");
      corners.push_back(w.vertex(p));
    }
    add_polygon(w.mesh, corners, path + ":" + std::to_string(t.line()));
    expect_word("endfacet");
  }
  return std::move(w.mesh);
}

}  // namespace

SurfaceMesh read_stl(std::string_view bytes, const std::string& path) {
  // A binary file's size follows from its count; an ASCII one starts with "solid" (so may a
  // binary header, which is why the size is tried first).
  if (bytes.size() >= 84) {
    uint32_t count = 0;
    for (int k = 0; k < 4; ++k) count |= uint32_t(uint8_t(bytes[80 + std::size_t(k)])) << (8 * k);
    if (bytes.size() == 84 + uint64_t(count) * 50) return read_binary(bytes, path, count);
  }
  // Text has no NUL bytes; a binary count below 2^24 always has one.
  const std::size_t a = bytes.find_first_not_of(" \t\r\n");
  if (a != std::string_view::npos && bytes.substr(a, 5) == "solid" &&
      bytes.find('\0') == std::string_view::npos)
    return read_ascii(bytes, path);
  if (bytes.size() >= 84) {
    uint32_t count = 0;
    for (int k = 0; k < 4; ++k) count |= uint32_t(uint8_t(bytes[80 + std::size_t(k)])) << (8 * k);
    throw InputError(
        path + ": not ASCII STL (no 'solid') and not binary STL: " + std::to_string(bytes.size()) +
        " bytes where a header counting " + std::to_string(count) + " triangles needs " +
        std::to_string(84 + uint64_t(count) * 50) + " (truncated?)");
  }
  throw InputError(path + ": not an STL file (too short for binary, no 'solid' for ASCII)");
}

}  // namespace chladni::precompute::mesh_io
