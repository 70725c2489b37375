// Paper sound: the animation format, the sheet's geometry and the per-frame analysis
// (Schreck et al. 2016, §4) against the generated scenarios, whose event frames are known.
#include <gtest/gtest.h>
#include <zlib.h>

#include <sys/wait.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/runtime/paper/paper_analysis.hpp"
#include "chladni/tools/paper_scenarios.hpp"
#include "cli_support.hpp"
#include "paper_fixtures.hpp"
#include "test_support.hpp"

namespace {

using namespace chladni;
using runtime::PaperAnalyzer;
using runtime::PaperEventType;
using test::cylinder;
using test::two_frames;

// Frames with crumpling events, and the largest amplitude among them.
std::vector<std::pair<std::uint32_t, double>> crumple_frames(const PaperAnimation& a) {
  PaperAnalyzer an(a);
  std::vector<std::pair<std::uint32_t, double>> out;
  for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
    double amp = 0;
    for (const auto& e : an.analyze(f).events) {
      EXPECT_EQ(e.type, PaperEventType::Crumple);
      amp = std::max(amp, e.amplitude);
    }
    if (amp > 0) out.push_back({f, amp});
  }
  return out;
}

bool near_any(std::uint32_t f, const std::vector<std::uint32_t>& frames, std::uint32_t tol) {
  for (std::uint32_t g : frames)
    if (f + tol >= g && f <= g + tol) return true;
  return false;
}

}  // namespace

TEST(PaperMesh, TopologyOrientsFacesAndRefusesNonManifoldSheets) {
  // 3 x 3 vertex grid, one face given the wrong way round.
  std::vector<std::array<std::uint32_t, 3>> tris = {{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4},
                                                    {3, 4, 7}, {3, 7, 6}, {4, 5, 8}, {4, 8, 7}};
  std::swap(tris[3][1], tris[3][2]);
  const auto t = runtime::PaperTopology::build(9, tris);
  EXPECT_EQ(t.flipped_faces, 1u);
  EXPECT_EQ(t.edges.size(), 16u);  // 12 grid edges + 4 diagonals
  std::size_t border = 0;
  for (std::uint32_t e = 0; e < t.edges.size(); ++e) {
    border += t.border(e);
    if (t.border(e)) continue;
    // Consistent: the two faces walk every interior edge in opposite directions.
    int forward = 0;
    for (std::int32_t f : t.edge_faces[e]) {
      const auto& tri = t.triangles[std::size_t(f)];
      for (int k = 0; k < 3; ++k)
        forward += tri[k] == t.edges[e][0] && tri[(k + 1) % 3] == t.edges[e][1];
    }
    EXPECT_EQ(forward, 1) << "edge " << e;
  }
  EXPECT_EQ(border, 8u);

  tris.push_back({4, 0, 2});  // a third face on the interior edge (0, 4)
  try {
    runtime::PaperTopology::build(9, tris);
    FAIL() << "a non-manifold edge was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("non-manifold"), std::string::npos) << e.what();
  }
  // A Moebius strip: 4 quads in a ring whose last one joins with a half twist.
  const std::vector<std::array<std::uint32_t, 3>> mobius = {
      {0, 1, 3}, {0, 3, 2}, {2, 3, 5}, {2, 5, 4}, {4, 5, 7}, {4, 7, 6}, {6, 7, 0}, {6, 0, 1}};
  try {
    runtime::PaperTopology::build(8, mobius);
    FAIL() << "a Moebius strip was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not orientable"), std::string::npos) << e.what();
  }
}

