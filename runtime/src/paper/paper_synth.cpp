#include "chladni/runtime/paper/paper_synth.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

#include "chladni/core/error.hpp"

namespace chladni::runtime {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

constexpr double kPi = std::numbers::pi;
// Modal gains are relative to a 1 kHz mode: acceleration per unit impulse grows with omega.
constexpr double kOmegaRef = 2 * kPi * 1000;
// A mode's slowest decay is the air term (>= 30/s by default): 0.4 s is below -100 dB.
constexpr double kRingOut = 0.4;

double disk_radius(const PaperResonator& r) {
  return std::sqrt(std::max(r.area, 1e-8) / kPi);
}

// The disk radius of the sheet an entry was recorded from (l_r x l_c/2): a sound is scaled by
// (a / this)^3 (Eq. 3), as the recording already holds its own sheet's size. Constrained
// entries have no size: the resonator's own radius, so no correction.
double recorded_radius(const PaperDbEntry& e, double a) {
  return e.constrained ? a : std::sqrt(e.l_r * e.l_c / 2 / kPi);
}

}  // namespace

PaperSynthMode parse_paper_mode(const std::string& name) {
  if (name == "database") return PaperSynthMode::Database;
  if (name == "modal") return PaperSynthMode::Modal;
  if (name == "both") return PaperSynthMode::Both;
  throw InputError("unknown paper mode '" + name + "' (expected database, modal or both)");
}

PaperRenderer::PaperRenderer(const PaperAnimation& anim, const PaperSoundDb* db, Filterbank* fb,
                             const PaperSynthOptions& options)
    : anim_(anim),
      db_(db),
      fb_(fb),
      opt_(options),
      analyzer_(anim, options.analysis),
      rng_(options.seed) {
  const bool use_db = opt_.mode != PaperSynthMode::Modal;
  const bool use_modal = opt_.mode != PaperSynthMode::Database;
  if (!(opt_.sample_rate >= 8000 && opt_.sample_rate <= 384000))
    throw InputError("paper synthesis: sample rate must be in 8000..384000 Hz");
  if (!(opt_.crumple_reference > 0) || !(opt_.crumple_max_scale > 0) || !(opt_.tail_seconds >= 0) ||
      !(opt_.friction_click_rate > 0) || !(opt_.modal_gain >= 0))
    throw InputError("paper synthesis: scales, rates and the tail must be positive and finite");
  if (use_db) {
    if (!db_) throw InputError("paper synthesis: database mode needs a sound database");
    db_->validate();
    if (db_->sample_rate != opt_.sample_rate)
      throw InputError("paper synthesis: the database is at " + std::to_string(db_->sample_rate) +
                       " Hz, the output at " + std::to_string(opt_.sample_rate) + " Hz");
    for (const PaperObstacle& o : anim_.obstacles) {
      if (!db_->has_surface(o.friction)) {
        std::string have;
        for (const std::string& s : db_->surfaces()) have += (have.empty() ? "" : ", ") + s;
        throw InputError("obstacle '" + o.name + "' slides on surface '" + o.friction +
                         "', which the paper sound database lacks (it has: " + have + ")");
      }
    }
    noise_ = std::make_unique<SpectralNoise>(2, opt_.seed * 0x9e3779b97f4a7c15ull + 1);
    mags_.resize(2 * SpectralNoise::kBins);
    hop_out_.resize(2 * SpectralNoise::kHop);
  }
  if (use_modal) {
    if (!fb_) throw InputError("paper synthesis: modal mode needs a filterbank");
    if (fb_->channels() != 2) throw InternalError("paper synthesis: the filterbank must be stereo");
    SynthOptions so;
    so.sample_rate = opt_.sample_rate;
    so.max_voices = opt_.max_voices;
    synth_ = std::make_unique<Synth>(*fb_, so);
    block_frames_ = std::min<std::uint32_t>(1024, fb_->max_frames());  // >= one frame
    block_.resize(2 * block_frames_);
    amps_.resize(opt_.modal_modes);
  }
  ears_ = ear_positions(anim_.listener);
  head_ = anim_.listener.position;
  if (opt_.live) {
    limit_ = std::numeric_limits<std::int64_t>::max();
    return;
  }
  const std::size_t frames = static_cast<std::size_t>(
      std::ceil((anim_.duration() + opt_.tail_seconds) * opt_.sample_rate));
  for (auto& ch : out_) ch.assign(frames, 0.0f);
  limit_ = static_cast<std::int64_t>(frames);
  report_.audio_seconds = double(frames) / opt_.sample_rate;
}

