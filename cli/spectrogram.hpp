#pragma once
// Spectrogram of a sound as a PNG image (time left to right, frequency bottom to top, linear
// up to Nyquist, dB colour scale), the way the paper's figures show its sounds.
#include <string>

#include "chladni/core/audio_file.hpp"

namespace chladni::cli {

struct SpectrogramOptions {
  int fft_size = 1024;
  int hop = 256;
  int height = 512;      ///< pixels; frequency bins are merged or repeated to fit
  int max_width = 4096;  ///< hops are merged (max power) beyond this many columns
  double range_db = 90;  ///< below the loudest cell maps to black
};

/// Channels are mixed to mono. Throws InputError when the file cannot be written.
void write_spectrogram_png(const std::string& path, const AudioBuffer& audio,
                           const SpectrogramOptions& options = {});

}  // namespace chladni::cli
