// Object File Format: an optional OFF/COFF/NOFF/STOFF... keyword, then "nv nf ne", nv vertex
// lines (the first three numbers are the position; colours, normals and texture coordinates
// after them are skipped) and nf lines "n i_1 ... i_n [colour]". '#' starts a comment.
#include <limits>

#include "mesh_text.hpp"

namespace chladni::precompute::mesh_io {

namespace {

// The text with comments blanked out (keeping line ends), since they may follow any value.
std::string without_comments(std::string_view text) {
  std::string s(text);
  bool comment = false;
  for (char& c : s) {
    if (c == '\n')
      comment = false;
    else if (c == '#')
      comment = true;
    if (comment) c = ' ';
  }
  return s;
}

}  // namespace

SurfaceMesh read_off(std::string_view raw, const std::string& path) {
  const std::string text = without_comments(raw);
  Tokens t(text, path);
  std::string_view tok = t.expect("the OFF header");
  if (tok.size() >= 3 && tok.substr(tok.size() - 3) == "OFF") {
    if (tok.find_first_not_of("STCN4n") < tok.size() - 3)
      t.fail("unknown OFF keyword '" + std::string(tok) + "'");
    if (tok.find_first_of("4n") < tok.size() - 3)
      t.fail("'" + std::string(tok) + "': only 3-D OFF files are supported");
    std::string_view next;
    if (t.next_on_line(next) && next == "BINARY") t.fail("binary OFF is not supported");
    if (!next.empty()) t.fail("unexpected '" + std::string(next) + "' after the keyword");
    tok = t.expect("the vertex count");
  }
  // Each vertex or face takes at least two bytes, so a count beyond the file size is a lie.
  const long long most = (long long)(text.size() / 2 + 1);
  const auto nv = std::size_t(t.integer(tok, "vertex count", 0, most));
  const auto nf = std::size_t(t.integer(t.expect("the face count"), "face count", 0, most));
  t.integer(t.expect("the edge count"), "edge count", 0, std::numeric_limits<long long>::max());
  t.skip_line();

  SurfaceMesh m;
  m.vertices.reserve(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    if (t.at_end())
      t.fail("the file ends after " + std::to_string(v) + " of " + std::to_string(nv) +
             " vertices");
    Vec3 p{};
    for (double& c : p) c = t.number(t.expect_on_line("3 vertex coordinates"), "coordinate");
    m.vertices.push_back(p);
    t.skip_line();
  }
  std::vector<uint32_t> corners;
  for (std::size_t f = 0; f < nf; ++f) {
    if (t.at_end())
      t.fail("the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    const auto n =
        std::size_t(t.integer(t.expect_on_line("a corner count"), "corner count", 0, most));
    corners.clear();
    for (std::size_t k = 0; k < n; ++k)
      corners.push_back(uint32_t(
          t.integer(t.expect_on_line("a vertex index"), "vertex index", 0, (long long)nv - 1)));
    add_polygon(m, corners, path + ":" + std::to_string(t.line()));
    t.skip_line();
  }
  if (!t.at_end()) t.fail("unexpected content after the " + std::to_string(nf) + " faces");
  return m;
}

}  // namespace chladni::precompute::mesh_io
