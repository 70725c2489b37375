#pragma once
// Paper sound synthesis (Schreck et al. 2016 §5-6): per frame, the analysis's events and
// resonators become sound. Database mode plays crumpling clips (Eq. 5: direct plus image copy
// per ear) and sums friction spectra weighted by Eq. 6 into inverse-FFT noise; modal mode runs
// each resonator as a modal voice on a filterbank (CPU or GPU), its modes from the sheet model
// at the resonator's (l_r, l_c), excited by crumple bursts or friction clicks. Offline, the
// whole animation renders into one stereo buffer; live (PaperSynthOptions::live), frames come
// from a simulation one at a time and each frame's audio is read once final, the same samples
// as offline. step()'s costs are what a game pays per frame.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

#include "chladni/core/audio_file.hpp"
#include "chladni/core/paper_animation.hpp"
#include "chladni/core/random.hpp"
#include "chladni/runtime/filterbank/filterbank.hpp"
#include "chladni/runtime/modal/synth.hpp"
#include "chladni/runtime/paper/paper_analysis.hpp"
#include "chladni/runtime/paper/paper_database.hpp"
#include "chladni/runtime/paper/paper_spatial.hpp"
#include "chladni/runtime/paper/spectral_noise.hpp"

namespace chladni::runtime {

enum class PaperSynthMode { Database, Modal, Both };
/// "database" | "modal" | "both"; throws InputError otherwise.
PaperSynthMode parse_paper_mode(const std::string& name);

struct PaperSynthOptions {
  PaperSynthMode mode = PaperSynthMode::Database;
  double sample_rate = 44100;  ///< database mode: must equal the database's
  std::uint64_t seed = 1;
  PaperAnalysisOptions analysis;
  PaperSpatialOptions spatial;
  /// A crumpling event of this amplitude (sum of |dH| over its vertices, 1/m) plays a clip at
  /// its recorded level; scaling is linear (the paper) up to crumple_max_scale.
  double crumple_reference = 200;
  double crumple_max_scale = 4;
  double tail_seconds = 0.5;  ///< rendered after the last frame so sounds can ring out
  // Modal resonator voices.
  PaperMaterial material;
  std::size_t modal_modes = 48;       ///< per resonator (thin_modes of the sheet's modes)
  double friction_click_rate = 1500;  ///< clicks per second driving a sliding resonator
  /// Levels of the modal voices, calibrated so the shipped examples' RMS matches the default
  /// database's (crumple and slide): crumple clicks and, on top, friction clicks.
  double modal_gain = 2.1e-5;
  double modal_friction_gain = 5.6;
  double modal_reference_radius = 0.05;  ///< m: the dipole size normalization (a / this)^3
  std::uint32_t max_voices = 16384;
  /// Frames come one at a time from a live simulation (PaperRenderer::step(xyz)) with no end
  /// known, and the audio is taken as it becomes final (read()); the animation's own frames are
  /// not read.
  bool live = false;
};

struct PaperRenderReport {
  std::uint32_t frames = 0;
  std::uint64_t friction_events = 0, crumple_events = 0, resonators = 0;
  std::vector<double> crumple_times;  ///< s, each frame with a crumpling event (for plots)
  std::uint32_t max_resonators_in_frame = 0;
  std::uint32_t peak_modal_voices = 0;
  double analysis_ms = 0, synthesis_ms = 0;  ///< totals
  double worst_frame_ms = 0;                 ///< analysis + synthesis of the slowest frame
  double wall_seconds = 0;
  double audio_seconds = 0;
};

class PaperRenderer {
 public:
  /// `db` is needed for database/both modes, `fb` (2 channels, >= 256 frames per call) for
  /// modal/both. Both must outlive the renderer.
  PaperRenderer(const PaperAnimation& anim, const PaperSoundDb* db, Filterbank* fb,
                const PaperSynthOptions& options);
  ~PaperRenderer();

  /// Analyses the next frame and synthesizes audio up to the following frame's start.
  const PaperFrameAnalysis& step();
  bool done() const { return !opt_.live && next_frame_ >= anim_.frame_count(); }
  /// Renders the tail and returns the stereo buffer (call once, after the last step()).
  AudioBuffer finish();
  const PaperRenderReport& report() const { return report_; }

  /// Live: the next frame from the caller's positions (3 floats per vertex), with `held`
  /// replacing the animation's anchors when given (PaperAnalyzer::analyze). The samples up to
  /// the following frame's start become final; sounds it starts may run on past them.
  const PaperFrameAnalysis& step(std::span<const float> xyz,
                                 const std::vector<std::uint32_t>* held = nullptr);
  /// Live: stops taking frames and renders tail_seconds after the last one.
  void end();
  /// Live: stereo frames final and not yet read.
  std::size_t ready() const;
  /// Live: moves the oldest `frames` (<= ready()) final stereo frames, interleaved, to `out`.
  void read(float* out, std::size_t frames);
  /// The frame the next step analyses.
  std::uint32_t next_frame() const { return next_frame_; }
  /// Hears the sounds started from now on from `listener` (a game's moving camera); sounds
  /// already playing keep their paths.
  void set_listener(const PaperListener& listener);

