// PLY (Turk's polygon file format), ASCII and binary of either byte order: the 'vertex'
// element's x, y, z and the 'face' element's vertex_indices (or vertex_index) list; every other
// element and property is read past. Counts are checked against the bytes left before anything
// is allocated for them.
#include <bit>
#include <cstring>
#include <limits>

#include "mesh_text.hpp"

namespace chladni::precompute::mesh_io {

namespace {

enum class Type { I8, U8, I16, U16, I32, U32, F32, F64 };
enum class Format { Ascii, Little, Big };

struct Property {
  std::string name;
  bool list = false;
  Type count_type = Type::U8, type = Type::F32;
};
struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
};

std::size_t size_of(Type t) {
  static constexpr std::size_t kSize[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSize[int(t)];
}
bool is_integer(Type t) {
  return t != Type::F32 && t != Type::F64;
}

Type parse_type(Tokens& h, std::string_view s) {
  static const std::pair<const char*, Type> kNames[] = {
      {"char", Type::I8},   {"int8", Type::I8},     {"uchar", Type::U8},   {"uint8", Type::U8},
      {"short", Type::I16}, {"int16", Type::I16},   {"ushort", Type::U16}, {"uint16", Type::U16},
      {"int", Type::I32},   {"int32", Type::I32},   {"uint", Type::U32},   {"uint32", Type::U32},
      {"float", Type::F32}, {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
  for (const auto& [name, t] : kNames)
    if (s == name) return t;
  h.fail("unknown PLY property type '" + std::string(s) + "'");
}

// Values in the body, in whichever encoding the header declared.
class Body {
 public:
  Body(std::string_view bytes, std::size_t start, std::size_t first_line, Format f,
       const std::string& path)
      : bytes_(bytes),
        pos_(start),
        format_(f),
        path_(path),
        text_(bytes.substr(start), path, first_line) {}

  double value(Type t) {
    if (format_ == Format::Ascii) {
      const std::string_view tok = text_.expect("a value");
      return is_integer(t) ? double(text_.integer(tok, "value", std::numeric_limits<int64_t>::min(),
                                                  std::numeric_limits<int64_t>::max()))
                           : text_.number(tok, "value");
    }
    const std::size_t n = size_of(t);
    if (bytes_.size() - pos_ < n) fail("the file ends inside the data");
    uint64_t u = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t at = format_ == Format::Little ? k : n - 1 - k;
      u |= uint64_t(uint8_t(bytes_[pos_ + at])) << (8 * k);
    }
    pos_ += n;
    switch (t) {
      case Type::I8:
        return double(int8_t(u));
      case Type::U8:
        return double(uint8_t(u));
      case Type::I16:
        return double(int16_t(u));
      case Type::U16:
        return double(uint16_t(u));
      case Type::I32:
        return double(int32_t(u));
      case Type::U32:
        return double(uint32_t(u));
      case Type::F32:
        return double(std::bit_cast<float>(uint32_t(u)));
      case Type::F64:
        return std::bit_cast<double>(u);
    }
    return 0;
  }
  // Fails unless `count` items of at least `item_bytes` each (two characters each in ASCII)
  // can still be in the file.
  void need(uint64_t count, std::size_t item_bytes, const std::string& what) {
    const std::size_t left = format_ == Format::Ascii
                                 ? (bytes_.size() - pos_ - text_.offset()) / 2 + 1
                                 : (bytes_.size() - pos_) / item_bytes;
    if (count > left)
      fail(what + ": " + std::to_string(count) + " do not fit in the rest of the file");
  }
  void set_item(const std::string& item) { item_ = item; }
  [[noreturn]] void fail(const std::string& what) const {
    if (format_ == Format::Ascii) text_.fail(what);
    throw InputError(path_ + ": " + (item_.empty() ? "" : item_ + ": ") + what);
  }
  void finish() {
    if (format_ == Format::Ascii ? !text_.at_end() : pos_ != bytes_.size())
      throw InputError(path_ + ": unexpected data after the last element");
  }

 private:
  std::string_view bytes_;
  std::size_t pos_;
  Format format_;
  const std::string& path_;
  Tokens text_;
  std::string item_;
};

// The header, up to and including "end_header"; returns where the body starts.
std::size_t parse_header(std::string_view bytes, const std::string& path, Format& format,
                         std::vector<Element>& elements, std::size_t& body_line) {
  const std::size_t end = bytes.find("end_header");
  if (bytes.substr(0, 3) != "ply") throw InputError(path + ": not a PLY file (no 'ply' magic)");
  if (end == std::string_view::npos) throw InputError(path + ": the PLY header has no end_header");
  std::size_t start = bytes.find('\n', end);
  start = start == std::string_view::npos ? bytes.size() : start + 1;
  Tokens h(bytes.substr(0, start), path);
  h.skip_line();
  bool have_format = false;
  std::string_view kw;
  while (h.next(kw)) {
    if (kw == "end_header") break;
    if (kw == "comment" || kw == "obj_info") {
    } else if (kw == "format") {
      const std::string_view f = h.expect_on_line("the format");
      if (f == "ascii")
        format = Format::Ascii;
      else if (f == "binary_little_endian")
        format = Format::Little;
      else if (f == "binary_big_endian")
        format = Format::Big;
      else
        h.fail("unknown PLY format '" + std::string(f) + "'");
      if (h.expect_on_line("the format version") != "1.0") h.fail("only PLY version 1.0 is known");
      have_format = true;
    } else if (kw == "element") {
      Element e;
      e.name = h.expect_on_line("the element name");
      e.count = uint64_t(h.integer(h.expect_on_line("the element count"), "element count", 0,
                                   std::numeric_limits<int64_t>::max()));
      elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (elements.empty()) h.fail("a property before any element");
      Property p;
      std::string_view ty = h.expect_on_line("the property type");
      if (ty == "list") {
        p.list = true;
        p.count_type = parse_type(h, h.expect_on_line("the list count type"));
        if (!is_integer(p.count_type)) h.fail("a list count must have an integer type");
        ty = h.expect_on_line("the list item type");
      }
      p.type = parse_type(h, ty);
      p.name = h.expect_on_line("the property name");
      elements.back().props.push_back(std::move(p));
    } else {
      h.fail("unknown PLY header keyword '" + std::string(kw) + "'");
    }
    std::string_view extra;
    if (kw != "comment" && kw != "obj_info" && h.next_on_line(extra))
      h.fail("unexpected '" + std::string(extra) + "' at the end of the header line");
    h.skip_line();
  }
  if (!have_format) throw InputError(path + ": the PLY header has no format line");
  body_line = h.line() + 1;
  return start;
}

}  // namespace

SurfaceMesh read_ply(std::string_view bytes, const std::string& path) {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  std::size_t body_line = 1;
  const std::size_t start = parse_header(bytes, path, format, elements, body_line);
  Body body(bytes, start, body_line, format, path);
  SurfaceMesh m;
  bool have_vertices = false, have_faces = false;
  std::vector<uint32_t> corners;
  for (const Element& e : elements) {
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1}, indices = -1;
    std::size_t min_bytes = 0;
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const Property& p = e.props[k];
      min_bytes += size_of(p.list ? p.count_type : p.type);
      for (int c = 0; c < 3; ++c)
        if (is_vertex && !p.list && p.name == std::string(1, char('x' + c))) xyz[c] = int(k);
      if (is_face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index"))
        indices = int(k);
    }
    if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
      throw InputError(path + ": the vertex element needs properties x, y and z");
    if (is_face && indices < 0)
      throw InputError(path + ": the face element needs a vertex_indices list");
    if (is_face && !is_integer(e.props[std::size_t(indices)].type))
      throw InputError(path + ": vertex_indices must have an integer type");
    body.need(e.count, std::max<std::size_t>(min_bytes, 1), "'" + e.name + "' elements");
    have_vertices |= is_vertex, have_faces |= is_face;
    for (uint64_t i = 0; i < e.count; ++i) {
      body.set_item(e.name + " " + std::to_string(i));
      Vec3 p{};
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const Property& pr = e.props[k];
        if (!pr.list) {
          const double x = body.value(pr.type);
          for (int c = 0; c < 3; ++c)
            if (int(k) == xyz[c]) p[c] = x;
          continue;
        }
        const double n = body.value(pr.count_type);
        if (n < 0) body.fail("negative list length");
        body.need(uint64_t(n), size_of(pr.type), "list items");
        const bool keep = int(k) == indices;
        if (keep) corners.clear();
        for (uint64_t j = 0; j < uint64_t(n); ++j) {
          const double v = body.value(pr.type);
          if (keep) {
            if (v < 0 || v > double(std::numeric_limits<uint32_t>::max()))
              body.fail("vertex index " + std::to_string(int64_t(v)) + " is out of range");
            corners.push_back(uint32_t(v));
          }
        }
      }
      if (is_vertex) {
        if (!is_finite(p)) body.fail("a coordinate is not finite");
        m.vertices.push_back(p);
      }
      if (is_face) add_polygon(m, corners, path + ": face " + std::to_string(i));
    }
  }
  body.finish();
  if (!have_vertices || !have_faces)
    throw InputError(path + ": a PLY mesh needs both a vertex and a face element");
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (uint32_t v : m.triangles[t])
      if (v >= m.vertices.size())
        throw InputError(path + ": a face refers to vertex " + std::to_string(v) +
                         " but the file has " + std::to_string(m.vertices.size()));
  return m;
}

}  // namespace chladni::precompute::mesh_io