TEST(PaperMesh, CylinderCurvatureAndRulingsMatchTheAnalyticValues) {
  const double r = 0.08, W = 0.2, L = 0.2;
  const auto a = two_frames(
      21, 21, W, L, [&](double u, double v) { return cylinder(u, v, r); },
      [&](double u, double v) {
        return Vec3{u, v, 0};
      });
  const auto topo = runtime::PaperTopology::build(a.vertex_count, a.triangles);
  runtime::PaperGeometry g;
  g.update(topo, a.frame(0));
  g.update_shape(topo);
  // Interior vertices: H = 1 / (2r) in magnitude; faces: principal curvature 1/r, ruling = x.
  for (std::uint32_t j = 2; j + 2 < 21; ++j)
    for (std::uint32_t i = 2; i + 2 < 21; ++i)
      EXPECT_NEAR(std::abs(g.mean_curvature[j * 21 + i]), 1 / (2 * r), 0.03 / (2 * r));
  double worst_k = 0, worst_dir = 1;
  for (std::size_t f = 0; f < topo.triangles.size(); ++f) {
    bool interior = true;
    for (std::uint32_t v : topo.triangles[f])
      interior &= v % 21 >= 1 && v % 21 <= 19 && v / 21 >= 1 && v / 21 <= 19;
    if (!interior) continue;
    worst_k = std::max(worst_k, std::abs(g.face_curvature[f] * r - 1));
    worst_dir = std::min(worst_dir, std::abs(g.ruling[f][0]));
  }
  EXPECT_LT(worst_k, 0.05);
  EXPECT_GT(worst_dir, 0.999);
  g.update(topo, a.frame(1));  // flat
  g.update_shape(topo);
  for (double h : g.mean_curvature) EXPECT_NEAR(h, 0.0, 1e-6);
  for (double k : g.face_curvature) EXPECT_NEAR(k, 0.0, 1e-6);
}

TEST(PaperAnalysis, FlapSnapsAreCrumplesOfTheWholeSheetAtTheirFrames) {
  for (std::uint32_t tris : {200u, 2000u}) {
    tools::PaperScenarioOptions o;
    o.triangles = tris;
    const auto s = tools::make_paper_scenario("flap", o);
    const auto got = crumple_frames(s.animation);
    ASSERT_EQ(got.size(), s.event_frames.size()) << tris << " triangles";
    for (std::size_t k = 0; k < got.size(); ++k)
      EXPECT_LE(std::abs(int(got[k].first) - int(s.event_frames[k])), 2) << k;
    // The whole sheet vibrates: one curved resonator, free along both bent edges.
    PaperAnalyzer an(s.animation);
    for (std::uint32_t f = 0; f <= got[0].first; ++f) {
      const auto fa = an.analyze(f);
      if (f < got[0].first) continue;
      ASSERT_EQ(fa.events.size(), 1u);
      ASSERT_EQ(fa.events[0].resonators.size(), 1u);
      const auto& r = fa.events[0].resonators[0];
      EXPECT_TRUE(r.curved);
      EXPECT_FALSE(r.constrained);
      EXPECT_NEAR(r.ruling_length, s.sheet_width, 0.02 * s.sheet_width);
      EXPECT_NEAR(r.free_border, 2 * s.sheet_length, 0.15 * 2 * s.sheet_length);
      EXPECT_NEAR(r.area, s.sheet_width * s.sheet_length, 0.02 * s.sheet_width * s.sheet_length);
    }
  }
}

TEST(PaperAnalysis, ShakeReversalsAreCrumplesAtTheTurningPoints) {
  const auto s = tools::make_paper_scenario("shake", {});
  const auto got = crumple_frames(s.animation);
  ASSERT_EQ(got.size(), s.event_frames.size());
  for (std::size_t k = 0; k < got.size(); ++k)
    EXPECT_LE(std::abs(int(got[k].first) - int(s.event_frames[k])), 2) << k;
}

TEST(PaperAnalysis, SlidingSheetRubsTheTableAndItsCurlResonates) {
  const auto s = tools::make_paper_scenario("slide", {});
  PaperAnalyzer an(s.animation);
  double first_lc = -1, last_lc = 0, last_lr = 0;
  for (std::uint32_t f = 0; f < s.animation.frame_count(); ++f) {
    const auto fa = an.analyze(f);
    if (f == 0) {
      EXPECT_TRUE(fa.events.empty());
      continue;
    }
    ASSERT_EQ(fa.events.size(), 1u) << "frame " << f;
    const auto& e = fa.events[0];
    EXPECT_EQ(e.type, PaperEventType::Friction);
    EXPECT_EQ(e.obstacle, 0);
    EXPECT_NEAR(e.amplitude, 0.05, 0.001);  // the sliding speed, m/s
    // The part lying on the table is one constrained resonator.
    std::size_t flat = 0;
    for (const auto& r : e.resonators) {
      if (r.curved) {
        if (first_lc < 0) first_lc = r.free_border;
        last_lc = r.free_border, last_lr = r.ruling_length;
      } else {
        ++flat;
        EXPECT_TRUE(r.constrained);
      }
    }
    EXPECT_EQ(flat, 1u) << "frame " << f;
  }
  // The curl grows (l_c) and spans the sheet's width along its rulings (l_r).
  EXPECT_GT(last_lc, 3 * first_lc);
  EXPECT_NEAR(last_lr, s.sheet_width, 0.15 * s.sheet_width);
}

