// Soundbank round trips, and corrupted or truncated files refused with the section named.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <random>

#include "chladni/core/error.hpp"
#include "chladni/core/soundbank.hpp"
#include "chladni/core/spherical.hpp"
#include "fem_fixtures.hpp"

using namespace chladni;

namespace {

Soundbank small_bank() {
  Soundbank b;
  b.metadata_json = R"({"source":"test"})";
  b.material = find_material("sl2016-wood:caughey");
  b.omega = {2 * M_PI * 440, 2 * M_PI * 1000.5};
  b.decay = {3.5, 12.25};
  b.residual = {1e-9f, 2e-8f};
  b.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  b.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const float s = float(1 / std::sqrt(3.0));
  b.normals = {{-s, -s, -s}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 2 * 4 * 3; ++i) b.shapes.push_back(0.25f * float(i) - 1.0f);
  Transfer t;
  t.centre = {0.25, 0.25, 0.25};
  t.radius = 0.9;
  for (uint32_t i = 0; i < 2; ++i) {
    ModeTransfer m;
    m.wavenumber = b.omega[i] / t.sound_speed;
    m.order = i + 1;
    m.sources = 130 + i;
    m.fit_residual = 0.01f * float(i + 1), m.held_out_error = 0.6f * float(i),
    m.expansion_error = 1e-4f;
    std::vector<std::complex<double>> a((i + 2) * (i + 2));
    for (std::size_t k = 0; k < a.size(); ++k) a[k] = {0.5 * double(k), -1.0 / double(k + 1)};
    t.add_mode(m, a);
  }
  b.transfer = t;
  return b;
}

std::string error_of(const std::vector<uint8_t>& bytes) {
  try {
    parse_soundbank(bytes, "t.chbank");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Offset and size of a section, read from the table (docs/soundbank-format.md).
std::pair<std::size_t, std::size_t> locate(const std::vector<uint8_t>& f, const char* tag) {
  uint32_t count;
  std::memcpy(&count, &f[12], 4);
  for (uint32_t s = 0; s < count; ++s) {
    const uint8_t* e = &f[32 + 32 * s];
    if (std::memcmp(e, tag, 4) == 0) {
      uint64_t off, size;
      std::memcpy(&off, e + 8, 8);
      std::memcpy(&size, e + 16, 8);
      return {off, size};
    }
  }
  return {0, 0};
}

}  // namespace

TEST(Soundbank, RoundTripsEveryField) {
  const Soundbank a = small_bank();
  const auto path = (std::filesystem::temp_directory_path() / "chladni_rt.chbank").string();
  write_soundbank(path, a);
  const Soundbank b = read_soundbank(path);
  EXPECT_EQ(b.metadata_json, a.metadata_json);
  EXPECT_EQ(b.material.name, a.material.name);
  EXPECT_EQ(b.material.source, a.material.source);
  EXPECT_EQ(b.material.youngs_modulus, a.material.youngs_modulus);
  EXPECT_EQ(b.material.damping.kind, a.material.damping.kind);
  EXPECT_EQ(b.material.damping.alpha, a.material.damping.alpha);
  EXPECT_EQ(b.omega, a.omega);
  EXPECT_EQ(b.decay, a.decay);
  EXPECT_EQ(b.residual, a.residual);
  EXPECT_EQ(b.vertices, a.vertices);
  EXPECT_EQ(b.triangles, a.triangles);
  EXPECT_EQ(b.normals, a.normals);
  EXPECT_EQ(b.shapes, a.shapes);
  ASSERT_TRUE(b.transfer.has_value());
  EXPECT_EQ(b.transfer->centre, a.transfer->centre);
  EXPECT_EQ(b.transfer->radius, a.transfer->radius);
  EXPECT_EQ(b.transfer->coefficients, a.transfer->coefficients);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(b.transfer->modes[i].order, a.transfer->modes[i].order);
    EXPECT_EQ(b.transfer->modes[i].offset, a.transfer->modes[i].offset);
    EXPECT_EQ(b.transfer->modes[i].wavenumber, a.transfer->modes[i].wavenumber);
    EXPECT_EQ(b.transfer->modes[i].held_out_error, a.transfer->modes[i].held_out_error);
  }
  EXPECT_FALSE(b.transfer->poor(0));
  EXPECT_TRUE(b.transfer->poor(1));
  std::filesystem::remove(path);
}

TEST(Soundbank, TransferIsOptional) {
  Soundbank b = small_bank();
  b.transfer.reset();
  const Soundbank a = parse_soundbank(serialize_soundbank(b), "t.chbank");
  EXPECT_FALSE(a.transfer.has_value());
  EXPECT_FALSE(to_modal_model(a, "x").transfer.has_value());
}

TEST(Soundbank, IsLittleEndianWithTheDocumentedHeader) {
  const auto f = serialize_soundbank(small_bank());
  EXPECT_EQ(std::string(f.begin(), f.begin() + 8), "CHLADNIB");
  EXPECT_EQ(f[8], 1);  // major, low byte first
  EXPECT_EQ(f[9], 0);
  EXPECT_EQ(f[12], 6);  // META MATL MODE SURF SHAP XFER
  uint64_t size = 0;
  for (int k = 0; k < 8; ++k) size |= uint64_t(f[16 + k]) << (8 * k);
  EXPECT_EQ(size, f.size());
  for (const char* tag : {"META", "MATL", "MODE", "SURF", "SHAP", "XFER"}) {
    const auto [off, len] = locate(f, tag);
    EXPECT_GT(len, 0u) << tag;
    EXPECT_EQ(off % 8, 0u) << tag;
  }
}

TEST(Soundbank, CorruptionInEachSectionNamesThatSection) {
  const auto good = serialize_soundbank(small_bank());
  for (const char* tag : {"META", "MATL", "MODE", "SURF", "SHAP", "XFER"}) {
    auto f = good;
    const auto [off, len] = locate(f, tag);
    f[off + len / 2] ^= 0x5a;
    const std::string err = error_of(f);
    EXPECT_NE(err.find(std::string("section '") + tag + "' checksum mismatch"), std::string::npos)
        << tag << ": " << err;
  }
  auto f = good;
  f[40] ^= 1;  // inside the section table
  EXPECT_NE(error_of(f).find("section table checksum"), std::string::npos);
  f = good;
  f[10] = 9;  // minor version without fixing the header checksum
  EXPECT_NE(error_of(f).find("header checksum"), std::string::npos);
}

TEST(Soundbank, TruncationAndForeignFilesAreRefused) {
  const auto good = serialize_soundbank(small_bank());
  for (std::size_t n :
       {std::size_t(0), std::size_t(7), std::size_t(31), std::size_t(100), good.size() - 1}) {
    const std::vector<uint8_t> cut(good.begin(), good.begin() + n);
    EXPECT_FALSE(error_of(cut).empty()) << n << " bytes";
  }
  const std::string cut = error_of(std::vector<uint8_t>(good.begin(), good.end() - 1));
  EXPECT_NE(cut.find("truncated"), std::string::npos) << cut;
  std::vector<uint8_t> wav(64, 0);
  std::memcpy(wav.data(), "RIFF", 4);
  EXPECT_NE(error_of(wav).find("not a Chladni soundbank"), std::string::npos);
  EXPECT_THROW(read_soundbank("/nonexistent/x.chbank"), InputError);
}

TEST(Soundbank, UnknownMajorVersionIsRefused) {
  Soundbank b = small_bank();
  auto f = serialize_soundbank(b);
  f[8] = 2;
  // Re-seal the header so that only the version is wrong.
  const uint32_t crc = uint32_t(crc32(crc32(0L, Z_NULL, 0), f.data(), 28));
  for (int k = 0; k < 4; ++k) f[28 + k] = uint8_t(crc >> (8 * k));
  const std::string err = error_of(f);
  EXPECT_NE(err.find("format version 2." + std::to_string(Soundbank::kVersionMinor) +
                     " is not supported"),
            std::string::npos)
      << err;
}

TEST(Soundbank, RandomByteFlipsNeverCrash) {
  const auto good = serialize_soundbank(small_bank());
  std::mt19937 rng(1);
  for (int trial = 0; trial < 2000; ++trial) {
    auto f = good;
    const int flips = 1 + int(rng() % 4);
    for (int k = 0; k < flips; ++k) f[rng() % f.size()] ^= uint8_t(1 + rng() % 255);
    try {
      // Accepted only when the flips hit the zero padding between sections: same content.
      const Soundbank b = parse_soundbank(f, "fuzz");
      EXPECT_EQ(serialize_soundbank(b), good) << "trial " << trial;
    } catch (const InputError&) {
    }
  }
}

TEST(Soundbank, InvalidContentIsRefusedBeforeWriting) {
  Soundbank b = small_bank();
  b.triangles[1][2] = 9;
  try {
    serialize_soundbank(b);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 1 refers to vertex 9"), std::string::npos);
  }
  b = small_bank();
  b.omega[1] = std::nan("");
  EXPECT_THROW(serialize_soundbank(b), InputError);
  b = small_bank();
  b.shapes.pop_back();
  EXPECT_THROW(serialize_soundbank(b), InputError);
  // Transfer: a NaN coefficient, a mode count that is not the bank's, a coefficient short.
  auto message = [](const Soundbank& bad) {
    try {
      serialize_soundbank(bad);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  b = small_bank();
  b.transfer->coefficients[3] = {std::nanf(""), 0.0f};
  EXPECT_NE(message(b).find("coefficient 3 is not finite"), std::string::npos) << message(b);
  b = small_bank();
  b.transfer->modes.pop_back();
  EXPECT_NE(message(b).find("transfer has 1 modes but the bank has 2"), std::string::npos);
  b = small_bank();
  b.transfer->coefficients.pop_back();
  EXPECT_NE(message(b).find("needs more coefficients"), std::string::npos) << message(b);
}

TEST(Soundbank, ModalModelCarriesShapesAndRadiation) {
  const Soundbank b = small_bank();
  const ModalModel m = to_modal_model(b, "bank");
  ASSERT_EQ(m.mode_count(), 2u);
  EXPECT_EQ(m.points.size(), 4u);
  EXPECT_FLOAT_EQ(float(m.shape(1, 2)[1]), b.shapes[(1 * 4 + 2) * 3 + 1]);
  for (double r : m.radiation) EXPECT_GT(r, 0);
  ASSERT_TRUE(m.transfer.has_value());
  EXPECT_EQ(m.transfer->mode_count(), 2u);
  EXPECT_NO_THROW(m.validate());
  // keep_modes keeps the transfer of the kept modes only.
  ModalModel k = m;
  keep_modes(k, {1});
  ASSERT_TRUE(k.transfer.has_value());
  ASSERT_EQ(k.transfer->mode_count(), 1u);
  EXPECT_EQ(k.transfer->modes[0].order, 2u);
  EXPECT_EQ(k.transfer->coefficients.size(), 9u);
  EXPECT_EQ(k.transfer->coefficients[4], m.transfer->coefficients_of(1)[4]);
}

TEST(Soundbank, CompactSourceGainHasTheQuadrupoleTerm) {
  // A sphere whose mode has normal displacement P_2(cos t): no net volume, no dipole moment. Its
  // volume-velocity far field is 4 pi a^2 j_2(ka) P_2 per unit displacement (plane-wave
  // expansion), rms over directions sqrt(1/5) of that; at ka = 0.1 the Taylor quadrupole is it.
  const double a = 0.1, k = 1.0;
  const auto sphere = test::icosphere(a, 3);
  Soundbank b;
  b.vertices = sphere.vertices;
  b.triangles = sphere.triangles;
  b.omega = {k * 343.0};
  b.decay = {1.0};
  for (const Vec3& v : b.vertices) {
    const Vec3 n = scale(v, 1.0 / norm(v));
    b.normals.push_back({float(n[0]), float(n[1]), float(n[2])});
    const double p2 = std::legendre(2u, n[2]);
    for (int c = 0; c < 3; ++c) b.shapes.push_back(float(n[c] * p2));
  }
  const ModalModel m = to_modal_model(b, "p2");
  double j2[3];
  sph_bessel_j(2, k * a, j2);
  const double want =
      1.204 / (4 * std::numbers::pi) * 4 * std::numbers::pi * a * a * j2[2] * std::sqrt(1.0 / 5);
  EXPECT_NEAR(m.radiation[0], want, 0.03 * want);
}

TEST(Soundbank, TransferMethodRoundTripsAndUnknownOnesAreRefused) {
  Soundbank b = small_bank();
  b.transfer->modes[1].method = TransferMethod::Bem;
  b.transfer->modes[1].iterations = 17;
  Soundbank r = parse_soundbank(serialize_soundbank(b), "mem");
  EXPECT_EQ(r.transfer->modes[0].method, TransferMethod::Sources);
  EXPECT_EQ(r.transfer->modes[1].method, TransferMethod::Bem);
  EXPECT_EQ(r.transfer->modes[1].iterations, 17);
  b.transfer->modes[0].method = TransferMethod::Wave;  // format 1.3
  r = parse_soundbank(serialize_soundbank(b), "mem");
  EXPECT_EQ(r.transfer->modes[0].method, TransferMethod::Wave);
  EXPECT_STREQ(to_string(r.transfer->modes[0].method), "wave");
  b.transfer->modes[0].method = static_cast<TransferMethod>(7);
  try {
    parse_soundbank(serialize_soundbank(b), "mem");
    FAIL() << "accepted an unknown transfer method";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mode 0 has unknown transfer method 7"), std::string::npos)
        << e.what();
  }
}