PaperRenderer::~PaperRenderer() = default;

std::int64_t PaperRenderer::sample_of(std::uint32_t frame) const {
  return static_cast<std::int64_t>(std::llround(frame / anim_.frame_rate * opt_.sample_rate));
}

const PaperFrameAnalysis& PaperRenderer::step() {
  if (opt_.live) throw InternalError("PaperRenderer::step() on a live renderer: step(xyz)");
  if (done()) throw InternalError("PaperRenderer::step past the last frame");
  return step_at(anim_.frame(next_frame_), nullptr);
}

const PaperFrameAnalysis& PaperRenderer::step_at(std::span<const float> xyz,
                                                 const std::vector<std::uint32_t>* held) {
  const auto t0 = Clock::now();
  last_ = analyzer_.analyze(next_frame_, xyz, held);  // may throw: nothing changed yet
  const std::uint32_t f = next_frame_++;
  const double analysis_ms = ms_since(t0);
  const auto t1 = Clock::now();
  const std::int64_t at = sample_of(f), next = sample_of(f + 1);
  const bool use_db = opt_.mode != PaperSynthMode::Modal;
  const bool use_modal = opt_.mode != PaperSynthMode::Database;
  friction_.clear();
  std::uint32_t resonators = 0;
  for (const PaperEvent& ev : last_.events) {
    resonators += static_cast<std::uint32_t>(ev.resonators.size());
    if (ev.type == PaperEventType::Crumple) {
      ++report_.crumple_events;
      const double t = f / anim_.frame_rate;
      if (report_.crumple_times.empty() || report_.crumple_times.back() < t)
        report_.crumple_times.push_back(t);
      // Clips scale linearly with the curvature change (§5), up to a cap.
      const double scale = std::min(ev.amplitude / opt_.crumple_reference, opt_.crumple_max_scale);
      for (const PaperResonator& r : ev.resonators) {
        if (use_db) play_crumple_clip(r, scale, at);
        if (use_modal) start_crumple_voice(r, scale, at);
      }
    } else {
      ++report_.friction_events;
      for (const PaperResonator& r : ev.resonators) {
        if (use_db) add_friction_source(ev, r);
        if (use_modal) touch_friction_voice(ev, r, f);
      }
    }
  }
  report_.resonators += resonators;
  report_.max_resonators_in_frame = std::max(report_.max_resonators_in_frame, resonators);
  if (use_modal) {
    // Sliding stops where no event touched the voice this frame; silent voices end.
    for (auto it = friction_voices_.begin(); it != friction_voices_.end();) {
      ModalVoice& v = it->second;
      if (v.last_frame != f) v.speed = 0;
      if ((f - v.last_frame) / anim_.frame_rate > kRingOut) {
        synth_->stop_voice(v.id);
        it = friction_voices_.erase(it);
      } else {
        ++it;
      }
    }
    report_.peak_modal_voices = std::max<std::uint32_t>(
        report_.peak_modal_voices,
        static_cast<std::uint32_t>(friction_voices_.size() + crumple_voices_.size()));
    render_modal_until(next);
  }
  if (use_db) render_friction_until(next);
  const double synthesis_ms = ms_since(t1);
  report_.frames = next_frame_;
  report_.analysis_ms += analysis_ms;
  report_.synthesis_ms += synthesis_ms;
  report_.worst_frame_ms = std::max(report_.worst_frame_ms, analysis_ms + synthesis_ms);
  return last_;
}

void PaperRenderer::render_tail(std::int64_t end) {
  const auto t = Clock::now();
  friction_.clear();
  for (auto& [key, v] : friction_voices_) v.speed = 0;
  if (synth_) render_modal_until(end);
  if (noise_) render_friction_until(end);
  report_.synthesis_ms += ms_since(t);
}