TEST(PaperAnalysis, CrumpleEventsFallAtTheSnapsOfItsBumps) {
  tools::PaperScenarioOptions o;
  o.triangles = 2000;
  const auto s = tools::make_paper_scenario("crumple", o);
  const auto got = crumple_frames(s.animation);
  double peak = 0;
  for (const auto& [f, amp] : got) peak = std::max(peak, amp);
  // Every snap is heard, and every strong event is a snap (weak ones are curvature drifting
  // through the threshold as the sheet is squeezed).
  for (std::uint32_t snap_frame : s.event_frames) {
    bool found = false;
    for (const auto& [f, amp] : got) found |= f + 2 >= snap_frame && f <= snap_frame + 2;
    EXPECT_TRUE(found) << "no event near frame " << snap_frame;
  }
  for (const auto& [f, amp] : got)
    if (amp > 0.2 * peak) {
      EXPECT_TRUE(near_any(f, s.event_frames, 2)) << "frame " << f;
    }
}

TEST(PaperAnalysis, RidgesAndAnchorsStopTheVibration) {
  // Creased at v = L/2 by 1.2 rad (> a_max); the half beyond the crease flips its bend.
  const double W = 0.2, L = 0.2, crease = 1.2;
  auto sheet = [&](double bend_sign) {
    return [=](double u, double v) -> Vec3 {
      if (v <= L / 2) return {u, v, 0.3};
      const double s = v - L / 2, r = 0.1 * bend_sign;
      // Cylindrical bend of radius |r| after the crease, in the creased half's plane.
      const double along = r * std::sin(s / r), up = r * (1 - std::cos(s / r));
      return {u, L / 2 + along * std::cos(crease) - up * std::sin(crease),
              0.3 + along * std::sin(crease) + up * std::cos(crease)};
    };
  };
  auto a = two_frames(21, 41, W, L, sheet(1.0), sheet(-1.0));
  PaperAnalyzer an(a);
  an.analyze(0);
  const auto fa = an.analyze(1);
  ASSERT_FALSE(fa.events.empty());
  double area = 0;
  for (const auto& e : fa.events)
    for (const auto& r : e.resonators) area += r.area;
  EXPECT_NEAR(area, W * L / 2, 0.12 * W * L / 2) << "the flood crossed the crease";

  // The same flip with no crease but the middle line held by a ruler: stops there too.
  auto flat_then = [&](double sign) {
    return [=](double u, double v) -> Vec3 {
      if (v <= L / 2) return {u, v, 0.3};
      const double s = v - L / 2, r = 0.1 * sign;
      return {u, L / 2 + r * std::sin(s / r), 0.3 + r * (1 - std::cos(s / r))};
    };
  };
  auto b = two_frames(21, 41, W, L, flat_then(1.0), flat_then(-1.0));
  PaperAnchor ruler;
  for (std::uint32_t i = 0; i < 21; ++i) ruler.vertices.push_back(20 * 21 + i);
  ruler.last_frame = 1;
  b.anchors = {ruler};
  PaperAnalyzer bn(b);
  bn.analyze(0);
  area = 0;
  for (const auto& e : bn.analyze(1).events)
    for (const auto& r : e.resonators) area += r.area;
  EXPECT_NEAR(area, W * L / 2, 0.12 * W * L / 2) << "the flood crossed the held line";
}

