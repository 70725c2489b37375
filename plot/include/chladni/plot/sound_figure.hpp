#pragma once
// The spectrogram every command that makes a sound writes with --spectrogram: time (s) against
// frequency (Hz, logarithmic unless asked for linear), a dB colour bar, a title naming the input
// and settings, and the command's events (impacts, paper events, shakes) as dashed markers.
#include <string>
#include <vector>

#include "chladni/plot/figure.hpp"

namespace chladni::plot {

struct SoundFigureOptions {
  std::string title;    ///< the input and the settings that made the sound
  Events events;        ///< times the command knows (s)
  bool linear = false;  ///< linear frequency axis from 0 Hz
  double fmin = 20;     ///< bottom of the logarithmic axis (Hz)
  double range_db = 90;
};

/// Layout of the figure, public so that a test can tell where a frequency lands.
inline constexpr int kSoundFigureWidth = 1200, kSoundFigureHeight = 620;
inline constexpr Rect kSoundPanel{90, 70, 1000, 470};

/// Pixel row (from the image top) of frequency `f` in a panel spanning [fmin, fmax].
double frequency_row(const Rect& panel, double f, double fmin, double fmax, bool linear);

/// Writes `mono` (sample rate `fs`) as that figure; InputError naming `path` if it cannot.
void write_sound_png(const std::string& path, const std::vector<double>& mono, double fs,
                     const SoundFigureOptions& options);

}  // namespace chladni::plot
