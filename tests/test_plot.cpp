// The labelled figures: a sound's spectrogram puts known tones and a chirp at the rows its axis
// says, has axes, ticks and labels around the panel, and every command that draws writes one.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "browser.hpp"
#include "chladni/plot/sound_figure.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace {

using chladni::plot::kSoundPanel;
using chladni::test::Image;

double luminance(const Image& im, int x, int y) {
  const uint8_t* p = im.at(x, y);
  return 0.3 * p[0] + 0.59 * p[1] + 0.11 * p[2];
}

// The middle of the brightest run of rows of column x inside the panel (where several rows show
// one frequency bin, they are equally bright).
double brightest_row(const Image& im, int x) {
  int best = 0;
  double top = -1;
  const int y0 = int(kSoundPanel.y) + 1, y1 = int(kSoundPanel.y + kSoundPanel.h) - 1;
  for (int y = y0; y < y1; ++y)
    if (luminance(im, x, y) > top) top = luminance(im, x, y), best = y;
  int end = best;
  while (end + 1 < y1 && luminance(im, x, end + 1) >= top - 1) ++end;
  return 0.5 * (best + end);
}

// Non-white pixels in a rectangle: ticks, numbers, labels.
int inked(const Image& im, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += luminance(im, x, y) < 200;
  return n;
}

TEST(PlotPng, TonesAndAChirpLandOnTheirRows) {
  const double fs = 48000, fmin = 20, fmax = fs / 2;
  for (bool linear : {false, true}) {
    // 0-1 s: a 440 Hz tone then (1-2 s) 3.5 kHz; 2-4 s: a log chirp 200 Hz -> 8 kHz.
    std::vector<double> x(std::size_t(4 * fs));
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double t = i / fs;
      if (t < 1)
        x[i] = 0.5 * std::sin(2 * std::numbers::pi * 440 * t);
      else if (t < 2)
        x[i] = 0.5 * std::sin(2 * std::numbers::pi * 3500 * t);
      else {
        const double T = 2, k = std::log(8000 / 200.0) / T, u = t - 2;
        x[i] = 0.5 * std::sin(2 * std::numbers::pi * 200 * (std::exp(k * u) - 1) / k);
      }
    }
    const std::string path = chladni::test::temp_path(linear ? "plot_lin.png" : "plot_log.png");
    chladni::plot::SoundFigureOptions o;
    o.title = "test tones";
    o.linear = linear;
    o.events = {{1.0, 2.0}, "switch"};
    chladni::plot::write_sound_png(path, x, fs, o);
    const Image im = chladni::test::read_png(path);
    ASSERT_EQ(im.width, chladni::plot::kSoundFigureWidth);
    ASSERT_EQ(im.height, chladni::plot::kSoundFigureHeight);
    auto column = [&](double t) { return int(kSoundPanel.x + kSoundPanel.w * t / 4.0); };
    auto row = [&](double f) {
      return chladni::plot::frequency_row(kSoundPanel, f, fmin, fmax, linear);
    };
    // Within two pixels and the height of one FFT bin (2048 points) at f.
    const double bin = fs / 2048;
    auto tol = [&](double f) { return 2 + std::abs(row(f + bin / 2) - row(f - bin / 2)); };
    const char* axis = linear ? "linear" : "log";
    EXPECT_NEAR(brightest_row(im, column(0.5)), row(440), tol(440)) << axis;
    EXPECT_NEAR(brightest_row(im, column(1.5)), row(3500), tol(3500)) << axis;
    for (double u : {0.3, 1.0, 1.7}) {  // the chirp moves during a frame: two pixels more
      const double f = 200 * std::exp(std::log(40.0) * u / 2);
      EXPECT_NEAR(brightest_row(im, column(2 + u)), row(f), tol(f) + 2) << f << " Hz, " << axis;
    }
    // Axes: ticks and numbers left of and below the panel, a colour bar at its right.
    const int px = int(kSoundPanel.x), py = int(kSoundPanel.y), pw = int(kSoundPanel.w),
              ph = int(kSoundPanel.h);
    EXPECT_GT(inked(im, px - 60, py, px - 2, py + ph), 100) << "frequency axis";
    EXPECT_GT(inked(im, px, py + ph + 2, px + pw, py + ph + 45), 100) << "time axis";
    EXPECT_GT(inked(im, px + pw + 10, py, px + pw + 60, py + ph), 500) << "colour bar";
    EXPECT_GT(inked(im, 0, 0, im.width, py - 20), 50) << "title";
  }
}

TEST(PlotPng, RenderShakeAndInfoWriteLabelledFigures) {
  using chladni::test::run_cli;
  const std::string d = chladni::test::temp_path("");
  auto r = run_cli("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " + d +
                   "plot_r.wav --spectrogram " + d + "plot_r.png -q");
  ASSERT_EQ(r.code, 0) << r.output;
  Image im = chladni::test::read_png(d + "plot_r.png");
  EXPECT_EQ(im.width, chladni::plot::kSoundFigureWidth);
  EXPECT_EQ(im.height, chladni::plot::kSoundFigureHeight);
  r = run_cli("shake maraca -o " + d + "plot_s.wav --duration 0.5 --spectrogram " + d +
              "plot_s.png --linear-frequency -q");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(chladni::test::read_png(d + "plot_s.png").width, chladni::plot::kSoundFigureWidth);
  r = run_cli("precompute " CHLADNI_SOURCE_DIR "/meshes/bar.obj -o " + d +
              "plot_bar.chbank --max-modes 6 --no-transfer -q");
  ASSERT_EQ(r.code, 0) << r.output;
  r = run_cli("info " + d + "plot_bar.chbank --plot " + d + "plot_info.png");
  ASSERT_EQ(r.code, 0) << r.output;
  im = chladni::test::read_png(d + "plot_info.png");
  EXPECT_EQ(im.width, 1200);
  EXPECT_GT(inked(im, 40, 70, 100, 430), 100) << "damping axis";
  // A plot path that is a folder is refused before any work.
  r = run_cli("render " CHLADNI_SOURCE_DIR "/examples/struck_bar.json -o " + d +
              "plot_r2.wav --spectrogram " + d + " -q");
  EXPECT_EQ(r.code, 2) << r.output;
}

}  // namespace
