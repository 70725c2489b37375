// Scene parsing: a good scene, and each kind of bad input named by its JSON path.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

#include "chladni/core/error.hpp"
#include "chladni/core/scene.hpp"

using namespace chladni;
using nlohmann::json;

namespace {

json good() {
  return json::parse(R"({
    "sample_rate": 44100, "channels": 1,
    "listener": {"position": [0, 0, 0]},
    "objects": [
      {"name": "bar", "position": [0, 1, 0], "bar": {"length": 0.3, "damping": "rayleigh:1,1e-9"}},
      {"name": "cup", "modes": [{"frequency": 800, "decay": 3, "amplitude": 0.1}]}
    ],
    "events": [
      {"time": 0.5, "type": "impact", "object": "cup", "impulse": 0.01},
      {"time": 0.1, "type": "impact", "object": "bar", "impulse": 0.02, "vertex": 3,
       "direction": [0, 0, -2], "contact_time": 0.001}
    ]})");
}

std::string error_of(const json& j) {
  try {
    parse_scene(j, ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Scene, ParsesAGoodSceneAndSortsEvents) {
  const Scene s = parse_scene(good(), ".");
  EXPECT_EQ(s.sample_rate, 44100);
  EXPECT_EQ(s.channels, 1);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].source, SceneObject::Source::Bar);
  EXPECT_DOUBLE_EQ(s.objects[0].bar.damping.alpha[1], 1e-9);
  ASSERT_EQ(s.events.size(), 2u);
  EXPECT_DOUBLE_EQ(s.events[0].time, 0.1);  // sorted
  EXPECT_EQ(s.events[0].object, 0u);
  EXPECT_EQ(*s.events[0].vertex, 3u);
  EXPECT_NEAR(s.events[0].direction[2], -1.0, 1e-12);  // normalized
}

TEST(Scene, NamesTheJsonPathOfEachProblem) {
  struct Case {
    std::function<void(json&)> edit;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["events"][0].erase("time"); }, "$.events[0]: missing required field 'time'"},
      {[](json& j) { j["events"][1]["time"] = -1; }, "$.events[1].time: must lie in [0, 3600] s"},
      {[](json& j) { j["events"][0]["object"] = "plate"; },
       "$.events[0].object: unknown object 'plate'"},
      {[](json& j) { j["events"][0]["impulse"] = "hard"; },
       "$.events[0].impulse: expected a number, got string"},
      {[](json& j) { j["events"][0]["impluse"] = 1; }, "$.events[0]: unknown field 'impluse'"},
      {[](json& j) { j["events"][0]["type"] = "scrape"; },
       "$.events[0].type: unknown event type 'scrape'"},
      {[](json& j) {
         j["objects"][1]["modes"][0]["frequency"] = std::numeric_limits<double>::infinity();
       },
       "$.objects[1].modes[0].frequency: must be finite"},
      {[](json& j) { j["objects"][1]["modes"][0]["decay"] = -3; },
       "$.objects[1].modes[0].decay: must be >= 0"},
      {[](json& j) { j["objects"][1]["name"] = "bar"; }, "$.objects[1].name: duplicate name 'bar'"},
      {[](json& j) { j["objects"][0]["bar"]["poisson_ratio"] = 0.7; },
       "$.objects[0].bar.poisson_ratio: must lie in (-1, 0.5)"},
      {[](json& j) { j["objects"][0]["bar"]["damping"] = "viscous:1"; },
       "$.objects[0].bar.damping: damping 'viscous:1': unknown model"},
      {[](json& j) { j["objects"][1]["bar"] = json::object(); },
       "$.objects[1]: needs exactly one of"},
      {[](json& j) {
         j["listener"]["position"] = json::array({0, 1});
       },
       "$.listener.position: expected an array of 3 numbers"},
      {[](json& j) {
         j["events"][1]["direction"] = json::array({0, 0, 0});
       },
       "$.events[1].direction: must be a non-zero vector"},
      {[](json& j) { j["channels"] = 3; }, "$.channels: must be 1 or 2"},
      {[](json& j) { j.erase("objects"); }, "$: missing required field 'objects'"},
      {[](json& j) { j["events"] = json::object(); }, "$.events: expected an array, got object"},
  };
  for (const Case& c : cases) {
    json j = good();
    c.edit(j);
    const std::string err = error_of(j);
    EXPECT_NE(err.find(c.expect), std::string::npos) << "got: " << err << "\nwant: " << c.expect;
  }
}

TEST(Scene, SyntaxErrorsNameFileLineAndColumn) {
  const auto path = std::filesystem::temp_directory_path() / "chladni_bad_scene.json";
  {
    std::ofstream f(path);
    f << "{\n  \"objects\": [\n    {\"name\": \"a\", \"modes\": [NaN]}\n  ]\n}\n";
  }
  try {
    load_scene(path.string());
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path.string() + ":3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("syntax error"), std::string::npos) << msg;
  }
  EXPECT_THROW(load_scene("/nonexistent/scene.json"), InputError);
}

