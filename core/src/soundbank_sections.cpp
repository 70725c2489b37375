#include "soundbank_sections.hpp"

#include <string>

namespace chladni::soundbank_sections {

using binary_io::Reader;
using binary_io::Writer;

Writer write_material(const Material& m) {
  Writer w;
  w.le(m.youngs_modulus), w.le(m.poisson_ratio), w.le(m.density);
  w.le<uint32_t>(static_cast<uint32_t>(m.damping.kind));
  w.le<uint32_t>(static_cast<uint32_t>(m.damping.alpha.size()));
  for (double a : m.damping.alpha) w.le(a);
  w.str(m.name);
  w.str(m.source);
  return w;
}

Material read_material(Reader& r) {
  Material m;
  m.youngs_modulus = r.le<double>();
  m.poisson_ratio = r.le<double>();
  m.density = r.le<double>();
  const auto kind = r.le<uint32_t>();
  if (kind > uint32_t(DampingModel::Kind::Hybrid))
    r.fail("unknown damping model " + std::to_string(kind));
  m.damping.kind = DampingModel::Kind(kind);
  const auto na = r.le<uint32_t>();
  r.need_items(na, 8, "damping parameters");
  m.damping.alpha.resize(na);
  for (double& a : m.damping.alpha) a = r.le<double>();
  m.name = r.str(4096);
  m.source = r.str(1 << 16);
  r.expect_end();
  try {
    m.validate();
  } catch (const InputError& e) {
    r.fail(e.what());
  }
  return m;
}

Writer write_modes(const Soundbank& b) {
  Writer w;
  w.le<uint32_t>(static_cast<uint32_t>(b.omega.size())), w.le<uint32_t>(0);
  for (std::size_t i = 0; i < b.omega.size(); ++i)
    w.le(b.omega[i]), w.le(b.decay[i]), w.le(b.residual[i]), w.le<uint32_t>(0);
  return w;
}

void read_modes(Reader& r, Soundbank& b) {
  const auto n = r.le<uint32_t>();
  r.le<uint32_t>();
  r.need_items(n, 24, "modes");
  b.omega.resize(n), b.decay.resize(n), b.residual.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    b.omega[i] = r.le<double>(), b.decay[i] = r.le<double>(), b.residual[i] = r.le<float>();
    r.le<uint32_t>();
  }
  r.expect_end();
}

Writer write_surface(const Soundbank& b) {
  Writer w;
  w.le<uint32_t>(static_cast<uint32_t>(b.vertices.size()));
  w.le<uint32_t>(static_cast<uint32_t>(b.triangles.size()));
  for (const Vec3& v : b.vertices) w.le(v[0]), w.le(v[1]), w.le(v[2]);
  for (const auto& t : b.triangles) w.le(t[0]), w.le(t[1]), w.le(t[2]);
  for (const auto& q : b.normals) w.le(q[0]), w.le(q[1]), w.le(q[2]);
  return w;
}

void read_surface(Reader& r, Soundbank& b) {
  const auto nv = r.le<uint32_t>(), nt = r.le<uint32_t>();
  r.need_items(uint64_t(nv) * 3, 8, "vertices");
  b.vertices.resize(nv);
  for (Vec3& v : b.vertices) v = {r.le<double>(), r.le<double>(), r.le<double>()};
  r.need_items(uint64_t(nt) * 3, 4, "triangles");
  b.triangles.resize(nt);
  for (auto& t : b.triangles) t = {r.le<uint32_t>(), r.le<uint32_t>(), r.le<uint32_t>()};
  r.need_items(uint64_t(nv) * 3, 4, "normals");
  b.normals.resize(nv);
  for (auto& q : b.normals) q = {r.le<float>(), r.le<float>(), r.le<float>()};
  r.expect_end();
}

Writer write_shapes(const Soundbank& b) {
  Writer w;
  w.le<uint32_t>(static_cast<uint32_t>(b.omega.size()));
  w.le<uint32_t>(static_cast<uint32_t>(b.vertices.size()));
  for (float s : b.shapes) w.le(s);
  return w;
}