AudioBuffer PaperRenderer::finish() {
  if (opt_.live) throw InternalError("PaperRenderer::finish on a live renderer: end() and read()");
  render_tail(limit_);
  AudioBuffer a;
  a.sample_rate = static_cast<int>(opt_.sample_rate);
  a.channels = 2;
  a.samples.resize(2 * static_cast<std::size_t>(limit_));
  take(a.samples.data(), static_cast<std::size_t>(limit_));
  return a;
}

// --- Database mode -----------------------------------------------------------------------

void PaperRenderer::play_crumple_clip(const PaperResonator& r, double scale, std::int64_t at) {
  const PaperDbEntry& e = db_->nearest_crumple(r.ruling_length, r.free_border, r.constrained);
  const std::vector<float>& clip =
      e.crumple[rng_.index(static_cast<std::uint32_t>(e.crumple.size()))];
  const double a = disk_radius(r);
  const double a_ref = recorded_radius(e, a);
  for (int ear = 0; ear < 2; ++ear) {
    paths_scratch_.clear();
    dipole_paths(r.centroid, r.normal, a, a_ref, ears_[ear], anim_.obstacles, opt_.spatial,
                 paths_scratch_);
    for (const SoundPath& p : paths_scratch_) {  // Eq. 5: direct and image copies
      const std::int64_t start = at + std::llround(p.delay * opt_.sample_rate);
      const float g = static_cast<float>(scale * p.gain);
      const std::int64_t n =
          std::min<std::int64_t>(static_cast<std::int64_t>(clip.size()), limit_ - start);
      if (n <= 0) continue;
      float* dst = window(ear, start, start + n);  // planar: the loop vectorizes
      for (std::int64_t i = 0; i < n; ++i) dst[i] += g * clip[i];
    }
  }
}

const std::vector<float>& PaperRenderer::hop_bins(const std::vector<float>& spectrum) {
  auto it = hop_bins_.find(&spectrum);
  if (it != hop_bins_.end()) return it->second;
  std::vector<float> bins(SpectralNoise::kBins);
  spectrum_to_hop_bins(spectrum, bins.data());
  return hop_bins_.emplace(&spectrum, std::move(bins)).first->second;
}

void PaperRenderer::add_friction_source(const PaperEvent& ev, const PaperResonator& r) {
  const std::string& surface = anim_.obstacles.at(ev.obstacle).friction;
  const PaperDbEntry& e =
      db_->nearest_friction(surface, r.ruling_length, r.free_border, r.constrained);
  const auto& spectra = e.friction.at(surface);
  FrictionSource s;
  s.bins = &hop_bins(spectra[rng_.index(static_cast<std::uint32_t>(spectra.size()))]);
  s.weight = ev.amplitude / db_->friction_reference_speed;  // linear in sliding speed (§5)
  const double a = disk_radius(r);
  const double a_ref = recorded_radius(e, a);
  for (int ear = 0; ear < 2; ++ear)
    dipole_paths(r.centroid, r.normal, a, a_ref, ears_[ear], anim_.obstacles, opt_.spatial,
                 s.paths[ear]);
  friction_.push_back(std::move(s));
}

void PaperRenderer::render_friction_until(std::int64_t end) {
  const std::int64_t frames = limit_;
  constexpr std::size_t K = SpectralNoise::kBins;
  const double dw = 2 * kPi * opt_.sample_rate / double(SpectralNoise::kSize);
  while (friction_pos_ < end && friction_pos_ < frames) {
    std::fill(mags_.begin(), mags_.end(), 0.0f);
    for (const FrictionSource& s : friction_) {
      for (int ear = 0; ear < 2; ++ear) {
        float* m = mags_.data() + ear * K;
        const auto& paths = s.paths[ear];
        if (paths.size() == 1) {  // no reflector: a flat factor
          const float g = static_cast<float>(s.weight * std::abs(paths[0].gain));
          for (std::size_t k = 0; k < K; ++k) m[k] += g * (*s.bins)[k];
        } else {  // Eq. 6 per bin; each path's phasor e^{i w_k R/c} turns by a fixed step
          phasor_.assign(paths.size(), {1.0, 0.0});
          step_.resize(paths.size());
          for (std::size_t p = 0; p < paths.size(); ++p)
            step_[p] = std::polar(1.0, dw * paths[p].delay);
          for (std::size_t k = 0; k < K; ++k) {
            std::complex<double> sum = 0;
            for (std::size_t p = 0; p < paths.size(); ++p) {
              sum += paths[p].gain * phasor_[p];
              phasor_[p] *= step_[p];
            }
            m[k] += static_cast<float>(s.weight * std::abs(sum)) * (*s.bins)[k];
          }
        }
      }
    }
    noise_->hop(mags_, hop_out_.data());
    add_interleaved(friction_pos_, hop_out_.data(),
                    std::min<std::int64_t>(SpectralNoise::kHop, frames - friction_pos_));
    friction_pos_ += SpectralNoise::kHop;
  }
}

