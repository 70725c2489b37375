#include "chladni/runtime/paper_database.hpp"

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

// The sheet's acceleration response, summed over modes, to white force at random points:
// E|A(w)|^2 = sum_i weight_i^2 <phi_i^2> |w^2 / (w0_i^2 - w^2 + 2 i d_i w)|^2, <phi^2> = 1/4.
std::vector<float> expected_friction_spectrum(const std::vector<SheetMode>& modes, double fs) {
  std::vector<float> out(kFrictionBins);
  for (std::size_t k = 0; k < kFrictionBins; ++k) {
    const double w = 2 * std::numbers::pi * fs * double(k) / (2.0 * kFrictionBins);
    double p = 0;
    for (const SheetMode& m : modes) {
      const double w02 = m.omega * m.omega + m.decay * m.decay;
      const double re = w02 - w * w, im = 2 * m.decay * w;
      const double h2 = (w * w) * (w * w) / (re * re + im * im);  // |h|^2, no complex division
      p += 0.25 * double(m.weight) * m.weight * h2;
    }
    out[k] = static_cast<float>(std::sqrt(p));
  }
  return out;
}

// Acceleration of the sheet's modes under a burst of clicks, one complex one-pole per mode
// (the filterbank's recursion, in double): a click of strength s at (u, v) kicks mode i by
// s * phi_i(u, v) * weight_i * omega_i (acceleration of a unit-impulse response).
std::vector<float> crumple_clip(const std::vector<SheetMode>& modes,
                                const std::vector<CrumpleImpulse>& burst, double fs,
                                double seconds) {
  const std::size_t n = static_cast<std::size_t>(seconds * fs);
  std::vector<double> acc(n, 0.0);
  for (const SheetMode& m : modes) {
    const std::complex<double> p = std::exp(std::complex<double>(-m.decay, m.omega) / fs);
    std::complex<double> z = 0;
    std::size_t next = 0;
    for (std::size_t t = 0; t < n; ++t) {
      z *= p;
      while (next < burst.size() && burst[next].time * fs <= double(t)) {
        const CrumpleImpulse& c = burst[next++];
        z += c.strength * sheet_mode_shape(m, c.u, c.v) * m.weight * m.omega;
      }
      acc[t] += z.imag();
      if (next == burst.size() && std::norm(z) < 1e-30) break;
    }
  }
  // A short fade-out so a clip never ends on a step.
  const std::size_t fade = std::min<std::size_t>(n, static_cast<std::size_t>(0.01 * fs));
  std::vector<float> out(n);
  for (std::size_t t = 0; t < n; ++t) {
    const double g = t + fade >= n ? double(n - t) / double(fade) : 1.0;
    out[t] = static_cast<float>(acc[t] * g);
  }
  return out;
}

void scale_all(PaperSoundDb& db, double clip_peak, double friction_rms) {
  double peak = 0, rms = 0;
  for (const PaperDbEntry& e : db.entries) {
    for (const auto& c : e.crumple)
      for (float x : c) peak = std::max(peak, double(std::abs(x)));
    for (const auto& [surface, spectra] : e.friction)
      for (const auto& s : spectra) {
        double p = 0;
        for (float x : s) p += double(x) * x;
        rms = std::max(rms, std::sqrt(p / s.size()));
      }
  }
  for (PaperDbEntry& e : db.entries) {
    for (auto& c : e.crumple)
      for (float& x : c) x = static_cast<float>(x * clip_peak / peak);
    for (auto& [surface, spectra] : e.friction)
      for (auto& s : spectra)
        for (float& x : s) x = static_cast<float>(x * friction_rms / rms);
  }
}

