#pragma once
// Shared pieces of the mesh readers: a whitespace tokenizer that knows its line, strict number
// parsing, and polygon fan triangulation with index checks. Every error names the file and the
// line (text formats) or the element (binary formats).
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/precompute/surface_mesh.hpp"

namespace chladni::precompute::mesh_io {

/// Tokens of a text, separated by spaces, tabs and line ends (CR LF too).
class Tokens {
 public:
  Tokens(std::string_view text, std::string path, std::size_t first_line = 1)
      : text_(text), path_(std::move(path)), line_(first_line) {}

  /// The next token on any line; false at the end of the text.
  bool next(std::string_view& tok) {
    skip_space(true);
    if (pos_ >= text_.size()) return false;
    const std::size_t a = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_])) ++pos_;
    tok = text_.substr(a, pos_ - a);
    return true;
  }
  /// The next token on the current line; false at a line end (which is not consumed).
  bool next_on_line(std::string_view& tok) {
    skip_space(false);
    if (pos_ >= text_.size() || text_[pos_] == '\n') return false;
    return next(tok);
  }
  /// Skips the rest of the current line, including its line end.
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    if (pos_ < text_.size()) ++pos_, ++line_;
  }
  bool at_end() {
    skip_space(true);
    return pos_ >= text_.size();
  }
  std::size_t line() const { return line_; }
  std::size_t offset() const { return pos_; }

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_ + ":" + std::to_string(line_) + ": " + what);
  }
  /// A finite number token (a leading '+' is allowed, as C's strtod does).
  double number(std::string_view tok, const char* what) const {
    if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
    double x = 0;
    const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
    if (ec == std::errc::result_out_of_range)
      fail(std::string(what) + " '" + std::string(tok) + "' is out of range");
    if (ec != std::errc() || end != tok.data() + tok.size())
      fail(std::string(what) + " '" + std::string(tok) + "' is not a number");
    if (!std::isfinite(x)) fail(std::string(what) + " '" + std::string(tok) + "' is not finite");
    return x;
  }
  /// A whole-number token in [lo, hi].
  long long integer(std::string_view tok, const char* what, long long lo, long long hi) const {
    if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
    long long x = 0;
    const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
    if (ec != std::errc() || end != tok.data() + tok.size())
      fail(std::string(what) + " '" + std::string(tok) + "' is not a whole number");
    if (x < lo || x > hi)
      fail(std::string(what) + " " + std::to_string(x) + " is outside [" + std::to_string(lo) +
           ", " + std::to_string(hi) + "]");
    return x;
  }
  /// The next token on the current line, or a failure saying what was expected.
  std::string_view expect_on_line(const char* what) {
    std::string_view tok;
    if (!next_on_line(tok)) fail(std::string("expected ") + what + " before the line ends");
    return tok;
  }
  /// The next token anywhere, or a failure saying what was expected.
  std::string_view expect(const char* what) {
    std::string_view tok;
    if (!next(tok)) fail(std::string("the file ends where ") + what + " was expected");
    return tok;
  }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
  }
  void skip_space(bool lines) {
    while (pos_ < text_.size() && is_space(text_[pos_])) {
      if (text_[pos_] == '\n') {
        if (!lines) return;
        ++line_;
      }
      ++pos_;
    }
  }
  std::string_view text_;
  std::string path_;
  std::size_t pos_ = 0, line_;
};

/// Appends polygon `corners` (0-based, already checked < vertex count) as a triangle fan.
/// Fails with `where` when it has fewer than three corners.
inline void add_polygon(SurfaceMesh& m, const std::vector<uint32_t>& corners,
                        const std::string& where) {
  if (corners.size() < 3)
    throw InputError(where + ": a face needs at least 3 corners, this one has " +
                     std::to_string(corners.size()));
  for (std::size_t k = 1; k + 1 < corners.size(); ++k)
    m.triangles.push_back({corners[0], corners[k], corners[k + 1]});
}

// One reader per format: the whole file's bytes in, the surface out (coordinates unscaled).
SurfaceMesh read_obj(std::string_view text, const std::string& path);
SurfaceMesh read_off(std::string_view text, const std::string& path);
SurfaceMesh read_ply(std::string_view bytes, const std::string& path);
SurfaceMesh read_stl(std::string_view bytes, const std::string& path);

}  // namespace chladni::precompute::mesh_io