TEST(PaperFormat, ObjAndBinaryFramesRoundTrip) {
  tools::PaperScenarioOptions o;
  o.triangles = 100;
  o.duration = 0.1;
  const auto s = tools::make_paper_scenario("shake", o);
  for (auto storage : {PaperFrameStorage::Obj, PaperFrameStorage::Binary}) {
    const std::string dir =
        test::temp_path(storage == PaperFrameStorage::Obj ? "paper_rt_obj" : "paper_rt_bin");
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    write_paper_animation(dir + "/shake.json", s.animation, storage);
    const PaperAnimation b = load_paper_animation(dir + "/shake.json");
    EXPECT_EQ(b.vertex_count, s.animation.vertex_count);
    EXPECT_EQ(b.triangles, s.animation.triangles);
    ASSERT_EQ(b.positions.size(), s.animation.positions.size());
    for (std::size_t i = 0; i < b.positions.size(); ++i)
      EXPECT_NEAR(b.positions[i], s.animation.positions[i], 1e-6) << i;
    EXPECT_EQ(b.frame_rate, s.animation.frame_rate);
    ASSERT_EQ(b.anchors.size(), 1u);
    EXPECT_EQ(b.anchors[0].vertices, s.animation.anchors[0].vertices);
    EXPECT_EQ(b.anchors[0].last_frame, s.animation.anchors[0].last_frame);
    ASSERT_EQ(b.obstacles.size(), 1u);
    EXPECT_EQ(b.obstacles[0].name, "table");
    EXPECT_EQ(b.event_frames, s.animation.event_frames);
    EXPECT_EQ(b.listener.position, s.animation.listener.position);
  }
}