TEST(Scene, ResolvesSoundbankPathsAgainstTheSceneFolder) {
  json j = good();
  j["objects"][1].erase("modes");
  j["objects"][1]["soundbank"] = "banks/cup.chbank";
  const Scene s = parse_scene(j, "/data/scenes");
  EXPECT_EQ(s.objects[1].soundbank, "/data/scenes/banks/cup.chbank");
}

TEST(Scene, OrientationAndMoveEvents) {
  json j = good();
  j["objects"][0]["orientation"] = {2, 0, 0, 2};  // 90 degrees about z, normalized on reading
  j["events"].push_back(
      {{"time", 0.3}, {"type", "move"}, {"object", "cup"}, {"position", {1, 2, 3}}});
  j["events"].push_back(
      {{"time", 0.2}, {"type", "listener"}, {"position", {0, -1, 0}}, {"forward", {1, 0, 0}}});
  const Scene s = parse_scene(j, ".");
  const Quat& q = s.objects[0].orientation;
  EXPECT_NEAR(q[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(q[3], std::sqrt(0.5), 1e-12);
  const Vec3 x = rotate(q, {1, 0, 0});
  EXPECT_NEAR(x[1], 1.0, 1e-12);  // object x is world y
  const Vec3 back = rotate_inverse(q, x);
  EXPECT_NEAR(back[0], 1.0, 1e-12);
  ASSERT_EQ(s.events.size(), 2u);
  ASSERT_EQ(s.moves.size(), 2u);
  EXPECT_FALSE(s.moves[0].object.has_value());  // the listener, sorted first
  EXPECT_EQ(*s.moves[1].object, 1u);
  EXPECT_DOUBLE_EQ((*s.moves[1].position)[2], 3.0);

  j = good();
  j["objects"][0]["orientation"] = {0, 0, 0, 0};
  EXPECT_NE(error_of(j).find("$.objects[0].orientation: must be a non-zero quaternion"),
            std::string::npos)
      << error_of(j);
  j = good();
  j["events"].push_back({{"time", 0.3}, {"type", "move"}, {"object", "cup"}});
  EXPECT_NE(error_of(j).find("$.events[2]: a move event needs 'position' or 'orientation'"),
            std::string::npos)
      << error_of(j);
  j = good();
  j["events"].push_back({{"time", 0.3}, {"type", "listener"}, {"forward", {0, 0, 1}}});
  EXPECT_NE(error_of(j).find("must not be parallel"), std::string::npos) << error_of(j);
  j = good();
  j["events"].push_back({{"time", 0.3}, {"type", "teleport"}});
  EXPECT_NE(error_of(j).find(
                "unknown event type 'teleport' (known: impact, move, listener, shake, contact)"),
            std::string::npos)
      << error_of(j);
}

// nlohmann-json alone keeps the last of two equal keys and throws its own text for 1e400.
TEST(Scene, DuplicateKeysAndOverflowingNumbersNameFileAndPlace) {
  const auto error = [](const std::string& name, const std::string& text) {
    const auto path = std::filesystem::temp_directory_path() / name;
    std::ofstream(path) << text;
    try {
      load_scene(path.string());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  std::string msg = error("chladni_dup.json", R"({"objects": [{"name": "a", "gain": 1,
    "modes": [{"frequency": 440, "decay": 1, "amplitude": 1}], "gain": 2}], "events": []})");
  EXPECT_NE(msg.find("chladni_dup.json: $.objects[0]: duplicate key 'gain'"), std::string::npos)
      << msg;
  msg = error("chladni_dup2.json", R"({"sample_rate": 48000, "events": [], "sample_rate": 44100})");
  EXPECT_NE(msg.find("chladni_dup2.json: $: duplicate key 'sample_rate'"), std::string::npos)
      << msg;
  msg = error("chladni_big.json", "{\"objects\": [],\n \"gain\": 1e400}");
  EXPECT_NE(msg.find("chladni_big.json:2:10: the number 1e400 does not fit a double"),
            std::string::npos)
      << msg;
}

// A scene is held in memory while it renders: every time is bounded, so a typo cannot ask for
// a render of days (or silently drop an event at 1e300 s).
TEST(Scene, EventTimesAreBoundedToAnHour) {
  for (double t : {3600.5, 1e5, 1e300}) {
    json j = good();
    j["events"][0]["time"] = t;
    EXPECT_NE(error_of(j).find("$.events[0].time: must lie in [0, 3600] s"), std::string::npos)
        << t << ": " << error_of(j);
  }
  json j = good();
  j["events"][0]["time"] = 3600.0;
  EXPECT_EQ(error_of(j), "(no error)");
}

TEST(Scene, DirectoriesAndDevicesAreRefusedWithTheirName) {
  const auto error = [](const std::string& path) {
    try {
      load_scene(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string dir = std::filesystem::temp_directory_path().string();
  EXPECT_NE(error(dir).find("scene " + dir + ": is a directory"), std::string::npos);
  EXPECT_NE(error("/dev/zero").find("scene /dev/zero: is a device"), std::string::npos);
  EXPECT_NE(error("").find("the file name is empty"), std::string::npos);
}
