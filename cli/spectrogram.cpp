#include "spectrogram.hpp"

#include <fftw3.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"

namespace chladni::cli {
namespace {

// A perceptually ordered dark-to-bright ramp (black, purple, red, orange, pale yellow).
void colour(double x, png_byte* rgb) {
  static const double stops[5][3] = {
      {0, 0, 4}, {80, 18, 123}, {182, 54, 121}, {251, 136, 97}, {252, 253, 191}};
  x = std::clamp(x, 0.0, 1.0) * 4;
  const int i = std::min(3, static_cast<int>(x));
  const double t = x - i;
  for (int c = 0; c < 3; ++c)
    rgb[c] = static_cast<png_byte>(std::lround(stops[i][c] * (1 - t) + stops[i + 1][c] * t));
}

}  // namespace

void write_spectrogram_png(const std::string& path, const AudioBuffer& audio,
                           const SpectrogramOptions& o) {
  const std::size_t frames = audio.frames();
  const int n = o.fft_size, bins = n / 2;
  std::vector<float> mono(frames + n, 0.0f);
  for (std::size_t t = 0; t < frames; ++t)
    for (int c = 0; c < audio.channels; ++c) mono[t] += audio.samples[t * audio.channels + c];
  const std::size_t hops = std::max<std::size_t>(1, (frames + o.hop - 1) / o.hop);
  const std::size_t per_column = (hops + o.max_width - 1) / o.max_width;
  const std::size_t width = (hops + per_column - 1) / per_column;
  const int height = o.height;

  float* in = fftwf_alloc_real(n);
  fftwf_complex* spec = fftwf_alloc_complex(n / 2 + 1);
  fftwf_plan plan = fftwf_plan_dft_r2c_1d(n, in, spec, FFTW_ESTIMATE);
  std::vector<double> power(width * height, 0.0);
  for (std::size_t h = 0; h < hops; ++h) {
    for (int i = 0; i < n; ++i) {
      const double w = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * i / n);
      in[i] = static_cast<float>(w * mono[h * o.hop + i]);
    }
    fftwf_execute(plan);
    const std::size_t col = h / per_column;
    for (int y = 0; y < height; ++y) {
      // Row y covers bins [y * bins / height, (y + 1) * bins / height): the strongest one.
      const int b0 = y * bins / height, b1 = std::max(b0 + 1, (y + 1) * bins / height);
      double p = 0;
      for (int b = b0; b < b1; ++b)
        p = std::max(p, double(spec[b][0]) * spec[b][0] + double(spec[b][1]) * spec[b][1]);
      double& cell = power[col * height + y];
      cell = std::max(cell, p);
    }
  }
  fftwf_destroy_plan(plan);
  fftwf_free(in);
  fftwf_free(spec);

  const double peak = *std::max_element(power.begin(), power.end());
  std::vector<png_byte> image(width * height * 3);
  for (std::size_t x = 0; x < width; ++x)
    for (int y = 0; y < height; ++y) {
      const double p = power[x * height + y];
      const double db = peak > 0 && p > 0 ? 10 * std::log10(p / peak) : -1e9;
      colour(1 + db / o.range_db, &image[((height - 1 - y) * width + x) * 3]);
    }

  // Into a temporary beside the target, renamed over it once complete.
  const std::string tmp = temporary_path(path);
  {
    std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(tmp.c_str(), "wb"), &std::fclose);
    if (!file) throw InputError(path + ": cannot open for writing");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) throw InternalError("libpng: out of memory");
    if (setjmp(png_jmpbuf(png))) {  // libpng reports errors by longjmp
      png_destroy_write_struct(&png, &info);
      file.reset();
      std::remove(tmp.c_str());
      throw InputError(path + ": writing the PNG failed");
    }
    png_init_io(png, file.get());
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < height; ++y) png_write_row(png, &image[std::size_t(y) * width * 3]);
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    if (std::fflush(file.get()) != 0) {
      file.reset();
      std::remove(tmp.c_str());
      throw InputError(path + ": writing the PNG failed");
    }
  }
  commit_temporary(tmp, path, "spectrogram");
}

}  // namespace chladni::cli
