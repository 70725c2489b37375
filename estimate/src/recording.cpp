#include "chladni/estimate/recording.hpp"

#include <sndfile.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "chladni/core/error.hpp"

namespace chladni::estimate {
namespace {

std::string seconds_text(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g s", s);
  return text;
}

// Samples at the file's largest magnitude in runs of three or more: a clipped converter or an
// editor's hard limit.
std::size_t clipped_samples(const std::vector<double>& x) {
  double peak = 0;
  for (double v : x) peak = std::max(peak, std::abs(v));
  if (peak <= 0) return 0;
  std::size_t count = 0, run = 0;
  for (double v : x) {
    run = std::abs(v) >= peak * (1 - 1e-6) ? run + 1 : 0;
    if (run == 3) count += 3;
    if (run > 3) ++count;
  }
  return count;
}

}  // namespace

Recording read_recording(const std::string& path, const RecordingOptions& o) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status))
    throw InputError("recording " + path + ": no such file");
  if (!std::filesystem::is_regular_file(status))
    throw InputError("recording " + path + ": not a regular file");
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (!f) throw InputError("recording " + path + ": " + sf_strerror(nullptr));
  struct Closer {
    SNDFILE* f;
    ~Closer() { sf_close(f); }
  } closer{f};
  if (info.channels < 1 || info.channels > 64)
    throw InputError("recording " + path + ": " + std::to_string(info.channels) +
                     " channels (1 to 64 are read)");
  if (info.samplerate < 4000 || info.samplerate > 768000)
    throw InputError("recording " + path + ": sample rate " + std::to_string(info.samplerate) +
                     " Hz (4 kHz to 768 kHz are read)");
  const double fs = info.samplerate;
  if (double(info.frames) > kMaxRecordingSeconds * fs)
    throw InputError("recording " + path + ": " + seconds_text(double(info.frames) / fs) +
                     " long; at most an hour is analysed (cut it, or use --start/--end)");
  if (!(o.start >= 0) || !(o.end >= 0) || !std::isfinite(o.start) || !std::isfinite(o.end))
    throw InputError("recording " + path + ": start and end must be finite and >= 0");
  const auto first = static_cast<sf_count_t>(std::llround(o.start * fs));
  const sf_count_t last =
      o.end > 0 ? std::min<sf_count_t>(info.frames, std::llround(o.end * fs)) : info.frames;
  if (first >= last)
    throw InputError("recording " + path + ": nothing between start " + seconds_text(o.start) +
                     " and end " + (o.end > 0 ? seconds_text(o.end) : "of file") + " (it is " +
                     seconds_text(double(info.frames) / fs) + " long)");
  if (first > 0 && sf_seek(f, first, SEEK_SET) != first)
    throw InputError("recording " + path + ": cannot seek to " + seconds_text(o.start));
  const auto frames = static_cast<std::size_t>(last - first);
  std::vector<float> raw(frames * static_cast<std::size_t>(info.channels));
  if (sf_readf_float(f, raw.data(), static_cast<sf_count_t>(frames)) !=
      static_cast<sf_count_t>(frames))
    throw InputError("recording " + path + ": truncated");
  Recording r;
  r.origin = path;
  r.sample_rate = fs;
  r.channels = info.channels;
  r.samples.resize(frames);
  for (std::size_t i = 0; i < frames; ++i) {
    double sum = 0;
    for (int c = 0; c < info.channels; ++c) {
      const float v = raw[i * info.channels + c];
      if (!std::isfinite(v))
        throw InputError("recording " + path + ": sample " + std::to_string(first + i) +
                         " (channel " + std::to_string(c) + ") is not finite");
      sum += v;
    }
    r.samples[i] = sum / info.channels;
  }
  r.clipped = clipped_samples(r.samples);
  return r;
}

void check_recording(const Recording& r) {
  const auto& x = r.samples;
  double peak = 0, mean = 0;
  for (double v : x) {
    peak = std::max(peak, std::abs(v));
    mean += v;
  }
  mean /= std::max<std::size_t>(x.size(), 1);
  if (peak < 1e-6) throw InputError("recording " + r.origin + ": silent (peak below -120 dBFS)");
  double ac = 0;
  for (double v : x) ac = std::max(ac, std::abs(v - mean));
  if (ac < 1e-3 * peak)
    throw InputError("recording " + r.origin + ": a constant (DC) signal, nothing rings");
  std::size_t at = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::abs(x[i]) > std::abs(x[at])) at = i;
  const double after = double(x.size() - at) / r.sample_rate;
  if (after < 0.05)
    throw InputError("recording " + r.origin + ": only " + seconds_text(after) +
                     " after its peak; at least 50 ms of ringing are needed");
}

}  // namespace chladni::estimate
