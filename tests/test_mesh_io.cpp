// The mesh readers: the same solid from every format and encoding, and malformed files refused
// with the file, the line or element, and what is wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "chladni/core/error.hpp"
#include "chladni/precompute/surface_mesh.hpp"
#include "test_support.hpp"

using namespace chladni;
using namespace chladni::precompute;

namespace {

// Unit cube, outward counter-clockwise triangles.
const float kFloatCubeV[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                 {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kFloatCubeF[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string xyz(const float* v) {
  return std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]);
}

std::string write_bytes(const std::string& name, const std::string& bytes) {
  const std::string path = chladni::test::temp_path(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

template <class T>
void put(std::string& s, T v, bool big = false) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

std::string ply_binary(bool big) {
  std::string s = std::string("ply\nformat ") +
                  (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\ncomment made by a test\nelement vertex 8\nproperty double x\n"
                  "property double y\nproperty double z\nproperty uchar red\n"
                  "element face 12\nproperty list uchar uint vertex_indices\n"
                  "property list uchar float texcoord\nend_header\n";
  for (auto& v : kFloatCubeV) {
    for (int k = 0; k < 3; ++k) put<double>(s, v[k], big);
    put<uint8_t>(s, 200);
  }
  for (auto& f : kFloatCubeF) {
    put<uint8_t>(s, 3);
    for (int k = 0; k < 3; ++k) put<uint32_t>(s, uint32_t(f[k]), big);
    put<uint8_t>(s, 2);
    put<float>(s, 0.5f, big), put<float>(s, 0.25f, big);
  }
  return s;
}

std::string stl_binary(uint32_t claimed) {
  std::string s = "solid but actually binary";
  s.resize(80, ' ');
  put<uint32_t>(s, claimed);
  for (auto& f : kFloatCubeF) {
    for (int k = 0; k < 3; ++k) put<float>(s, 0.f);
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) put<float>(s, kFloatCubeV[f[c]][k]);
    put<uint16_t>(s, 0);
  }
  return s;
}

std::map<std::string, std::string> cube_files() {
  std::string obj = "# cube\nmtllib x.mtl\no cube\n", off = "COFF\n# counts\n8 12 0\n",
              ply =
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float "
                  "y\nproperty float z\nelement face 12\nproperty list uchar int "
                  "vertex_indices\nend_header\n",
              stl = "solid cube\n";
  for (auto& v : kFloatCubeV) {
    obj += "v " + xyz(v) + "\r\nvn 0 0 1\n";
    off += xyz(v) + " 255 0 0 255  # a coloured vertex\n";
    ply += xyz(v) + "\n";
  }
  for (auto& f : kFloatCubeF) {
    // Negative (relative) indices and v//n corners in OBJ.
    obj += "f " + std::to_string(f[0] - 8) + "//1 " + std::to_string(f[1] + 1) + "/1/1 " +
           std::to_string(f[2] + 1) + "\n";
    off += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
           "\n";
    ply += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
           "\n";
    stl += "facet normal 0 0 0\n outer loop\n";
    for (int k = 0; k < 3; ++k) stl += "  vertex " + xyz(kFloatCubeV[f[k]]) + "\n";
    stl += " endloop\nendfacet\n";
  }
  stl += "endsolid cube\n";
  // As Windows editors save text: a byte-order mark before the first keyword.
  const std::string bom = "\xEF\xBB\xBF";
  return {{"c.obj", obj},
          {"bom.obj", bom + obj.substr(obj.find("v "))},
          {"bom.off", bom + off},
          {"bom.ply", bom + ply},
          {"c.off", off},
          {"c.ply", ply},
          {"cle.ply", ply_binary(false)},
          {"cbe.ply", ply_binary(true)},
          {"c.STL", stl},
          {"cb.stl", stl_binary(12)}};
}

std::string message(const std::string& name, const std::string& bytes) {
  try {
    read_mesh(write_bytes("chladni_io_" + name, bytes));
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(MeshIo, ReadsTheSameCubeFromEveryFormatAndEncoding) {
  for (const auto& [name, bytes] : cube_files()) {
    const SurfaceMesh m = read_mesh(write_bytes("chladni_io_" + name, bytes), 0.01);
    ASSERT_EQ(m.vertices.size(), 8u) << name;  // STL corners are welded into 8 vertices
    ASSERT_EQ(m.triangles.size(), 12u) << name;
    double volume = 0;  // divergence theorem: the 1 cm cube, outward faces
    for (const auto& t : m.triangles) {
      const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
      volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0])) /
                6;
    }
    EXPECT_NEAR(volume, 1e-6, 1e-12) << name;
  }
}

TEST(MeshIo, QuadsAreFanTriangulated) {
  const SurfaceMesh m = read_mesh(chladni::test::write_temp(
      "chladni_io_quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
}

TEST(MeshIo, UnitsScaleCoordinates) {
  EXPECT_DOUBLE_EQ(unit_scale("mm"), 0.001);
  EXPECT_DOUBLE_EQ(unit_scale("cm"), 0.01);
  EXPECT_THROW(unit_scale("inch"), InputError);
  const SurfaceMesh m =
      read_mesh(write_bytes("chladni_io_u.obj", cube_files()["c.obj"]), unit_scale("mm") * 2);
  EXPECT_DOUBLE_EQ(m.vertices[6][0], 0.002);
}

// Each malformed file is refused with its name, where, and what.
TEST(MeshIo, MalformedFilesNameTheFileThePlaceAndTheProblem) {
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\n";
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const std::pair<std::string, std::string> cases[][2] = {
      {{"nan.obj", tri + "v 0 nan 0\nf 1 2 3\n"}, {"nan.obj:4", "'nan' is not finite"}},
      {{"word.obj", "v 0 0 0\nv 1 0 zero\n"}, {"word.obj:2", "'zero' is not a number"}},
      {{"idx.obj", tri + "f 1 2 9\n"}, {"idx.obj:4", "refers to vertex 9 but the file has 3"}},
      {{"zero.obj", tri + "f 0 1 2\n"}, {"zero.obj:4", "vertex index 0"}},
      {{"two.obj", tri + "f 1 2\n"}, {"two.obj:4", "at least 3 corners"}},
      {{"empty.obj", "# nothing\n"}, {"empty.obj", "holds no faces"}},
      {{"big.obj", "v 1e400 0 0\n"}, {"big.obj:1", "out of range"}},
      {{"garbage.off", "OFF\n3 1 0\n0 0 0\nhello\n"}, {"garbage.off:4", "'hello' is not a number"}},
      {{"count.off", "OFF\n4000000000 1 0\n"}, {"count.off:2", "vertex count 4000000000"}},
      {{"short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"},
       {"short.off:6", "vertex index 3"}},
      {{"bin.off", "OFF BINARY\n"}, {"bin.off:1", "binary OFF"}},
      {{"typo.ply", ply_head.substr(0, 21) + "elemnt vertex 3\nend_header\n"},
       {"typo.ply:3", "unknown PLY header keyword 'elemnt'"}},
      {{"noend.ply", ply_head}, {"noend.ply", "no end_header"}},
      {{"huge.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n"},
       {"huge.ply", "'vertex' elements: 4294967295 do not fit"}},
      {{"list.ply", ply_head +
                        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                        "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"},
       {"list.ply", "refers to vertex 7 but the file has 3"}},
      {{"type.ply", ply_head + "property quad w\nend_header\n"},
       {"type.ply:7", "unknown PLY property type 'quad'"}},
      {{"noface.ply", ply_head + "end_header\n0 0 0\n1 0 0\n0 1 0\n"},
       {"noface.ply", "both a vertex and a face element"}},
      {{"trunc.stl", stl_binary(13)}, {"trunc.stl", "a header counting 13 triangles needs 734"}},
      {{"word.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nendloop\n"},
       {"word.stl:6", "'endloop' is not a number"}},
      {{"cut.stl", "solid x\nfacet normal 0 0 1\nouter loop\n"},
       {"cut.stl:", "the file ends where 'vertex' was expected"}},
  };
  for (const auto& [file, expect] : cases) {
    const std::string msg = message(file.first, file.second);
    EXPECT_NE(msg.find("chladni_io_" + expect.first), std::string::npos) << msg;
    EXPECT_NE(msg.find(expect.second), std::string::npos) << msg;
  }
}

TEST(MeshIo, MissingDirectoryAndForeignPathsAreRefused) {
  auto msg = [](const std::string& path) {
    try {
      read_mesh(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(msg("/nonexistent/a.obj").find("mesh /nonexistent/a.obj: cannot open"),
            std::string::npos);
  EXPECT_NE(msg(chladni::test::temp_path("")).find("unsupported mesh format"), std::string::npos);
  std::filesystem::create_directories(chladni::test::temp_path("chladni_io_dir.obj"));
  EXPECT_NE(msg(chladni::test::temp_path("chladni_io_dir.obj")).find("is a directory"),
            std::string::npos);
  EXPECT_NE(
      msg(chladni::test::write_temp("chladni_io.xyz", "1 2 3\n")).find("unsupported mesh format"),
      std::string::npos);
}
