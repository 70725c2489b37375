// chladni report: the folder it writes and what it refuses, and the page in headless Chromium:
// no console error, a drawn view that follows the selected mode, and a click whose audio,
// rendered through an OfflineAudioContext, is the runtime's own render of that strike.
#include <gtest/gtest.h>

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>

#include "browser.hpp"
#include "chladni/core/audio_file.hpp"
#include "chladni/core/soundbank.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using chladni::test::run_cli;
using chladni::test::temp_path;
using nlohmann::json;

// The bar's 8 lowest modes (no transfer: compact-source gains), made once per process.
const std::string& bar_bank() {
  static const std::string bank = [] {
    const std::string b = temp_path("report_bar.chbank");
    const auto r = run_cli("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + b +
                           " --max-modes 8 --no-transfer --quiet");
    EXPECT_EQ(r.code, 0) << r.output;
    return b;
  }();
  return bank;
}

json report_data(const fs::path& dir) {
  const std::string text = chladni::test::read_file((dir / "bank-data.js").string()),
                    head = "window.CHLADNI_REPORT = ";
  EXPECT_EQ(text.rfind(head, 0), 0u);
  return json::parse(text.substr(head.size(), text.rfind(';') - head.size()));
}

// The page's mode table and `chladni info --json` describe a mode under the same names with the
// same values: one set of facts, from one place.
TEST(ReportCli, ModesCarryInfosNamesAndValues) {
  const fs::path dir = temp_path("report_names");
  fs::remove_all(dir);
  auto r = run_cli("report " + bar_bank() + " -o " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  const json page = report_data(dir);
  r = run_cli("info " + bar_bank() + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const json info = json::parse(r.output);
  ASSERT_EQ(page["modes"].size(), info["modes"].size());
  EXPECT_EQ(page["material"], info["material"]);
  for (std::size_t i = 0; i < page["modes"].size(); ++i) {
    const json& m = page["modes"][i];
    EXPECT_EQ(m["bank_index"].get<std::size_t>(), i);
    for (const auto& [key, value] : info["modes"][i].items()) {
      ASSERT_TRUE(m.contains(key)) << "mode " << i << " of the page has no " << key;
      EXPECT_EQ(m[key], value) << "mode " << i << ": " << key;
    }
  }
}

TEST(ReportCli, WritesTheFolderAndRefusesBadInput) {
  const fs::path dir = temp_path("report_cli");
  fs::remove_all(dir);
  auto r = run_cli("report " + bar_bank() + " -o " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f :
       {"index.html", "report.css", "viewer.js", "strike.js", "report.js", "bank-data.js"})
    EXPECT_GT(fs::file_size(dir / f), 100u) << f;
  const json j = report_data(dir);
  const chladni::Soundbank bank = chladni::read_soundbank(bar_bank());
  ASSERT_EQ(j["modes"].size(), bank.mode_count());
  for (std::size_t i = 0; i < bank.mode_count(); ++i) {
    const double w = bank.omega[i], d = bank.decay[i];
    EXPECT_NEAR(j["modes"][i]["frequency_hz"].get<double>(),
                std::sqrt(w * w - d * d) / (2 * std::numbers::pi), 1e-9 * w);
  }
  EXPECT_EQ(j["points"]["count"].get<std::size_t>(), bank.vertices.size());
  // Without transfer the runtime's gain is the compact-source estimate, the same in every
  // direction: each mode's directivity is 1 all round.
  const std::string packed = j["directivity"]["values"];
  const std::vector<uint8_t> bytes = chladni::test::base64_decode(packed);
  ASSERT_EQ(bytes.size(),
            4 * bank.mode_count() * 3 * j["directivity"]["angles"].get<std::size_t>());
  for (std::size_t k = 0; k < bytes.size(); k += 4) {
    float v;
    std::memcpy(&v, bytes.data() + k, 4);
    ASSERT_NEAR(v, 1.0f, 1e-5) << "directivity value " << k / 4;
  }
  EXPECT_EQ(j["surface"]["triangles"].get<std::size_t>(), bank.triangles.size());

  // The bank's own mesh as --mesh (in millimetres) lies on it; a mesh elsewhere does not.
  const std::string mm = chladni::test::write_temp("report_bar_mm.obj", [] {
    std::ifstream in(CHLADNI_SOURCE_DIR "/meshes/bar.obj");
    std::string out, line;
    while (std::getline(in, line)) {
      if (line.rfind("v ", 0) == 0) {
        double x, y, z;
        std::sscanf(line.c_str(), "v %lf %lf %lf", &x, &y, &z);
        line = "v " + std::to_string(1000 * x) + " " + std::to_string(1000 * y) + " " +
               std::to_string(1000 * z);
      }
      out += line + "\n";
    }
    return out;
  }());
  r = run_cli("report " + bar_bank() + " -o " + dir.string() + " --mesh " + mm + " --unit mm");
  EXPECT_EQ(r.code, 0) << r.output;
  r = run_cli("report " + bar_bank() + " -o " + dir.string() + " --mesh " + mm);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(mm + ": the mesh does not lie on the soundbank's surface"),
            std::string::npos)
      << r.output;

  const std::string file = chladni::test::write_temp("report_not_a_folder", "x");
  r = run_cli("report " + bar_bank() + " -o " + file);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(file + ": exists and is not a folder"), std::string::npos) << r.output;
  r = run_cli("report /nonexistent.chbank -o " + dir.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("/nonexistent.chbank"), std::string::npos) << r.output;
  r = run_cli("report " + bar_bank() + " -o " + dir.string() + " --listener 1,2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--listener must be X,Y,Z"), std::string::npos) << r.output;
}

