#include "chladni/core/soundbank.hpp"

#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numbers>

#include "binary_io.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/input_file.hpp"
#include "chladni/core/output_file.hpp"
#include "soundbank_sections.hpp"

namespace chladni {
namespace {

using binary_io::crc32_of;
using binary_io::Reader;
using binary_io::Writer;
namespace sections = soundbank_sections;

// Layout (docs/soundbank-format.md): 32-byte header, section_count 32-byte table entries, then
// 8-byte aligned payloads.
constexpr char kMagic[8] = {'C', 'H', 'L', 'A', 'D', 'N', 'I', 'B'};
constexpr std::size_t kHeaderSize = 32, kEntrySize = 32;
constexpr std::size_t kMaxSections = 64;

std::string tag_name(uint32_t tag) {
  std::string s;
  for (int k = 0; k < 4; ++k) {
    const char c = char(tag >> (8 * k));
    s += (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}
constexpr uint32_t make_tag(const char (&t)[5]) {
  return uint32_t(uint8_t(t[0])) | uint32_t(uint8_t(t[1])) << 8 | uint32_t(uint8_t(t[2])) << 16 |
         uint32_t(uint8_t(t[3])) << 24;
}
constexpr uint32_t kMeta = make_tag("META"), kMatl = make_tag("MATL"), kMode = make_tag("MODE"),
                   kSurf = make_tag("SURF"), kShap = make_tag("SHAP"), kXfer = make_tag("XFER");

}  // namespace

void Soundbank::validate() const {
  material.validate();
  const std::size_t n = omega.size(), nv = vertices.size();
  if (decay.size() != n || residual.size() != n)
    throw InputError("soundbank: " + std::to_string(n) + " frequencies but " +
                     std::to_string(decay.size()) + " decay rates and " +
                     std::to_string(residual.size()) + " residuals");
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(omega[i]) || !(omega[i] > 0) || !std::isfinite(decay[i]) || decay[i] < 0 ||
        !(decay[i] < omega[i]) || !std::isfinite(residual[i]) || residual[i] < 0)
      throw InputError("soundbank: mode " + std::to_string(i) +
                       ": frequency, decay or residual is not finite or out of range");
    if (i > 0 && omega[i] < omega[i - 1])
      throw InputError("soundbank: mode " + std::to_string(i) + " is out of ascending order");
  }
  if (nv == 0) throw InputError("soundbank: the surface has no vertices");
  for (std::size_t v = 0; v < nv; ++v)
    if (!is_finite(vertices[v]))
      throw InputError("soundbank: surface vertex " + std::to_string(v) + " is not finite");
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (uint32_t idx : triangles[t])
      if (idx >= nv)
        throw InputError("soundbank: triangle " + std::to_string(t) + " refers to vertex " +
                         std::to_string(idx) + " of " + std::to_string(nv));
  if (normals.size() != nv) throw InputError("soundbank: normals and vertices differ in count");
  for (std::size_t v = 0; v < nv; ++v) {
    const auto& q = normals[v];
    const double len = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2]);
    if (!(std::abs(len - 1.0) < 1e-3))
      throw InputError("soundbank: normal of vertex " + std::to_string(v) +
                       " is not a unit vector");
  }
  if (shapes.size() != n * nv * 3)
    throw InputError("soundbank: " + std::to_string(shapes.size()) + " shape values for " +
                     std::to_string(n) + " modes x " + std::to_string(nv) + " vertices x 3");
  for (std::size_t k = 0; k < shapes.size(); ++k)
    if (!std::isfinite(shapes[k]))
      throw InputError("soundbank: shape of mode " + std::to_string(k / (3 * nv)) + " at vertex " +
                       std::to_string((k / 3) % nv) + " is not finite");
  if (transfer) {
    if (transfer->mode_count() != n)
      throw InputError("soundbank: transfer has " + std::to_string(transfer->mode_count()) +
                       " modes but the bank has " + std::to_string(n));
    transfer->validate();
  }
}

