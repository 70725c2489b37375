#pragma once
// --spectrogram PNG [--linear-frequency] for the commands that make a sound (render, paper,
// shake): the sound, mixed to mono, as plot::write_sound_png's labelled figure.
#include <CLI/CLI.hpp>
#include <string>

#include "chladni/core/audio_file.hpp"
#include "chladni/plot/sound_figure.hpp"

namespace chladni::cli {

struct SpectrogramArgs {
  std::string path;  ///< empty: none asked for
  bool linear = false;
};

/// Adds --spectrogram and --linear-frequency to `cmd`.
void add_spectrogram_options(CLI::App& cmd, SpectrogramArgs& args);

/// Writes `audio` (channels mixed) with `title` and `events`; prints "wrote PATH" unless quiet.
void write_spectrogram(const SpectrogramArgs& args, const AudioBuffer& audio,
                       const std::string& title, const plot::Events& events = {},
                       bool quiet = false);

}  // namespace chladni::cli