namespace {
std::string load_error(const std::string& path) {
  try {
    load_paper_animation(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}
void expect_has(const std::string& msg, const std::string& part) {
  EXPECT_NE(msg.find(part), std::string::npos) << "message: " << msg << "\nexpected: " << part;
}
}  // namespace

namespace {
// A small flap animation written to a fresh folder `name` (OBJ frames, or one binary file).
struct BadInputCase {
  std::string dir, json;
  tools::PaperScenario scenario;
  BadInputCase(const std::string& name, PaperFrameStorage storage) {
    tools::PaperScenarioOptions o;
    o.triangles = 50;
    o.duration = 0.05;
    scenario = tools::make_paper_scenario("flap", o);
    dir = test::temp_path(name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    json = dir + "/flap.json";
    write_paper_animation(json, scenario.animation, storage);
  }
};
}  // namespace

TEST(PaperFormat, BadObjFramesNameFileFrameAndProblem) {
  const BadInputCase c("paper_bad_obj", PaperFrameStorage::Obj);
  const std::string &dir = c.dir, &json = c.json;
  const std::string frame1 = dir + "/flap/flap_0001.obj";
  std::ifstream in(frame1);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();

  // Topology change: frame 1 joins other vertices.
  std::string bad = good;
  const auto fpos = bad.find("\nf ");
  bad.replace(fpos, bad.find('\n', fpos + 1) - fpos, "\nf 1 2 5");
  std::ofstream(frame1) << bad;
  std::string msg = load_error(json);
  expect_has(msg, "flap_0001.obj");
  expect_has(msg, "topology changed");

  // A NaN coordinate names file and line.
  bad = good;
  bad.replace(0, bad.find('\n'), "v nan 0 0");
  std::ofstream(frame1) << bad;
  msg = load_error(json);
  expect_has(msg, "flap_0001.obj:1");
  expect_has(msg, "non-finite");

  // A missing frame.
  std::filesystem::remove(frame1);
  msg = load_error(json);
  expect_has(msg, "frame 1");
  expect_has(msg, "missing frame");
  std::ofstream(frame1) << good;
  EXPECT_EQ(load_error(json), "(accepted)");
}

TEST(PaperFormat, BadJsonNamesItsPath) {
  const BadInputCase c("paper_bad_json", PaperFrameStorage::Obj);
  const std::string &dir = c.dir, &json = c.json;
  // JSON problems name their path.
  auto with = [&](const std::string& from, const std::string& to) {
    std::ifstream j(json);
    std::string text((std::istreambuf_iterator<char>(j)), std::istreambuf_iterator<char>());
    const auto p = text.find(from);
    EXPECT_NE(p, std::string::npos) << from;
    text.replace(p, from.size(), to);
    const std::string path = dir + "/edited.json";
    std::ofstream(path) << text;
    return load_error(path);
  };
  expect_has(with("\"frame_rate\"", "\"frame_rat\""), "unknown field 'frame_rat'");
  expect_has(with("\"vertices\": [", "\"vertices\": [99999,"), "anchors[0]");
  expect_has(with("\"normal\": [", "\"normal\": [0, 0, 0], \"x\": ["), "obstacles[0]");
  expect_has(with("{", "{,"), "edited.json:1:");
  // A frame rate that would turn the frames into days of sound, or a division by almost zero.
  expect_has(with("\"frame_rate\": 60.0", "\"frame_rate\": 1e-300"),
             "frame_rate must lie in [1, 10000]");
  expect_has(with("\"frame_rate\": 60.0", "\"frame_rate\": 0.01"),
             "frame_rate must lie in [1, 10000]");
  expect_has(with("\"frame_rate\": 60.0", "\"frame_rate\": 60.0, \"frame_rate\": 30"),
             "duplicate key 'frame_rate'");
}

TEST(PaperFormat, BadBinaryFramesAreRefusedBeforeAllocating) {
  const BadInputCase c("paper_bad_bin", PaperFrameStorage::Obj);
  const std::string& dir = c.dir;
  const auto& s = c.scenario;
  // Binary frames: a flipped byte is a checksum error, a cut file too.
  write_paper_animation(dir + "/bin.json", s.animation, PaperFrameStorage::Binary);
  const std::string bin = dir + "/bin.chpaper";
  std::fstream f(bin, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(40);
  f.put('\x7f');
  f.close();
  expect_has(load_error(dir + "/bin.json"), "checksum");
  std::filesystem::resize_file(bin, 30);
  expect_has(load_error(dir + "/bin.json"), "bin.chpaper");

  // A .chpaper claiming 2^32 - 1 triangles with a valid checksum is refused before allocating.
  {
    std::vector<uint8_t> b = {'C', 'H', 'P', 'A', 'P', 'E', 'R', '1'};
    for (uint32_t v : {1u, 4u, 0xffffffffu, 2u}) {  // version, vertices, triangles, frames
      for (int k = 0; k < 4; ++k) b.push_back(uint8_t(v >> (8 * k)));
    }
    b.resize(b.size() + 64, 0);
    const uint32_t c = uint32_t(crc32(crc32(0L, Z_NULL, 0), b.data(), uInt(b.size())));
    for (int k = 0; k < 4; ++k) b.push_back(uint8_t(c >> (8 * k)));
    std::ofstream(bin, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
    const std::string m = load_error(dir + "/bin.json");
    expect_has(m, "bin.chpaper");
    expect_has(m, "do not fit");
  }
  // The frame file given as a directory.
  std::filesystem::remove(bin);
  std::filesystem::create_directories(bin);
  expect_has(load_error(dir + "/bin.json"), "bin.chpaper: is a directory");
}

TEST(PaperCli, GeneratesAndAnalysesTheExamples) {
  const std::string dir = test::temp_path("paper_cli");
  std::filesystem::remove_all(dir);
  const std::string exe = CHLADNI_EXE;
  ASSERT_EQ(
      std::system((exe + " paper-gen all -o " + dir + " --triangles 200 > /dev/null").c_str()), 0);
  for (const std::string n : {"slide", "shake", "flap", "crumple"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + n + ".json")) << n;
  const std::string events = dir + "/flap_events.json";
  ASSERT_EQ(std::system(("CHLADNI_CACHE_DIR=" + dir + "/cache " + exe + " paper " + dir +
                         "/flap.json --events " + events + " > /dev/null")
                            .c_str()),
            0);
  std::ifstream in(events);
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("event_frames").size(), 4u);
  // Bad input: exit code 2.
  const int status = std::system((exe + " paper " + dir + "/nope.json 2> /dev/null").c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

TEST(PaperCli, DefaultDatabaseIsCachedOnceAndADamagedCacheIsRebuilt) {
  const std::string dir = test::temp_path("paper_cache");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string env = "CHLADNI_CACHE_DIR=" + dir + "/cache";
  auto paper = [&](const std::string& wav, const std::string& e) {
    return test::run_cli(
        "paper " CHLADNI_SOURCE_DIR "/meshes/paper/slide.json -o " + dir + "/" + wav, e);
  };
  auto bytes = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  // The same samples (the files' PEAK chunks carry a time stamp).
  auto same = [&](const std::string& a, const std::string& b) {
    return read_audio(dir + "/" + a).samples == read_audio(dir + "/" + b).samples;
  };
  test::CliResult r = paper("a.wav", env);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("generated the default paper sound database"), std::string::npos);
  EXPECT_NE(r.output.find("cached in " + dir + "/cache/"), std::string::npos) << r.output;
  std::string snapshot;
  for (const auto& f : std::filesystem::directory_iterator(dir + "/cache")) snapshot = f.path();
  ASSERT_FALSE(snapshot.empty());
  // From the cache: the same sound, sample for sample.
  r = paper("b.wav", env);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("read the default paper sound database from " + snapshot),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(same("a.wav", "b.wav"));
  // A damaged byte, then a truncated file: each is noticed, regenerated and replaced.
  std::string snap = bytes(snapshot);
  snap[snap.size() / 2] ^= 0x40;
  std::ofstream(snapshot, std::ios::binary) << snap;
  r = paper("c.wav", env);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("CRC mismatch"), std::string::npos) << r.output;
  EXPECT_TRUE(same("a.wav", "c.wav"));
  std::filesystem::resize_file(snapshot, 1000);
  r = paper("d.wav", env);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("unusable"), std::string::npos) << r.output;
  r = paper("e.wav", env);
  EXPECT_NE(r.output.find("read the default paper sound database"), std::string::npos) << r.output;
  // An empty CHLADNI_CACHE_DIR caches nothing.
  r = paper("f.wav", "CHLADNI_CACHE_DIR=");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find("cached"), std::string::npos) << r.output;
  EXPECT_TRUE(same("a.wav", "f.wav"));
}

TEST(PaperExamples, ShippedAnimationsHaveTheirEventsAtTheirFrames) {
  for (const std::string n : {"slide", "shake", "flap", "crumple"}) {
    const PaperAnimation a =
        load_paper_animation(CHLADNI_SOURCE_DIR "/meshes/paper/" + n + ".json");
    ASSERT_FALSE(a.event_frames.empty()) << n;
    PaperAnalyzer an(a);
    std::vector<std::uint32_t> friction, crumple;
    double peak = 0;
    std::vector<std::pair<std::uint32_t, double>> strong;
    for (std::uint32_t f = 0; f < a.frame_count(); ++f) {
      for (const auto& e : an.analyze(f).events) {
        EXPECT_FALSE(e.resonators.empty()) << n << " frame " << f;
        if (e.type == PaperEventType::Friction) {
          friction.push_back(f);
        } else {
          crumple.push_back(f);
          peak = std::max(peak, e.amplitude);
          strong.push_back({f, e.amplitude});
        }
      }
    }
    if (n == "slide") {
      // Rubbing on every frame from the first to the last of the slide, and nothing else.
      EXPECT_EQ(friction.size(), a.frame_count() - 1) << n;
      EXPECT_EQ(friction.front(), a.event_frames.front());
      EXPECT_EQ(friction.back(), a.event_frames.back());
      EXPECT_TRUE(crumple.empty());
      continue;
    }
    EXPECT_TRUE(friction.empty()) << n;
    for (std::uint32_t g : a.event_frames)
      EXPECT_TRUE(near_any(g, crumple, 2)) << n << ": no crumple near frame " << g;
    for (const auto& [f, amp] : strong) {
      if (amp > 0.2 * peak) {
        EXPECT_TRUE(near_any(f, a.event_frames, 2)) << n << ": unexpected crumple at " << f;
      }
    }
  }
}