std::string cm(double m) {
  std::ostringstream s;
  s << m * 100;
  return s.str();
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

PaperSoundDb generate_paper_database(const PaperDbOptions& o,
                                     const std::function<void(double)>& progress) {
  if (o.variants < 1) throw InputError("paper database: variants must be >= 1");
  if (!(o.clip_seconds > 0)) throw InputError("paper database: clip length must be > 0");
  PaperSoundDb db;
  db.description = "generated by chladni paper-db generate (seed " + std::to_string(o.seed) +
                   "): bent-sheet modal model, docs/paper.md";
  const std::vector<double> grid = paper_db_grid();
  std::vector<std::pair<double, double>> sizes;  // (l_r, l_c); (0, 0) = constrained
  sizes.push_back({0, 0});
  for (double lr : grid)
    for (double lc : grid) sizes.push_back({lr, lc});
  Rng rng(o.seed);
  for (std::size_t s = 0; s < sizes.size(); ++s) {
    PaperDbEntry e;
    e.constrained = sizes[s].first == 0;
    e.l_r = sizes[s].first;
    e.l_c = sizes[s].second;
    for (int v = 0; v < o.variants; ++v) {
      PaperMaterial mat = o.material;
      mat.chord_ratio = o.material.chord_ratio + 0.05 * (v - (o.variants > 1 ? 1 : 0));
      const double a = e.constrained ? o.constrained_side : e.l_r;
      const double b = e.constrained ? o.constrained_side : e.l_c / 2;
      const auto all = sheet_modes(a, b, sheet_radius(b, mat), mat, 20, 0.45 * db.sample_rate);
      const auto burst = crumple_burst(rng);
      e.crumple.push_back(
          crumple_clip(thin_modes(all, o.clip_modes), burst, db.sample_rate, o.clip_seconds));
      const auto spectrum =
          expected_friction_spectrum(thin_modes(all, o.spectrum_modes), db.sample_rate);
      for (const std::string& surface : o.surfaces) e.friction[surface].push_back(spectrum);
    }
    db.entries.push_back(std::move(e));
    if (progress) progress(double(s + 1) / double(sizes.size()));
  }
  // One scale for the whole database keeps the sizes' relative loudness.
  scale_all(db, 0.5, 0.05);
  return db;
}

void write_paper_database(const std::string& dir, const PaperSoundDb& db, double friction_seconds,
                          std::uint64_t seed) {
  db.validate();
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "crumple", ec);
  fs::create_directories(fs::path(dir) / "friction", ec);
  if (ec) throw InputError(dir + ": cannot create the database folder: " + ec.message());
  json entries = json::array();
  const std::size_t friction_frames = static_cast<std::size_t>(friction_seconds * db.sample_rate);
  for (std::size_t i = 0; i < db.entries.size(); ++i) {
    const PaperDbEntry& e = db.entries[i];
    json j;
    const std::string tag = e.constrained ? "constrained" : "r" + cm(e.l_r) + "_c" + cm(e.l_c);
    if (e.constrained) {
      j["constrained"] = true;
    } else {
      j["l_r_cm"] = e.l_r * 100;
      j["l_c_cm"] = e.l_c * 100;
    }
    j["crumple"] = json::array();
    for (std::size_t v = 0; v < e.crumple.size(); ++v) {
      const std::string rel = "crumple/" + tag + "_v" + std::to_string(v) + ".wav";
      AudioBuffer a;
      a.sample_rate = static_cast<int>(db.sample_rate);
      a.samples = e.crumple[v];
      write_wav((fs::path(dir) / rel).string(), a, SampleFormat::Pcm16);
      j["crumple"].push_back(rel);
    }
    j["friction"] = json::object();
    for (const auto& [surface, spectra] : e.friction) {
      json files = json::array();
      for (std::size_t v = 0; v < spectra.size(); ++v) {
        // The spectrum as a noise recording: what a user's own recording would be.
        SpectralNoise noise(1, seed + 7919 * i + v);
        std::vector<float> bins(SpectralNoise::kBins);
        spectrum_to_hop_bins(spectra[v], bins.data());
        AudioBuffer a;
        a.sample_rate = static_cast<int>(db.sample_rate);
        a.samples.resize((friction_frames / SpectralNoise::kHop + 2) * SpectralNoise::kHop);
        for (std::size_t h = 0; h * SpectralNoise::kHop < a.samples.size(); ++h)
          noise.hop(bins, a.samples.data() + h * SpectralNoise::kHop);
        a.samples.erase(a.samples.begin(), a.samples.begin() + SpectralNoise::kHop);  // fade-in
        a.samples.resize(friction_frames);
        const std::string rel =
            "friction/" + surface + "_" + tag + "_v" + std::to_string(v) + ".wav";
        write_wav((fs::path(dir) / rel).string(), a, SampleFormat::Pcm16);
        files.push_back(rel);
      }
      j["friction"][surface] = files;
    }
    entries.push_back(j);
  }
  json root;
  root["chladni_paper_db"] = 1;
  root["sample_rate"] = db.sample_rate;
  root["friction_reference_speed"] = db.friction_reference_speed;
  root["description"] = db.description;
  root["entries"] = entries;
  const std::string index = (fs::path(dir) / "paper_db.json").string();
  // Written last and whole: a folder is a database only once every clip is in it.
  write_file_atomic(index, root.dump(1) + "\n", "paper sound database");
}

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
  const auto read = [&](const json& name, const std::string& path) {
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
    if (a.sample_rate != static_cast<int>(db.sample_rate))
      json_reader::fail(path, file + " is at " + std::to_string(a.sample_rate) +
                                  " Hz, the database at " + std::to_string(int(db.sample_rate)) +
                                  " Hz (resample it)");
    std::vector<float> mono(a.frames(), 0.0f);
    for (std::size_t t = 0; t < mono.size(); ++t) {
      for (int c = 0; c < a.channels; ++c) mono[t] += a.samples[t * a.channels + c];
      mono[t] /= float(a.channels);
      if (!std::isfinite(mono[t])) json_reader::fail(path, file + " has a non-finite sample");
    }
    if (mono.empty()) json_reader::fail(path, file + " is empty");
    return mono;
  };
  for (std::size_t i = 0; i < entries.size(); ++i) {
    Obj e(entries[i], json_reader::index_path(r.at("entries"), i));
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
        entry.crumple.push_back(read(clips[c], json_reader::index_path(e.at("crumple"), c)));
    }
    if (e.has("friction")) {
      const json& fr = e.get("friction");
      if (!fr.is_object()) json_reader::fail(e.at("friction"), "expected {surface: [files]}");
      for (auto it = fr.begin(); it != fr.end(); ++it) {
        const std::string path = e.at("friction") + "." + it.key();
        if (!it.value().is_array()) json_reader::fail(path, "expected an array of files");
        for (std::size_t c = 0; c < it.value().size(); ++c) {
          const std::string p = json_reader::index_path(path, c);
          const std::vector<float> rec = read(it.value()[c], p);
          try {
            entry.friction[it.key()].push_back(friction_spectrum(rec));
          } catch (const InputError& err) {
            json_reader::fail(p, err.what());
          }
        }
      }
    }
    e.done();
    db.entries.push_back(std::move(entry));
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
