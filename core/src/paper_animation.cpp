#include "chladni/core/paper_animation.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "binary_io.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"
#include "chladni/core/json_reader.hpp"
#include "chladni/core/output_file.hpp"

namespace chladni {
namespace {

using json_reader::fail;
using json_reader::index_path;
using json_reader::json;
using json_reader::Obj;

constexpr char kMagic[8] = {'C', 'H', 'P', 'A', 'P', 'E', 'R', '1'};
constexpr uint32_t kBinaryVersion = 1;
// Far beyond any real sheet; rejects corrupted counts before allocating.
constexpr uint64_t kMaxVertices = 1u << 24, kMaxFloats = uint64_t(1) << 31;

// "frames/flap_####.obj" with frame 12 -> "frames/flap_0012.obj": one run of '#' is the
// zero-padded frame number (a printf pattern from a file would be a format-string hazard).
std::string expand_pattern(const std::string& pattern, uint32_t frame) {
  const auto a = pattern.find('#');
  auto b = a;
  while (b < pattern.size() && pattern[b] == '#') ++b;
  std::string num = std::to_string(frame);
  if (num.size() < b - a) num.insert(0, b - a - num.size(), '0');
  return pattern.substr(0, a) + num + pattern.substr(b);
}

// One OBJ frame: 'v x y z' and triangular 'f a b c' (a, a/t, a/t/n, a//n; negative = relative).
void read_obj_frame(const std::string& path, uint32_t frame_index, PaperAnimation& anim,
                    std::vector<float>& positions) {
  std::ifstream in(path);
  if (!in) {
    throw InputError("frame " + std::to_string(frame_index) + ": cannot open " + path +
                     " (missing frame?)");
  }
  const bool first = frame_index == 0;
  std::vector<float> pos;
  std::size_t face = 0;
  std::string line;
  for (std::size_t n = 1; std::getline(in, line); ++n) {
    const std::string where = path + ":" + std::to_string(n);
    std::istringstream ss(line);
    std::string tag;
    if (!(ss >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      double x[3];
      for (double& c : x) {
        std::string tok;
        char* end = nullptr;
        if (!(ss >> tok)) throw InputError(where + ": a vertex needs 3 coordinates");
        c = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0')
          throw InputError(where + ": '" + tok + "' is not a number");
        if (!std::isfinite(c)) throw InputError(where + ": non-finite vertex coordinate");
      }
      for (double c : x) pos.push_back(static_cast<float>(c));
    } else if (tag == "f") {
      std::array<uint32_t, 3> tri{};
      std::string tok;
      int k = 0;
      while (ss >> tok) {
        if (k == 3) {
          throw InputError(where + ": face with more than 3 vertices (paper frames must be " +
                           "triangulated)");
        }
        char* end = nullptr;
        const long idx = std::strtol(tok.c_str(), &end, 10);
        if (end == tok.c_str() || (*end != '\0' && *end != '/') || idx == 0)
          throw InputError(where + ": bad face index '" + tok + "'");
        const long nv = long(pos.size() / 3);
        const long zero_based = idx > 0 ? idx - 1 : nv + idx;
        if (zero_based < 0 || zero_based >= nv)
          throw InputError(where + ": face index " + tok + " outside the " + std::to_string(nv) +
                           " vertices read so far");
        tri[k++] = static_cast<uint32_t>(zero_based);
      }
      if (k != 3) throw InputError(where + ": a face needs 3 vertices");
      if (first) {
        anim.triangles.push_back(tri);
      } else if (face >= anim.triangles.size() || anim.triangles[face] != tri) {
        throw InputError(where + ": topology changed: face " + std::to_string(face) +
                         " differs from frame 0 (frames must share one triangulation)");
      }
      ++face;
    }
  }
  const auto nv = static_cast<uint32_t>(pos.size() / 3);
  if (first) {
    anim.vertex_count = nv;
  } else {
    if (nv != anim.vertex_count)
      throw InputError(path + ": topology changed: " + std::to_string(nv) +
                       " vertices, frame 0 has " + std::to_string(anim.vertex_count));
    if (face != anim.triangles.size())
      throw InputError(path + ": topology changed: " + std::to_string(face) +
                       " faces, frame 0 has " + std::to_string(anim.triangles.size()));
  }
  positions.insert(positions.end(), pos.begin(), pos.end());
}

void write_obj_frame(const std::string& path, const PaperAnimation& anim, uint32_t f) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw InputError("cannot write " + path);
  const auto x = anim.frame(f);
  for (uint32_t v = 0; v < anim.vertex_count; ++v)
    std::fprintf(out, "v %.7g %.7g %.7g\n", x[3 * v], x[3 * v + 1], x[3 * v + 2]);
  for (const auto& t : anim.triangles)
    std::fprintf(out, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
  if (std::fclose(out) != 0) throw InputError("cannot write " + path);
}

std::vector<uint32_t> parse_vertex_list(const json& v, const std::string& path) {
  if (!v.is_array() || v.empty()) fail(path, "expected a non-empty array of vertex indices");
  std::vector<uint32_t> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number_unsigned()) fail(index_path(path, i), "expected a vertex index >= 0");
    out.push_back(v[i].get<uint32_t>());
  }
  return out;
}

}  // namespace