// --- Modal mode --------------------------------------------------------------------------

const std::vector<SheetMode>& PaperRenderer::resonator_modes(const PaperResonator& r) {
  // Curved and free: the l_r x l_c/2 sheet. Constrained or flat: a square of the same area.
  const double side = std::sqrt(std::max(r.area, 1e-6));
  double a = r.ruling_length, b = r.free_border / 2;
  if (r.constrained || !(a > 0) || !(b > 0)) a = b = side;
  a = std::clamp(a, 0.005, 1.0);
  b = std::clamp(b, 0.005, 1.0);
  const std::pair<int, int> key{static_cast<int>(std::lround(a * 1e4)),
                                static_cast<int>(std::lround(b * 1e4))};
  auto it = modes_cache_.find(key);
  if (it != modes_cache_.end()) return it->second;
  const double aq = key.first * 1e-4, bq = key.second * 1e-4;
  auto modes = thin_modes(sheet_modes(aq, bq, sheet_radius(bq, opt_.material), opt_.material, 20,
                                      0.45 * opt_.sample_rate),
                          opt_.modal_modes);
  return modes_cache_.emplace(key, std::move(modes)).first->second;
}

void PaperRenderer::set_voice_spatial(const ModalVoice& v, const PaperResonator& r) {
  const double a = disk_radius(r);
  float pan[2];
  for (int ear = 0; ear < 2; ++ear) {
    paths_scratch_.clear();
    dipole_paths(r.centroid, r.normal, a, opt_.modal_reference_radius, ears_[ear], {}, opt_.spatial,
                 paths_scratch_);
    pan[ear] = static_cast<float>(paths_scratch_[0].gain);
  }
  synth_->set_pan(v.id, pan[0], pan[1]);
  // The image sources as a per-mode factor (Eq. 6 at the mode's frequency, at the head).
  paths_scratch_.clear();
  dipole_paths(r.centroid, r.normal, a, opt_.modal_reference_radius, head_, anim_.obstacles,
               opt_.spatial, paths_scratch_);
  const double direct = std::abs(paths_scratch_[0].gain);
  gains_.resize(v.modes->size());
  for (std::size_t i = 0; i < v.modes->size(); ++i) {
    const SheetMode& m = (*v.modes)[i];
    const double image = direct > 1e-12 ? path_magnitude(paths_scratch_, m.omega) / direct : 1.0;
    gains_[i] = static_cast<float>(opt_.modal_gain * m.weight * (m.omega / kOmegaRef) * image);
  }
  synth_->set_mode_gains(v.id, gains_);
}

namespace {
std::vector<ModeSpec> mode_specs(const std::vector<SheetMode>& modes) {
  std::vector<ModeSpec> specs;
  for (const SheetMode& m : modes) specs.push_back({m.omega, m.decay, 1.0f});
  return specs;
}
}  // namespace

void PaperRenderer::start_crumple_voice(const PaperResonator& r, double scale, std::int64_t at) {
  ModalVoice v;
  v.modes = &resonator_modes(r);
  if (v.modes->empty()) return;
  v.id = synth_->start_voice(mode_specs(*v.modes));
  set_voice_spatial(v, r);
  const double delay = norm(sub(head_, r.centroid)) / opt_.spatial.sound_speed;
  const std::int64_t start = at + std::llround(delay * opt_.sample_rate);
  std::int64_t last = start;
  for (const CrumpleImpulse& c : crumple_burst(rng_)) {
    const std::int64_t s = start + std::llround(c.time * opt_.sample_rate);
    clicks_.push_back({s, v.id, v.modes, scale * c.strength, c.u, c.v});
    std::push_heap(clicks_.begin(), clicks_.end(), std::greater<>());
    last = std::max(last, s);
  }
  v.stop_at = last + std::llround(kRingOut * opt_.sample_rate);
  crumple_voices_.push_back(v);
}

