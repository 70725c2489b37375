#include "chladni/runtime/paper/paper_database.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/error.hpp"
#include "chladni/core/json_reader.hpp"
#include "chladni/core/output_file.hpp"

namespace chladni::runtime {
namespace fs = std::filesystem;
using json_reader::json;
using json_reader::Obj;

std::vector<double> paper_db_grid() {
  return {0.025, 0.05, 0.075, 0.10, 0.125, 0.15, 0.20, 0.25, 0.30};
}

namespace {

// Distance in the (l_r, l_c) plane, relative so that 2.5 vs 5 cm counts as much as 15 vs 30.
double grid_distance(const PaperDbEntry& e, double l_r, double l_c) {
  const auto rel = [](double a, double b) { return std::log((a + 0.01) / (b + 0.01)); };
  return std::hypot(rel(e.l_r, l_r), rel(e.l_c, l_c));
}

template <class Usable>
const PaperDbEntry& nearest(const PaperSoundDb& db, double l_r, double l_c, bool constrained,
                            Usable usable, const std::string& surface) {
  const PaperDbEntry* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const PaperDbEntry& e : db.entries) {
    if (!usable(e)) continue;
    if (constrained && e.constrained) return e;
    const double d = e.constrained ? 1e9 : grid_distance(e, l_r, l_c);  // last resort only
    if (d < best_d) best_d = d, best = &e;
  }
  if (!best)
    throw InputError(surface.empty() ? "the paper sound database has no crumpling clips"
                                     : "the paper sound database has no friction spectra for "
                                       "surface '" +
                                           surface + "'");
  return *best;
}

}  // namespace

const PaperDbEntry& PaperSoundDb::nearest_crumple(double l_r, double l_c, bool constrained) const {
  return nearest(
      *this, l_r, l_c, constrained, [](const PaperDbEntry& e) { return !e.crumple.empty(); },
      std::string());
}

const PaperDbEntry& PaperSoundDb::nearest_friction(const std::string& surface, double l_r,
                                                   double l_c, bool constrained) const {
  return nearest(
      *this, l_r, l_c, constrained,
      [&](const PaperDbEntry& e) {
        auto it = e.friction.find(surface);
        return it != e.friction.end() && !it->second.empty();
      },
      surface);
}

bool PaperSoundDb::has_surface(const std::string& surface) const {
  for (const PaperDbEntry& e : entries)
    if (e.friction.count(surface)) return true;
  return false;
}

std::vector<std::string> PaperSoundDb::surfaces() const {
  std::vector<std::string> out;
  for (const PaperDbEntry& e : entries)
    for (const auto& [s, spectra] : e.friction)
      if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  return out;
}

void PaperSoundDb::validate() const {
  if (!(sample_rate >= 8000 && sample_rate <= 384000))
    throw InputError("paper sound database: sample rate " + std::to_string(sample_rate) +
                     " Hz is outside 8000..384000");
  if (!(friction_reference_speed > 0))
    throw InputError("paper sound database: friction_reference_speed must be > 0");
  if (entries.empty()) throw InputError("paper sound database: no entries");
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const PaperDbEntry& e = entries[i];
    const std::string where = "paper sound database entry " + std::to_string(i);
    if (!e.constrained && !(e.l_r > 0 && e.l_c > 0 && std::isfinite(e.l_r) && std::isfinite(e.l_c)))
      throw InputError(where + ": l_r and l_c must be positive");
    for (std::size_t c = 0; c < e.crumple.size(); ++c) {
      if (e.crumple[c].empty())
        throw InputError(where + ": crumple clip " + std::to_string(c) + " is empty");
      for (float x : e.crumple[c])
        if (!std::isfinite(x))
          throw InputError(where + ": crumple clip " + std::to_string(c) +
                           " has a non-finite sample");
    }
    for (const auto& [surface, spectra] : e.friction)
      for (const auto& s : spectra) {
        if (s.size() != kFrictionBins)
          throw InputError(where + ": friction spectrum for '" + surface + "' has " +
                           std::to_string(s.size()) + " bins, expected " +
                           std::to_string(kFrictionBins));
        for (float x : s)
          if (!(std::isfinite(x) && x >= 0))
            throw InputError(where + ": friction spectrum for '" + surface +
                             "' has a negative or non-finite magnitude");
      }
  }
}