bool PaperAnimation::anchored(std::uint32_t v, std::uint32_t f) const {
  for (const PaperAnchor& a : anchors) {
    if (f < a.first_frame || f > a.last_frame) continue;
    for (uint32_t u : a.vertices)
      if (u == v) return true;
  }
  return false;
}

void validate_sheet(const PaperAnimation& anim, const std::string& where) {
  // Each frame becomes fs / frame_rate samples.
  if (!(anim.frame_rate >= 1 && anim.frame_rate <= 10000))
    throw InputError(where + ": frame_rate must lie in [1, 10000] frames/s");
  if (anim.vertex_count < 3 || anim.triangles.empty())
    throw InputError(where + ": the sheet needs at least one triangle");
  for (std::size_t t = 0; t < anim.triangles.size(); ++t) {
    const auto& tri = anim.triangles[t];
    for (uint32_t v : tri) {
      if (v >= anim.vertex_count)
        throw InputError(where + ": triangle " + std::to_string(t) + " refers to vertex " +
                         std::to_string(v) + " of " + std::to_string(anim.vertex_count));
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      throw InputError(where + ": triangle " + std::to_string(t) + " repeats a vertex");
  }
  for (std::size_t o = 0; o < anim.obstacles.size(); ++o) {
    const Vec3& n = anim.obstacles[o].normal;
    if (!is_finite(anim.obstacles[o].point) || !is_finite(n) ||
        std::abs(std::sqrt(dot(n, n)) - 1.0) > 1e-6)
      throw InputError(where + ": obstacles[" + std::to_string(o) +
                       "]: point must be finite and normal a unit vector");
  }
  if (!(anim.contact_distance > 0) || !std::isfinite(anim.contact_distance))
    throw InputError(where + ": contact_distance must be finite and > 0");
  if (!(anim.listener.ear_distance >= 0) || !std::isfinite(anim.listener.ear_distance))
    throw InputError(where + ": listener.ear_distance must be finite and >= 0");
}

void validate(const PaperAnimation& anim, const std::string& where) {
  validate_sheet(anim, where);
  // The sound is held in memory.
  if (anim.positions.size() % (3 * std::size_t(anim.vertex_count)) != 0)
    throw InputError(where + ": position count is not a whole number of frames");
  if (anim.frame_count() < 2) throw InputError(where + ": an animation needs at least 2 frames");
  if (anim.duration() > 3600)
    throw InputError(where + ": " + std::to_string(anim.frame_count()) + " frames at " +
                     std::to_string(anim.frame_rate) + " frames/s last more than an hour");
  for (uint32_t f = 0; f < anim.frame_count(); ++f) {
    const auto x = anim.frame(f);
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!std::isfinite(x[i]))
        throw InputError(where + ": frame " + std::to_string(f) + ", vertex " +
                         std::to_string(i / 3) + ": non-finite coordinate");
    }
  }
  for (std::size_t a = 0; a < anim.anchors.size(); ++a) {
    const PaperAnchor& an = anim.anchors[a];
    const std::string ap = where + ": anchors[" + std::to_string(a) + "]";
    for (uint32_t v : an.vertices) {
      if (v >= anim.vertex_count)
        throw InputError(ap + ": vertex " + std::to_string(v) + " does not exist (" +
                         std::to_string(anim.vertex_count) + " vertices)");
    }
    if (an.first_frame > an.last_frame || an.last_frame >= anim.frame_count())
      throw InputError(ap + ": frames [" + std::to_string(an.first_frame) + ", " +
                       std::to_string(an.last_frame) + "] outside 0.." +
                       std::to_string(anim.frame_count() - 1));
  }
}

void write_paper_frames_binary(const std::string& path, const PaperAnimation& anim) {
  binary_io::Writer w;
  w.u8s(kMagic, sizeof kMagic);
  w.le(kBinaryVersion);
  w.le<uint32_t>(anim.vertex_count);
  w.le<uint32_t>(static_cast<uint32_t>(anim.triangles.size()));
  w.le<uint32_t>(anim.frame_count());
  for (const auto& t : anim.triangles)
    for (uint32_t v : t) w.le(v);
  for (float x : anim.positions) w.le(x);
  w.le(binary_io::crc32_of(w.bytes.data(), w.bytes.size()));
  write_file_atomic(path,
                    std::string_view(reinterpret_cast<const char*>(w.bytes.data()), w.bytes.size()),
                    "paper frame file");
}