namespace {

using Sections = std::vector<std::pair<uint32_t, Writer>>;

// Header, section table, then the payloads at 8-byte aligned offsets.
std::vector<uint8_t> frame_sections(const Sections& sections) {
  Writer table;
  uint64_t offset = kHeaderSize + kEntrySize * sections.size();
  std::vector<uint64_t> offsets;
  for (auto& [tag, w] : sections) {
    offset = (offset + 7) & ~uint64_t(7);
    offsets.push_back(offset);
    table.le(tag), table.le<uint32_t>(0), table.le<uint64_t>(offset);
    table.le<uint64_t>(w.bytes.size()), table.le(crc32_of(w.bytes.data(), w.bytes.size()));
    table.le<uint32_t>(0);
    offset += w.bytes.size();
  }
  Writer out;
  out.u8s(kMagic, 8);
  out.le(Soundbank::kVersionMajor), out.le(Soundbank::kVersionMinor);
  out.le<uint32_t>(static_cast<uint32_t>(sections.size()));
  out.le<uint64_t>(offset);
  out.le(crc32_of(table.bytes.data(), table.bytes.size()));
  out.le(crc32_of(out.bytes.data(), out.bytes.size()));
  out.u8s(table.bytes.data(), table.bytes.size());
  for (std::size_t s = 0; s < sections.size(); ++s) {
    out.bytes.resize(offsets[s], 0);
    out.u8s(sections[s].second.bytes.data(), sections[s].second.bytes.size());
  }
  return std::move(out.bytes);
}

using Payloads = std::map<uint32_t, std::pair<const uint8_t*, std::size_t>>;

// Checks the header and every checksum; returns each section's payload by tag.
Payloads unframe_sections(const std::vector<uint8_t>& bytes, const std::string& who) {
  if (bytes.size() < kHeaderSize || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw InputError(who + ": not a Chladni soundbank (bad magic or shorter than its header)");
  Reader h(bytes.data() + 8, kHeaderSize - 8, who + ": header");
  const auto major = h.le<uint16_t>(), minor = h.le<uint16_t>();
  const auto count = h.le<uint32_t>();
  const auto file_size = h.le<uint64_t>();
  const auto table_crc = h.le<uint32_t>(), header_crc = h.le<uint32_t>();
  if (crc32_of(bytes.data(), 28) != header_crc)
    throw InputError(who + ": header checksum mismatch (file corrupted)");
  if (major != Soundbank::kVersionMajor)
    throw InputError(who + ": format version " + std::to_string(major) + "." +
                     std::to_string(minor) + " is not supported (this build reads " +
                     std::to_string(Soundbank::kVersionMajor) + ".x)");
  if (file_size != bytes.size())
    throw InputError(who + ": file is " + std::to_string(bytes.size()) +
                     " bytes but its header says " + std::to_string(file_size) +
                     " (truncated or padded)");
  if (count > kMaxSections || kHeaderSize + kEntrySize * count > bytes.size())
    throw InputError(who + ": section table of " + std::to_string(count) + " entries does not fit");
  const uint8_t* table = bytes.data() + kHeaderSize;
  if (crc32_of(table, kEntrySize * count) != table_crc)
    throw InputError(who + ": section table checksum mismatch (file corrupted)");
  Payloads found;
  for (uint32_t s = 0; s < count; ++s) {
    Reader e(table + kEntrySize * s, kEntrySize, who + ": section table");
    const auto tag = e.le<uint32_t>();
    e.le<uint32_t>();
    const auto off = e.le<uint64_t>(), size = e.le<uint64_t>();
    const auto crc = e.le<uint32_t>();
    const std::string name = "section '" + tag_name(tag) + "'";
    if (off < kHeaderSize + kEntrySize * count || off > bytes.size() || size > bytes.size() - off)
      throw InputError(who + ": " + name + " lies outside the file");
    if (crc32_of(bytes.data() + off, size) != crc)
      throw InputError(who + ": " + name + " checksum mismatch (file corrupted)");
    if (!found.emplace(tag, std::make_pair(bytes.data() + off, std::size_t(size))).second)
      throw InputError(who + ": " + name + " appears twice");
  }
  return found;
}

}  // namespace

std::vector<uint8_t> serialize_soundbank(const Soundbank& b) {
  b.validate();
  Writer meta;
  meta.u8s(b.metadata_json.data(), b.metadata_json.size());
  Sections list;
  list.emplace_back(kMeta, std::move(meta));
  list.emplace_back(kMatl, sections::write_material(b.material));
  list.emplace_back(kMode, sections::write_modes(b));
  list.emplace_back(kSurf, sections::write_surface(b));
  list.emplace_back(kShap, sections::write_shapes(b));
  if (b.transfer) list.emplace_back(kXfer, sections::write_transfer(*b.transfer));
  return frame_sections(list);
}

Soundbank parse_soundbank(const std::vector<uint8_t>& bytes, const std::string& origin) {
  const std::string who = "soundbank " + origin;
  const Payloads found = unframe_sections(bytes, who);
  auto section = [&](uint32_t tag) {
    auto it = found.find(tag);
    if (it == found.end())
      throw InputError(who + ": required section '" + tag_name(tag) + "' is missing");
    return Reader(it->second.first, it->second.second, who + ": section '" + tag_name(tag) + "'");
  };
  Soundbank b;
  if (auto it = found.find(kMeta); it != found.end())
    b.metadata_json.assign(reinterpret_cast<const char*>(it->second.first), it->second.second);
  Reader matl = section(kMatl);
  b.material = sections::read_material(matl);
  Reader mode = section(kMode);
  sections::read_modes(mode, b);
  Reader surf = section(kSurf);
  sections::read_surface(surf, b);
  Reader shap = section(kShap);
  sections::read_shapes(shap, b);
  if (found.count(kXfer)) {
    Reader xfer = section(kXfer);
    b.transfer = sections::read_transfer(xfer, b.omega.size());
  }
  try {
    b.validate();
  } catch (const InputError& e) {
    throw InputError(who + ": " + e.what());
  }
  return b;
}

void write_soundbank(const std::string& path, const Soundbank& bank) {
  const std::vector<uint8_t> bytes = serialize_soundbank(bank);
  write_file_atomic(path,
                    std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                    "soundbank");
}

Soundbank read_soundbank(const std::string& path) {
  return parse_soundbank(read_input_file(path, "soundbank", kMaxBinaryInputBytes), path);
}

ModalModel to_modal_model(const Soundbank& b, const std::string& name) {
  const double rho0 = b.transfer ? b.transfer->air_density : 1.204;
  const double c0 = b.transfer ? b.transfer->sound_speed : 343.0;
  ModalModel m;
  m.name = name;
  m.transfer = b.transfer;
  m.omega = b.omega;
  m.decay = b.decay;
  m.points = b.vertices;
  const std::size_t nv = b.vertices.size();
  for (const auto& q : b.normals) m.normals.push_back({q[0], q[1], q[2]});
  m.shapes.resize(b.omega.size() * nv);
  for (std::size_t k = 0; k < m.shapes.size(); ++k)
    m.shapes[k] = {b.shapes[3 * k], b.shapes[3 * k + 1], b.shapes[3 * k + 2]};
  // Area-weighted vertex normals dA_v n_v, and the centroid, for the surface moments.
  std::vector<Vec3> an(nv, Vec3{0, 0, 0});
  Vec3 c{0, 0, 0};
  for (const Vec3& v : b.vertices)
    for (int k = 0; k < 3; ++k) c[k] += v[k] / double(nv);
  for (const auto& t : b.triangles) {
    const Vec3 n2 = triangle_normal(b.vertices[t[0]], b.vertices[t[1]], b.vertices[t[2]]);
    for (uint32_t v : t)
      for (int k = 0; k < 3; ++k) an[v][k] += n2[k] / 6.0;  // (area vector) / 3 per corner
  }
  // Far field of the surface's volume velocity to second order in k (Taylor of e^(-ik x.y)):
  // A(x) = Q - ik x.D - (k^2/2) x.T.x with Q = int u_n, D = int u_n y, T = int u_n y y^T about
  // the centroid; radiation is the rms of rho0 |A| / (4 pi) over directions:
  // <|A|^2> = Q^2 + k^2 |D|^2 / 3 - k^2 Q tr T / 3 + k^4 (2 tr T^2 + (tr T)^2) / 60. The
  // quadrupole keeps modes with no net volume or dipole moment (a bowl's (2,0) pairs) audible.
  for (std::size_t i = 0; i < b.omega.size(); ++i) {
    double Q = 0, T[3][3] = {};
    Vec3 D{0, 0, 0};
    for (std::size_t v = 0; v < nv; ++v) {
      const Vec3& s = m.shapes[i * nv + v];
      const double un = s[0] * an[v][0] + s[1] * an[v][1] + s[2] * an[v][2];
      const Vec3 y = sub(b.vertices[v], c);
      Q += un;
      for (int k = 0; k < 3; ++k) {
        D[k] += y[k] * un;
        for (int l = 0; l < 3; ++l) T[k][l] += y[k] * y[l] * un;
      }
    }
    const double k = b.omega[i] / c0, k2 = k * k;
    const double d2 = D[0] * D[0] + D[1] * D[1] + D[2] * D[2];
    const double tr = T[0][0] + T[1][1] + T[2][2];
    double tt = 0;
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) tt += T[r][col] * T[col][r];
    const double ms =
        Q * Q + k2 * d2 / 3.0 - k2 * Q * tr / 3.0 + k2 * k2 * (2 * tt + tr * tr) / 60.0;
    m.radiation.push_back(rho0 / (4 * std::numbers::pi) * std::sqrt(std::max(ms, 0.0)));
  }
  return m;
}

}  // namespace chladni