void PaperRenderer::touch_friction_voice(const PaperEvent& ev, const PaperResonator& r,
                                         std::uint32_t frame) {
  // One voice per obstacle and resonator size (half-centimetre steps): a sliding resonator
  // keeps its voice from frame to frame while its size holds.
  const FrictionKey key{ev.obstacle, static_cast<int>(std::lround(r.ruling_length * 200)),
                        static_cast<int>(std::lround(r.free_border * 200)), r.constrained};
  const double ref = db_ ? db_->friction_reference_speed : 0.1;
  auto it = friction_voices_.find(key);
  if (it == friction_voices_.end()) {
    ModalVoice v;
    v.modes = &resonator_modes(r);
    if (v.modes->empty()) return;
    v.id = synth_->start_voice(mode_specs(*v.modes));
    v.next_click = double(modal_pos_);
    it = friction_voices_.emplace(key, v).first;
  }
  ModalVoice& v = it->second;
  const double speed = ev.amplitude / ref;
  v.speed = v.last_frame == frame && v.speed > 0 ? std::max(v.speed, speed) : speed;
  if (v.next_click < double(modal_pos_)) v.next_click = double(modal_pos_);
  v.last_frame = frame;
  set_voice_spatial(v, r);
}

void PaperRenderer::render_modal_until(std::int64_t end) {
  const std::int64_t frames = limit_;
  const double click_gap = opt_.sample_rate / opt_.friction_click_rate;
  const double click_gain = opt_.modal_friction_gain;
  while (modal_pos_ < end && modal_pos_ < frames) {
    const std::uint32_t n =
        static_cast<std::uint32_t>(std::min<std::int64_t>(block_frames_, end - modal_pos_));
    const std::int64_t block_end = modal_pos_ + n;
    // Sliding: Poisson clicks of normal strength (white-noise forcing, like the database's).
    for (auto& [key, v] : friction_voices_) {
      if (v.speed <= 0) continue;
      while (v.next_click < double(block_end)) {
        clicks_.push_back({static_cast<std::int64_t>(v.next_click), v.id, v.modes,
                           click_gain * v.speed * rng_.normal(), rng_.uniform(), rng_.uniform()});
        std::push_heap(clicks_.begin(), clicks_.end(), std::greater<>());
        v.next_click += rng_.exponential(1.0) * click_gap;
      }
    }
    while (!clicks_.empty() && clicks_.front().sample < block_end) {
      std::pop_heap(clicks_.begin(), clicks_.end(), std::greater<>());
      const Click c = clicks_.back();
      clicks_.pop_back();
      const std::size_t m = c.modes->size();
      for (std::size_t i = 0; i < m; ++i)
        amps_[i] = {static_cast<float>(c.strength * sheet_mode_shape((*c.modes)[i], c.u, c.v)), 0};
      const std::int64_t offset = std::max<std::int64_t>(0, c.sample - modal_pos_);
      if (synth_->pending_excitations() + m <= synth_->excitation_capacity())
        synth_->excite(c.voice, std::span(amps_.data(), m), static_cast<std::uint32_t>(offset));
    }
    synth_->render(n, block_.data());
    add_interleaved(modal_pos_, block_.data(), std::min<std::int64_t>(n, frames - modal_pos_));
    modal_pos_ = block_end;
    // Crumple voices whose burst has rung out give their slots back.
    for (std::size_t i = 0; i < crumple_voices_.size();) {
      if (crumple_voices_[i].stop_at <= modal_pos_) {
        synth_->stop_voice(crumple_voices_[i].id);
        crumple_voices_[i] = crumple_voices_.back();
        crumple_voices_.pop_back();
      } else {
        ++i;
      }
    }
  }
}

AudioBuffer render_paper(const PaperAnimation& anim, const PaperSoundDb* db, Filterbank* fb,
                         const PaperSynthOptions& options, PaperRenderReport* report) {
  const auto t = Clock::now();
  PaperRenderer r(anim, db, fb, options);
  while (!r.done()) r.step();
  AudioBuffer out = r.finish();
  if (report) {
    *report = r.report();
    report->wall_seconds = ms_since(t) / 1000;
  }
  return out;
}

}  // namespace chladni::runtime