void read_paper_frames_binary(const std::string& path, PaperAnimation& anim) {
  const std::vector<uint8_t> bytes =
      read_input_file(path, "paper frame file", kMaxBinaryInputBytes);
  if (bytes.size() < sizeof kMagic + 20 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw InputError(path + ": not a Chladni paper frame file (bad magic)");
  binary_io::Reader tail(bytes.data() + bytes.size() - 4, 4, path);
  if (binary_io::crc32_of(bytes.data(), bytes.size() - 4) != tail.le<uint32_t>())
    throw InputError(path + ": checksum mismatch (corrupted or truncated)");
  binary_io::Reader r(bytes.data() + sizeof kMagic, bytes.size() - sizeof kMagic - 4, path);
  const auto version = r.le<uint32_t>();
  if (version != kBinaryVersion)
    r.fail("unsupported version " + std::to_string(version) + " (this build reads " +
           std::to_string(kBinaryVersion) + ")");
  const auto nv = r.le<uint32_t>(), nt = r.le<uint32_t>(), nf = r.le<uint32_t>();
  if (nv > kMaxVertices || uint64_t(nv) * 3 * nf > kMaxFloats)
    r.fail("implausible counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
           " frames)");
  r.need_items(uint64_t(nt) * 3, 4, "triangles");
  r.need_items(uint64_t(nv) * 3 * nf + uint64_t(nt) * 3, 4, "triangles and positions");
  anim.vertex_count = nv;
  anim.triangles.resize(nt);
  r.le_array(reinterpret_cast<uint32_t*>(anim.triangles.data()), std::size_t(nt) * 3, "triangles");
  anim.positions.resize(std::size_t(nv) * 3 * nf);
  r.le_array(anim.positions.data(), anim.positions.size(), "positions");
  r.expect_end();
}

namespace {

// "frames": {"binary": FILE} or {"obj": PATTERN, "count": N[, "first": K]}, relative to the JSON.
void parse_frames(Obj& root, const std::filesystem::path& dir, PaperAnimation& anim) {
  auto resolve = [&](const std::string& p) {
    const std::filesystem::path fp(p);
    return (fp.is_absolute() || dir.empty() ? fp : dir / fp).string();
  };
  Obj fr(root.get("frames"), root.at("frames"));
  if (fr.has("binary") == fr.has("obj"))
    fail(fr.path(), "needs exactly one of 'obj' (a file pattern) or 'binary' (a .chpaper)");
  if (fr.has("binary")) {
    read_paper_frames_binary(resolve(fr.string("binary")), anim);
  } else {
    const std::string pattern = fr.string("obj");
    if (pattern.find('#') == std::string::npos)
      fail(fr.at("obj"), "the pattern needs a run of '#' for the frame number");
    const long count = fr.integer("count");
    if (count < 2 || count > 1000000) fail(fr.at("count"), "must lie in [2, 1000000]");
    const long first = fr.has("first") ? fr.integer("first") : 0;
    if (first < 0) fail(fr.at("first"), "must be >= 0");
    std::vector<float> positions;
    for (long f = 0; f < count; ++f) {
      const std::string file = resolve(expand_pattern(pattern, uint32_t(first + f)));
      read_obj_frame(file, uint32_t(f), anim, positions);
    }
    anim.positions = std::move(positions);
  }
  fr.done();
}

void parse_anchors(Obj& root, PaperAnimation& anim) {
  const json& arr = root.array("anchors");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    Obj a(arr[i], index_path(root.at("anchors"), i));
    PaperAnchor an;
    an.vertices = parse_vertex_list(a.get("vertices"), a.at("vertices"));
    const json& fr = a.get("frames");
    if (!fr.is_array() || fr.size() != 2 || !fr[0].is_number_unsigned() ||
        !fr[1].is_number_unsigned())
      fail(a.at("frames"), "expected [first, last] frame indices (inclusive)");
    an.first_frame = fr[0].get<uint32_t>();
    an.last_frame = fr[1].get<uint32_t>();
    a.done();
    anim.anchors.push_back(std::move(an));
  }
}

void parse_obstacles(Obj& root, PaperAnimation& anim) {
  const json& arr = root.array("obstacles");
  for (std::size_t i = 0; i < arr.size(); ++i) {
    Obj o(arr[i], index_path(root.at("obstacles"), i));
    PaperObstacle ob;
    ob.name = o.has("name") ? o.string("name") : "plane" + std::to_string(i);
    const std::string type = o.has("type") ? o.string("type") : "plane";
    if (type != "plane") fail(o.at("type"), "unknown obstacle type '" + type + "' (plane)");
    ob.point = o.vec3("point");
    ob.normal = o.unit("normal");
    if (o.has("friction")) ob.friction = o.string("friction");
    o.done();
    anim.obstacles.push_back(std::move(ob));
  }
}

void parse_listener(Obj& root, PaperAnimation& anim) {
  Obj l(root.get("listener"), root.at("listener"));
  if (l.has("position")) anim.listener.position = l.vec3("position");
  if (l.has("forward")) anim.listener.forward = l.unit("forward");
  if (l.has("up")) anim.listener.up = l.unit("up");
  anim.listener.ear_distance = l.non_negative("ear_distance", anim.listener.ear_distance);
  if (std::abs(dot(anim.listener.forward, anim.listener.up)) > 0.999)
    fail(l.path(), "'forward' and 'up' must not be parallel");
  l.done();
}

}  // namespace