void read_shapes(Reader& r, Soundbank& b) {
  const auto n = r.le<uint32_t>(), nv = r.le<uint32_t>();
  if (n != b.omega.size() || nv != b.vertices.size())
    r.fail("holds " + std::to_string(n) + " modes x " + std::to_string(nv) +
           " vertices, but the bank has " + std::to_string(b.omega.size()) + " modes and " +
           std::to_string(b.vertices.size()) + " vertices");
  r.need_items(uint64_t(n) * nv * 3, 4, "shape values");
  b.shapes.resize(std::size_t(n) * nv * 3);
  for (float& s : b.shapes) s = r.le<float>();
  r.expect_end();
}

Writer write_transfer(const Transfer& t) {
  Writer w;
  w.le<uint32_t>(static_cast<uint32_t>(t.modes.size())), w.le<uint32_t>(0);
  w.le(t.centre[0]), w.le(t.centre[1]), w.le(t.centre[2]);
  w.le(t.radius), w.le(t.sound_speed), w.le(t.air_density);
  for (const ModeTransfer& m : t.modes) {
    w.le(m.wavenumber), w.le(m.order), w.le(m.sources);
    w.le(m.fit_residual), w.le(m.held_out_error), w.le(m.expansion_error);
    w.le<uint16_t>(static_cast<uint16_t>(m.method)), w.le<uint16_t>(m.iterations);
  }
  w.le<uint64_t>(t.coefficients.size());
  for (const auto& z : t.coefficients) w.le(z.real()), w.le(z.imag());
  return w;
}

namespace {

ModeTransfer read_mode_transfer(Reader& r, uint32_t i) {
  ModeTransfer m;
  m.wavenumber = r.le<double>();
  m.order = r.le<uint32_t>(), m.sources = r.le<uint32_t>();
  m.fit_residual = r.le<float>(), m.held_out_error = r.le<float>();
  m.expansion_error = r.le<float>();
  const auto method = r.le<uint16_t>();  // 0 before format 1.2
  m.iterations = r.le<uint16_t>();
  if (method > uint16_t(TransferMethod::Wave))
    r.fail("mode " + std::to_string(i) + " has unknown transfer method " + std::to_string(method));
  m.method = TransferMethod(method);
  if (m.order > 200) r.fail("mode " + std::to_string(i) + " has order " + std::to_string(m.order));
  return m;
}

}  // namespace

Transfer read_transfer(Reader& r, std::size_t mode_count) {
  Transfer t;
  const auto n = r.le<uint32_t>();
  r.le<uint32_t>();
  if (n != mode_count)
    r.fail("holds " + std::to_string(n) + " modes, but the bank has " + std::to_string(mode_count));
  t.centre = {r.le<double>(), r.le<double>(), r.le<double>()};
  t.radius = r.le<double>(), t.sound_speed = r.le<double>(), t.air_density = r.le<double>();
  r.need_items(n, 40, "mode transfers");
  uint64_t total = 0;
  for (uint32_t i = 0; i < n; ++i) {
    ModeTransfer m = read_mode_transfer(r, i);
    m.offset = total;
    total += uint64_t(m.order + 1) * (m.order + 1);
    t.modes.push_back(m);
  }
  const auto nc = r.le<uint64_t>();
  if (nc != total)
    r.fail(std::to_string(nc) + " coefficients, but the orders need " + std::to_string(total));
  r.need_items(nc, 8, "coefficients");
  t.coefficients.resize(nc);
  for (auto& z : t.coefficients) {
    const float re = r.le<float>(), im = r.le<float>();
    z = {re, im};
  }
  r.expect_end();
  try {
    t.validate();
  } catch (const InputError& e) {
    r.fail(e.what());
  }
  return t;
}

}  // namespace chladni::soundbank_sections
