#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <numbers>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "chladni/report/bank_facts.hpp"
#include "chladni/report/radiation.hpp"
#include "chladni/report/report.hpp"
#include "chladni/runtime/modal/object_modes.hpp"
#include "chladni/runtime/scene/scene_objects.hpp"
#include "report_detail.hpp"

namespace chladni::report {
namespace {

using nlohmann::json;
constexpr double kTwoPi = 2 * std::numbers::pi;

std::string base64(const void* data, std::size_t bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes; i += 3) {
    const uint32_t v = uint32_t(p[i]) << 16 | (i + 1 < bytes ? uint32_t(p[i + 1]) << 8 : 0) |
                       (i + 2 < bytes ? p[i + 2] : 0);
    out += k[v >> 18 & 63];
    out += k[v >> 12 & 63];
    out += i + 1 < bytes ? k[v >> 6 & 63] : '=';
    out += i + 2 < bytes ? k[v & 63] : '=';
  }
  return out;
}

template <class T>
std::string packed(const std::vector<T>& v) {
  return base64(v.data(), v.size() * sizeof(T));
}

std::vector<float> flat(const std::vector<Vec3>& v) {
  std::vector<float> out;
  out.reserve(3 * v.size());
  for (const Vec3& p : v)
    for (double x : p) out.push_back(float(x));
  return out;
}

// Per vertex of the display surface: its position, normal and the model point it takes its
// shape from (itself for the bank's own surface, the nearest point for a separate mesh).
json surface_json(const ModalModel& model, const Soundbank& bank, const ReportOptions& o) {
  std::vector<Vec3> verts = bank.vertices;
  std::vector<std::array<uint32_t, 3>> tris = bank.triangles;
  std::vector<uint32_t> point_of(verts.size());
  for (std::size_t v = 0; v < verts.size(); ++v) point_of[v] = uint32_t(v);
  if (!o.mesh_path.empty()) {
    const precompute::SurfaceMesh mesh = precompute::read_mesh(o.mesh_path, o.mesh_scale);
    // Each display vertex looks up its nearest bank point (a linear search): bound the work.
    if (double(mesh.vertices.size()) * double(model.points.size()) > 4e9)
      throw InputError(o.mesh_path + ": " + std::to_string(mesh.vertices.size()) +
                       " vertices against the bank's " + std::to_string(model.points.size()) +
                       " surface points is too many to map; give a coarser display mesh");
    verts = mesh.vertices, tris = mesh.triangles;
    point_of.resize(verts.size());
    double size = 0, worst = 0;
    for (const Vec3& p : model.points) size = std::max(size, norm(sub(p, model.points[0])));
    for (std::size_t v = 0; v < verts.size(); ++v) {
      point_of[v] = uint32_t(model.nearest_point(verts[v]));
      worst = std::max(worst, norm(sub(verts[v], model.points[point_of[v]])));
    }
    if (worst > 0.25 * size)
      throw InputError(o.mesh_path +
                       ": the mesh does not lie on the soundbank's surface (a vertex is " +
                       std::to_string(worst) + " m from it, the object " + std::to_string(size) +
                       " m across): give it in the bank's frame, with --unit as at precompute");
  }
  std::vector<Vec3> normals(verts.size(), Vec3{0, 0, 0});
  for (const auto& t : tris) {
    const Vec3 n = cross(sub(verts[t[1]], verts[t[0]]), sub(verts[t[2]], verts[t[0]]));
    for (uint32_t v : t) normals[v] = add(normals[v], n);
  }
  for (Vec3& n : normals) {
    const double l = norm(n);
    if (l > 0) n = scale(n, 1 / l);
  }
  std::vector<uint32_t> idx;
  idx.reserve(3 * tris.size());
  for (const auto& t : tris) idx.insert(idx.end(), t.begin(), t.end());
  return {{"vertices", verts.size()},         {"triangles", tris.size()},
          {"positions", packed(flat(verts))}, {"normals", packed(flat(normals))},
          {"indices", packed(idx)},           {"point_of_vertex", packed(point_of)}};
}

// |p| on three great circles (planes xy, xz, yz) at a far-field distance, by the runtime's gain
// rule (the multipoles where the transfer is usable), each mode scaled to its loudest direction.
json directivity_json(const ModalModel& model, const Vec3& centre, double radius, int angles) {
  const std::size_t n = model.mode_count();
  const double r = std::max(1.0, 20 * radius);
  std::vector<Vec3> dirs;
  for (int plane = 0; plane < 3; ++plane)
    for (int a = 0; a < angles; ++a) {
      const double t = kTwoPi * a / angles, c = std::cos(t), s = std::sin(t);
      dirs.push_back(plane == 0 ? Vec3{c, s, 0} : plane == 1 ? Vec3{c, 0, s} : Vec3{0, c, s});
    }
  const std::vector<std::vector<double>> gains = gains_towards(model, centre, r, dirs);
  std::vector<float> values(n * dirs.size());
  for (std::size_t k = 0; k < dirs.size(); ++k)  // k = plane * angles + a
    for (std::size_t i = 0; i < n; ++i) values[i * dirs.size() + k] = float(gains[k][i]);
  for (std::size_t i = 0; i < n; ++i) {
    float* v = &values[i * dirs.size()];
    const float top = *std::max_element(v, v + dirs.size());
    for (std::size_t k = 0; k < dirs.size(); ++k) v[k] = top > 0 ? v[k] / top : 0.f;
  }
  return {{"angles", angles},
          {"distance_m", r},
          {"planes", {"xy", "xz", "yz"}},
          {"values", packed(values)}};
}

// The modes below Nyquist, as many as o.max_modes and the shape budget allow.
std::vector<std::size_t> modes_to_show(const ModalModel& model, const Soundbank& bank,
                                       const ReportOptions& o, ReportSummary* summary) {
  const std::size_t by_size = std::max<std::size_t>(
      1, std::size_t(o.max_shape_bytes / (12.0 * double(model.points.size()))));
  const std::size_t limit = std::min(o.max_modes, by_size);
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < model.mode_count() && kept.size() < limit; ++i)
    if (model.damped_omega(i) > 0 && model.damped_omega(i) < std::numbers::pi * o.sample_rate)
      kept.push_back(i);
  if (kept.empty())
    throw InputError(o.bank_path + ": no mode lies below the Nyquist frequency at " +
                     std::to_string(o.sample_rate) + " Hz");
  if (summary) {
    summary->bank_modes = bank.mode_count();
    summary->modes_shown = kept.size();
    summary->limited_by_size = by_size < o.max_modes && kept.size() == by_size;
  }
  return kept;
}