PaperAnimation load_paper_animation(const std::string& json_path) {
  const json j = json_reader::read_json_file(json_path, "paper animation");
  PaperAnimation anim;
  try {
    Obj root(j, "$");
    const long version = root.integer("chladni_paper_animation");
    if (version != 1)
      fail(root.at("chladni_paper_animation"),
           "unsupported version " + std::to_string(version) + " (this build reads 1)");
    anim.frame_rate = root.positive("frame_rate", anim.frame_rate);
    anim.contact_distance = root.positive("contact_distance", anim.contact_distance);
    parse_frames(root, std::filesystem::path(json_path).parent_path(), anim);
    if (root.has("anchors")) parse_anchors(root, anim);
    if (root.has("obstacles")) parse_obstacles(root, anim);
    if (root.has("description")) anim.description = root.string("description");
    if (root.has("event_frames")) {
      const json& ef = root.array("event_frames");
      for (std::size_t i = 0; i < ef.size(); ++i) {
        if (!ef[i].is_number_unsigned())
          fail(index_path(root.at("event_frames"), i), "expected a frame index >= 0");
        anim.event_frames.push_back(ef[i].get<uint32_t>());
      }
    }
    if (root.has("listener")) parse_listener(root, anim);
    root.done();
  } catch (const InputError& e) {
    throw InputError(json_path + ": " + e.what());
  }
  validate(anim, json_path);
  return anim;
}

void write_paper_animation(const std::string& json_path, const PaperAnimation& anim,
                           PaperFrameStorage storage) {
  validate(anim, json_path);
  const std::filesystem::path jp(json_path);
  const std::string stem = jp.stem().string();
  const std::filesystem::path dir = jp.parent_path();
  json j;
  j["chladni_paper_animation"] = 1;
  j["frame_rate"] = anim.frame_rate;
  j["contact_distance"] = anim.contact_distance;
  if (storage == PaperFrameStorage::Binary) {
    const std::string file = stem + ".chpaper";
    write_paper_frames_binary((dir / file).string(), anim);
    j["frames"] = {{"binary", file}};
  } else {
    std::filesystem::create_directories(dir / stem);
    const std::string pattern = stem + "/" + stem + "_####.obj";
    for (uint32_t f = 0; f < anim.frame_count(); ++f)
      write_obj_frame((dir / expand_pattern(pattern, f)).string(), anim, f);
    j["frames"] = {{"obj", pattern}, {"count", anim.frame_count()}};
  }
  if (!anim.description.empty()) j["description"] = anim.description;
  if (!anim.event_frames.empty()) j["event_frames"] = anim.event_frames;
  j["anchors"] = json::array();
  for (const PaperAnchor& a : anim.anchors)
    j["anchors"].push_back({{"vertices", a.vertices}, {"frames", {a.first_frame, a.last_frame}}});
  j["obstacles"] = json::array();
  for (const PaperObstacle& o : anim.obstacles)
    j["obstacles"].push_back({{"name", o.name},
                              {"type", "plane"},
                              {"point", o.point},
                              {"normal", o.normal},
                              {"friction", o.friction}});
  j["listener"] = {{"position", anim.listener.position},
                   {"forward", anim.listener.forward},
                   {"up", anim.listener.up},
                   {"ear_distance", anim.listener.ear_distance}};
  // Last, and whole: the animation exists once its frames do.
  write_file_atomic(json_path, j.dump(2) + "\n", "paper animation");
}

}  // namespace chladni
