#include "chladni/plot/sound_figure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "chladni/core/error.hpp"

namespace chladni::plot {

double frequency_row(const Rect& r, double f, double fmin, double fmax, bool linear) {
  const double u = linear ? f / fmax : std::log(f / fmin) / std::log(fmax / fmin);
  return r.y + r.h * (1 - u);
}

void write_sound_png(const std::string& path, const std::vector<double>& mono, double fs,
                     const SoundFigureOptions& o) {
  if (!(fs > 0)) throw InputError(path + ": no sample rate to plot at");
  const Spectrogram s = spectrogram(mono, fs);
  Figure fig(kSoundFigureWidth, kSoundFigureHeight, o.title);
  const double top = std::max(double(s.max_db()), -200.0);
  char sub[96];
  std::snprintf(sub, sizeof sub, "%.2f s at %.0f Hz; power in dB re full scale", mono.size() / fs,
                fs);
  fig.spectrogram(kSoundPanel, s, sub, o.fmin, fs / 2, top, o.range_db, o.linear, o.events);
  fig.write_png(path);
}

}  // namespace chladni::plot