// Mode i of the kept model, which is mode `index` of the bank: its facts under `chladni info`'s
// names, with the bank's index and its gain at the listener.
json kept_mode_json(const Soundbank& bank, std::size_t index, const std::vector<double>& errors,
                    double gain) {
  json m = mode_json(bank, index, errors);
  m["bank_index"] = index;
  m["gain"] = gain;
  return m;
}

}  // namespace

std::string report_json(const Soundbank& bank, const ReportOptions& o, ReportSummary* summary) {
  ModalModel model = to_modal_model(bank, o.bank_path);
  if (!model.has_geometry() || model.normals.size() != model.points.size())
    throw InputError(o.bank_path + ": the soundbank has no surface to show");
  const std::vector<std::size_t> kept = modes_to_show(model, bank, o, summary);
  keep_modes(model, kept);

  Vec3 lo = model.points[0], hi = lo;
  for (const Vec3& p : model.points)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  const Vec3 centre = model.transfer ? model.transfer->centre : scale(add(lo, hi), 0.5);
  const double radius = 0.5 * norm(sub(hi, lo));
  const Vec3 listener = o.listener.value_or(
      add(centre, scale(Vec3{1, 1, 1}, std::max(1.0, 4 * radius) / std::sqrt(3.0))));

  runtime::ObjectModes object = runtime::object_modes(model);
  runtime::gains_at_listener(model, object, listener);
  const std::vector<double> errors = frequency_errors(bank_metadata(bank), bank);
  json modes = json::array();
  for (std::size_t i = 0; i < model.mode_count(); ++i)
    modes.push_back(kept_mode_json(bank, kept[i], errors, object.modes[i].gain));
  std::vector<float> shapes;
  shapes.reserve(model.shapes.size() * 3);
  for (const Vec3& s : model.shapes)
    for (double x : s) shapes.push_back(float(x));

  json j;
  j["format"] = 1;
  j["bank"] = o.bank_path;
  j["material"] = material_json(bank.material);
  j["bank_modes"] = bank.mode_count();
  j["transfer"] = bank.transfer
                      ? json("multipoles, R " + std::to_string(bank.transfer->radius) + " m")
                      : json("none (compact-source gains)");
  j["centre"] = centre;
  j["radius_m"] = radius;
  j["listener"] = listener;
  j["strike"] = {
      {"sample_rate", o.sample_rate}, {"impulse", o.impulse}, {"contact_time", o.contact_time}};
  j["modes"] = modes;
  j["points"] = {{"count", model.points.size()},
                 {"positions", packed(flat(model.points))},
                 {"normals", packed(flat(model.normals))}};
  j["shapes"] = packed(shapes);
  j["surface"] = surface_json(model, bank, o);
  j["directivity"] = directivity_json(model, centre, radius, o.directivity_angles);
  return j.dump();
}

}  // namespace chladni::report