// Fraction of pixels in the canvas rectangle that differ between two screenshots.
double changed(const chladni::test::Image& a, const chladni::test::Image& b, int x0, int y0, int w,
               int h) {
  std::size_t n = 0;
  for (int y = y0; y < y0 + h; ++y)
    for (int x = x0; x < x0 + w; ++x) {
      const uint8_t *p = a.at(x, y), *q = b.at(x, y);
      n += std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) + std::abs(p[2] - q[2]) > 24;
    }
  return double(n) / (double(w) * h);
}

// The object covers part of the canvas rectangle in more than a few colours.
void expect_drawn(const chladni::test::Image& a, int x0, int y0, int w, int h) {
  std::size_t object = 0;
  std::set<uint32_t> colours;
  for (int y = y0 + 2; y < y0 + h - 2; ++y)
    for (int x = x0 + 2; x < x0 + w - 2; ++x) {
      const uint8_t* p = a.at(x, y);
      const bool background =
          std::abs(p[0] - 240) < 6 && std::abs(p[1] - 242) < 6 && std::abs(p[2] - 245) < 6;
      object += !background;
      colours.insert(uint32_t(p[0] >> 3) << 10 | uint32_t(p[1] >> 3) << 5 | uint32_t(p[2] >> 3));
    }
  EXPECT_GT(double(object) / (double(w) * h), 0.03) << "the canvas is blank";
  EXPECT_GT(colours.size(), 20u);
}

// The runtime's render of the page's strike `s` (a scene: the listener the report used, an
// impact at t = 0 on that point, into the surface, with the report's impulse and contact time).
chladni::AudioBuffer render_the_pages_strike(const json& s, const json& data, double seconds) {
  const chladni::Soundbank bank = chladni::read_soundbank(bar_bank());
  const std::size_t point = s["point"];
  if (point >= bank.vertices.size()) {
    ADD_FAILURE() << "the strike's point " << point << " is no vertex of the bank";
    return {};
  }
  const auto& v = bank.vertices[point];
  const json scene = {
      {"sample_rate", int(s["fs"].get<double>())},
      {"channels", 1},
      {"duration", seconds},
      {"listener", {{"position", data["listener"]}, {"forward", {0, 1, 0}}, {"up", {0, 0, 1}}}},
      {"objects", {{{"name", "bar"}, {"soundbank", bar_bank()}}}},
      {"events",
       {{{"time", 0.0},
         {"type", "impact"},
         {"object", "bar"},
         {"impulse", data["strike"]["impulse"]},
         {"contact_time", data["strike"]["contact_time"]},
         {"direction", s["direction"]},
         {"point", {v[0], v[1], v[2]}}}}}};
  const std::string scene_path = chladni::test::write_temp("report_strike.json", scene.dump());
  const std::string wav = temp_path("report_strike.wav");
  const auto r = run_cli("render " + scene_path + " -o " + wav + " --quiet");
  EXPECT_EQ(r.code, 0) << r.output;
  return r.code == 0 ? chladni::read_audio(wav) : chladni::AudioBuffer{};
}

// Spectral peaks of `page` within 30 dB of the loudest are the bank's frequencies within 0.5 %;
// returns how many there are.
int expect_peaks_are_modes(const std::vector<float>& page, double fs, const json& data) {
  std::size_t m = 1;
  while (m < page.size()) m *= 2;
  std::vector<float> in(m, 0.0f);
  for (std::size_t i = 0; i < page.size(); ++i)
    in[i] = page[i] * float(0.5 - 0.5 * std::cos(2 * std::numbers::pi * (i + 0.5) / page.size()));
  std::vector<fftwf_complex> out(m / 2 + 1);
  fftwf_plan plan = fftwf_plan_dft_r2c_1d(int(m), in.data(), out.data(), FFTW_ESTIMATE);
  fftwf_execute(plan);
  fftwf_destroy_plan(plan);
  std::vector<double> db(out.size());
  for (std::size_t k = 0; k < out.size(); ++k)
    db[k] = 10 * std::log10(double(out[k][0]) * out[k][0] + double(out[k][1]) * out[k][1] + 1e-30);
  const double top = *std::max_element(db.begin(), db.end());
  int peaks = 0;
  for (std::size_t k = 4; k + 4 < db.size(); ++k) {
    if (db[k] < top - 30 || *std::max_element(&db[k - 4], &db[k + 5]) > db[k]) continue;
    const double f =
        (k + 0.5 * (db[k - 1] - db[k + 1]) / (db[k - 1] - 2 * db[k] + db[k + 1])) * fs / double(m);
    double nearest = 1e9;
    for (const auto& mode : data["modes"])
      nearest = std::min(nearest, std::abs(mode["frequency_hz"].get<double>() / f - 1));
    EXPECT_LT(nearest, 0.005) << "a peak at " << f << " Hz is no mode of the bank";
    ++peaks;
  }
  return peaks;
}