 private:
  struct FrictionSource {
    const std::vector<float>* bins;  // SpectralNoise::kBins magnitudes at the reference speed
    double weight;
    std::vector<SoundPath> paths[2];
  };
  struct Click {
    std::int64_t sample;
    Synth::VoiceId voice;
    const std::vector<SheetMode>* modes;
    double strength, u, v;
    bool operator>(const Click& o) const { return sample > o.sample; }
  };
  struct ModalVoice {
    Synth::VoiceId id = -1;
    const std::vector<SheetMode>* modes = nullptr;  // in modes_cache_
    std::int64_t stop_at = 0;  // crumple voices: sample after which they are silent
    double speed = 0;          // friction voices: sliding speed / reference speed
    double next_click = 0;     // friction voices: sample of the next click
    std::uint32_t last_frame = 0;
  };
  using FrictionKey = std::tuple<std::int32_t, int, int, bool>;

  void play_crumple_clip(const PaperResonator& r, double scale, std::int64_t at);
  void add_friction_source(const PaperEvent& ev, const PaperResonator& r);
  void render_friction_until(std::int64_t end);
  void start_crumple_voice(const PaperResonator& r, double scale, std::int64_t at);
  void touch_friction_voice(const PaperEvent& ev, const PaperResonator& r, std::uint32_t frame);
  void render_modal_until(std::int64_t end);
  const std::vector<SheetMode>& resonator_modes(const PaperResonator& r);
  void set_voice_spatial(const ModalVoice& v, const PaperResonator& r);
  const std::vector<float>& hop_bins(const std::vector<float>& spectrum);
  const PaperFrameAnalysis& step_at(std::span<const float> xyz,
                                    const std::vector<std::uint32_t>* held);
  std::int64_t sample_of(std::uint32_t frame) const;
  void render_tail(std::int64_t end);
  // Channel `ch` of the output from absolute sample `from` to `to`, grown to hold it.
  float* window(int ch, std::int64_t from, std::int64_t to);
  // Adds `frames` interleaved stereo frames to the output from absolute sample `at`.
  void add_interleaved(std::int64_t at, const float* x, std::int64_t frames);
  // Moves the output's oldest `frames`, interleaved, to `out`.
  void take(float* out, std::size_t frames);

  const PaperAnimation& anim_;
  const PaperSoundDb* db_;
  Filterbank* fb_;
  PaperSynthOptions opt_;
  PaperAnalyzer analyzer_;
  PaperFrameAnalysis last_;
  std::array<Vec3, 2> ears_;
  Vec3 head_;
  Rng rng_;
  std::uint32_t next_frame_ = 0;
  // Left and right (planar until finish()) from absolute sample out_base_: the whole sound
  // offline; live, what is not yet read, up to where sounds already started reach.
  std::array<std::vector<float>, 2> out_;
  std::int64_t out_base_ = 0;
  std::int64_t limit_ = 0;   // samples rendered in all: offline the animation's, live unbounded
  std::int64_t ended_ = -1;  // live, after end(): the last sample's end
  PaperRenderReport report_;
  // Database friction.
  std::unique_ptr<SpectralNoise> noise_;
  std::vector<FrictionSource> friction_;
  std::int64_t friction_pos_ = 0;
  std::map<const std::vector<float>*, std::vector<float>> hop_bins_;
  std::vector<float> mags_, hop_out_;
  std::vector<SoundPath> paths_scratch_;
  std::vector<std::complex<double>> phasor_, step_;
  // Modal voices.
  std::unique_ptr<Synth> synth_;
  std::int64_t modal_pos_ = 0;
  std::uint32_t block_frames_ = 256;
  std::vector<Click> clicks_;  // min-heap on sample
  std::vector<ModalVoice> crumple_voices_;
  std::map<FrictionKey, ModalVoice> friction_voices_;
  std::map<std::pair<int, int>, std::vector<SheetMode>> modes_cache_;  // by (a, b) in 0.1 mm
  std::vector<std::complex<float>> amps_;
  std::vector<float> block_, gains_;
};

/// Analyses and synthesizes the whole animation.
AudioBuffer render_paper(const PaperAnimation& anim, const PaperSoundDb* db, Filterbank* fb,
                         const PaperSynthOptions& options, PaperRenderReport* report = nullptr);

}  // namespace chladni::runtime
