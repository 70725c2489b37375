#include "spectrogram.hpp"

#include <cstdio>
#include <vector>

namespace chladni::cli {

void add_spectrogram_options(CLI::App& cmd, SpectrogramArgs& a) {
  cmd.add_option("--spectrogram", a.path,
                 "Also write the sound's spectrogram as PNG (time, log frequency, dB)");
  cmd.add_flag("--linear-frequency", a.linear,
               "Linear frequency axis for --spectrogram (default: logarithmic from 20 Hz)");
}

void write_spectrogram(const SpectrogramArgs& a, const AudioBuffer& audio, const std::string& title,
                       const plot::Events& events, bool quiet) {
  if (a.path.empty()) return;
  const std::size_t frames = audio.frames();
  const int ch = std::max(1, audio.channels);
  std::vector<double> mono(frames, 0.0);
  for (std::size_t t = 0; t < frames; ++t)
    for (int c = 0; c < ch; ++c) mono[t] += audio.samples[t * ch + c] / double(ch);
  plot::SoundFigureOptions o;
  o.title = title;
  o.events = events;
  o.linear = a.linear;
  plot::write_sound_png(a.path, mono, audio.sample_rate, o);
  if (!quiet) std::printf("wrote %s\n", a.path.c_str());
}

}  // namespace chladni::cli