namespace {

// A recording named at JSON path `path`, relative to the database folder, as mono at its rate.
std::vector<float> read_recording(const std::string& dir, double sample_rate, const json& name,
                                  const std::string& path) {
  if (!name.is_string()) json_reader::fail(path, "expected a file name");
  const std::string file = (fs::path(dir) / name.get<std::string>()).string();
  std::error_code missing;
  const bool there = fs::exists(file, missing);
  if (missing)
    json_reader::fail(
        path, "a file name of " + std::to_string(file.size()) + " bytes: " + missing.message());
  if (!there) json_reader::fail(path, "file " + file + " does not exist");
  AudioBuffer a;
  try {
    a = read_audio(file);
  } catch (const InputError& e) {
    json_reader::fail(path, e.what());
  }
  if (a.sample_rate != static_cast<int>(sample_rate))
    json_reader::fail(path, file + " is at " + std::to_string(a.sample_rate) +
                                " Hz, the database at " + std::to_string(int(sample_rate)) +
                                " Hz (resample it)");
  std::vector<float> mono(a.frames(), 0.0f);
  for (std::size_t t = 0; t < mono.size(); ++t) {
    for (int c = 0; c < a.channels; ++c) mono[t] += a.samples[t * a.channels + c];
    mono[t] /= float(a.channels);
    if (!std::isfinite(mono[t])) json_reader::fail(path, file + " has a non-finite sample");
  }
  if (mono.empty()) json_reader::fail(path, file + " is empty");
  return mono;
}

PaperDbEntry parse_entry(Obj& e, const std::string& dir, double sample_rate) {
  PaperDbEntry entry;
  if (e.has("constrained")) {
    const json& c = e.get("constrained");
    if (!c.is_boolean()) json_reader::fail(e.at("constrained"), "expected true or false");
    entry.constrained = c.get<bool>();
  }
  if (!entry.constrained) {
    entry.l_r = e.positive("l_r_cm", 0) / 100;
    entry.l_c = e.positive("l_c_cm", 0) / 100;
  }
  if (e.has("crumple")) {
    const json& clips = e.array("crumple");
    for (std::size_t c = 0; c < clips.size(); ++c)
      entry.crumple.push_back(
          read_recording(dir, sample_rate, clips[c], json_reader::index_path(e.at("crumple"), c)));
  }
  if (e.has("friction")) {
    const json& fr = e.get("friction");
    if (!fr.is_object()) json_reader::fail(e.at("friction"), "expected {surface: [files]}");
    for (auto it = fr.begin(); it != fr.end(); ++it) {
      const std::string path = e.at("friction") + "." + it.key();
      if (!it.value().is_array()) json_reader::fail(path, "expected an array of files");
      for (std::size_t c = 0; c < it.value().size(); ++c) {
        const std::string p = json_reader::index_path(path, c);
        const std::vector<float> rec = read_recording(dir, sample_rate, it.value()[c], p);
        try {
          entry.friction[it.key()].push_back(friction_spectrum(rec));
        } catch (const InputError& err) {
          json_reader::fail(p, err.what());
        }
      }
    }
  }
  e.done();
  return entry;
}

}  // namespace

PaperSoundDb load_paper_database(const std::string& dir) {
  const std::string index = (fs::path(dir) / "paper_db.json").string();
  std::error_code ec;
  const bool has_index = fs::exists(index, ec);
  if (ec) throw InputError(dir + ": " + ec.message());
  if (!has_index)
    throw InputError(dir +
                     ": not a paper sound database (no paper_db.json; make one with "
                     "'chladni paper-db generate -o " +
                     dir + "')");
  const json root = json_reader::read_json_file(index, "paper sound database");
  Obj r(root, index);
  if (r.integer("chladni_paper_db") != 1)
    json_reader::fail(r.at("chladni_paper_db"), "unsupported version (this build reads 1)");
  PaperSoundDb db;
  db.sample_rate = r.positive("sample_rate", 44100);
  db.friction_reference_speed = r.positive("friction_reference_speed", 0.1);
  if (r.has("description")) db.description = r.string("description");
  const json& entries = r.array("entries");
  if (entries.empty()) json_reader::fail(r.at("entries"), "no entries");
  for (std::size_t i = 0; i < entries.size(); ++i) {
    Obj e(entries[i], json_reader::index_path(r.at("entries"), i));
    db.entries.push_back(parse_entry(e, dir, db.sample_rate));
  }
  r.done();
  try {
    db.validate();
  } catch (const InputError& e) {
    json_reader::fail(index, e.what());
  }
  return db;
}

}  // namespace chladni::runtime
