#pragma once
// Labelled plots as PNG through cairo (text in DejaVu Sans): panels with linear or logarithmic
// axes, ticks and units, spectrograms with a dB colour bar, lines, points with error bars and a
// legend. One figure holds several panels; write_png() replaces the file atomically.
#include <memory>
#include <string>
#include <vector>

namespace chladni::plot {

struct Rect {
  double x = 0, y = 0, w = 0, h = 0;  ///< pixels, origin top left
};

struct Axis {
  std::string label;  ///< with its unit, e.g. "frequency (Hz)"
  double lo = 0, hi = 1;
  bool log = false;
};

struct Colour {
  double r = 0, g = 0, b = 0;
};

/// A short-time spectrum in dB: frames x bins, frame k at time k * hop, bin j at j * bin_hz.
struct Spectrogram {
  std::size_t frames = 0, bins = 0;
  double hop_s = 0, bin_hz = 0;
  std::vector<float> db;  ///< frames * bins, 10 log10 of the power
  float max_db() const;
};

/// Hann-windowed STFT of `x` at sample rate `fs`. Past `max_frames` hops, consecutive frames are
/// merged (the loudest per bin), so a long sound keeps its short events in bounded memory.
Spectrogram spectrogram(const std::vector<double>& x, double fs, std::size_t fft_size = 2048,
                        std::size_t hop = 256, std::size_t max_frames = 4096);

/// Markers in time (s), drawn as dashed verticals over a spectrogram; `label` names them in the
/// panel's legend.
struct Events {
  std::vector<double> times;
  std::string label;
};

class Figure {
 public:
  Figure(int width, int height, const std::string& title);
  ~Figure();
  Figure(const Figure&) = delete;
  Figure& operator=(const Figure&) = delete;

  /// A spectrogram panel: time on x, frequency on y (log from `fmin` unless `linear`), the
  /// colour from `top_db` down `range_db`, with a colour bar at the right of `r`.
  void spectrogram(const Rect& r, const Spectrogram& s, const std::string& title, double fmin,
                   double fmax, double top_db, double range_db = 80, bool linear = false,
                   const Events& events = {});

  /// Starts an x-y panel; the calls below draw into the last one started.
  void panel(const Rect& r, const Axis& x, const Axis& y, const std::string& title);
  void line(const std::vector<double>& x, const std::vector<double>& y, Colour c,
            const std::string& label, double width = 2.0);
  /// Points with vertical bars from lo to hi (empty: no bars).
  void points(const std::vector<double>& x, const std::vector<double>& y,
              const std::vector<double>& lo, const std::vector<double>& hi, Colour c,
              const std::string& label);

  /// Writes the figure; throws InputError naming `path` when it cannot.
  void write_png(const std::string& path);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chladni::plot