TEST(ReportBrowser, DrawsTheModesAndAClickSoundsLikeTheRuntime) {
  const fs::path dir = temp_path("report_browser");
  fs::remove_all(dir);
  ASSERT_EQ(run_cli("report " + bar_bank() + " -o " + dir.string()).code, 0);
  chladni::test::Browser browser;
  browser.navigate("file://" + (dir / "index.html").string());
  ASSERT_TRUE(browser.evaluate("window.chladniReport && window.chladniReport.ready").get<bool>())
      << browser.evaluate("JSON.stringify(window.chladniReport && window.chladniReport.errors)");
  const json rect = browser.evaluate(
      "(() => { const r = document.getElementById('view').getBoundingClientRect();"
      " return [Math.round(r.left), Math.round(r.top), Math.round(r.width), Math.round(r.height)]; "
      "})()");
  const int x0 = rect[0], y0 = rect[1], w = rect[2], h = rect[3];

  // Drawn: the object covers part of the canvas in more than a few colours.
  browser.evaluate("chladniReport.selectMode(0); chladniReport.freeze(Math.PI / 2)");
  const auto a = browser.screenshot();
  ASSERT_GE(a.width, x0 + w);
  ASSERT_GE(a.height, y0 + h);
  expect_drawn(a, x0, y0, w, h);
  // Another mode (chosen in the selector), another picture; the first again (a click on its
  // table row), the first picture.
  browser.evaluate(
      "(() => { const s = document.getElementById('mode-select'); s.value = '3';"
      " s.dispatchEvent(new Event('change')); chladniReport.freeze(Math.PI / 2); })()");
  EXPECT_EQ(browser.evaluate("chladniReport.selected()").get<int>(), 3);
  const auto b = browser.screenshot();
  EXPECT_GT(changed(a, b, x0, y0, w, h), 0.01);
  browser.evaluate(
      "document.getElementById('modes').tBodies[0].rows[0].click();"
      " chladniReport.freeze(Math.PI / 2)");
  EXPECT_EQ(browser.evaluate("chladniReport.selected()").get<int>(), 0);
  EXPECT_LT(changed(a, browser.screenshot(), x0, y0, w, h), 0.001);

  // A real click on the surface point nearest the canvas centre's hit.
  browser.click(x0 + w / 2.0, y0 + h / 2.0);
  const json s = browser.evaluate(
      "new Promise((done, fail) => { const t0 = Date.now(); (function poll() {"
      " const r = chladniReport; if (r.strikes > 0) done({point: r.lastStrike.point,"
      " direction: r.lastStrike.direction, position: r.lastStrike.position,"
      " fs: r.lastStrike.sampleRate, peak: r.lastStrike.peakPa,"
      " samples: Array.from(r.lastStrike.samples)});"
      " else if (Date.now() - t0 > 30000) fail(new Error('no strike: ' + r.errors));"
      " else setTimeout(poll, 50); })(); })");
  EXPECT_TRUE(browser.errors().empty()) << browser.errors().front();

  // The runtime renders the same strike.
  const json data = report_data(dir);
  const std::vector<float> page = s["samples"].get<std::vector<float>>();
  const double fs = s["fs"].get<double>();
  const chladni::AudioBuffer ref = render_the_pages_strike(s, data, double(page.size()) / fs);
  ASSERT_EQ(ref.channels, 1);
  const std::size_t n = std::min(ref.samples.size(), page.size());
  ASSERT_GT(n, 1000u);
  double ref_peak = 0, page_peak = 0;
  for (std::size_t i = 0; i < n; ++i)
    ref_peak = std::max(ref_peak, double(std::abs(ref.samples[i]))),
    page_peak = std::max(page_peak, double(std::abs(page[i])));
  ASSERT_GT(ref_peak, 0);
  EXPECT_NEAR(s["peak"].get<double>() / ref_peak, 1.0, 0.01) << "levels (Pa) differ";
  // Sample by sample, each scaled to its peak (the page normalizes before playing).
  double err = 0;
  for (std::size_t i = 0; i < n; ++i)
    err = std::max(err, std::abs(page[i] / page_peak - ref.samples[i] / ref_peak));
  EXPECT_LT(err, 0.01) << "the page's strike departs from the runtime's render";

  // Its spectral peaks (within 30 dB of the loudest) are the bank's frequencies within 0.5 %.
  EXPECT_GE(expect_peaks_are_modes(page, fs, data), 2);
}

}  // namespace
