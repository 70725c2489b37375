#include "chladni/core/audio_file.hpp"

#include <sndfile.h>

#include <filesystem>

#include "chladni/core/error.hpp"
#include "chladni/core/output_file.hpp"

namespace chladni {

void write_wav(const std::string& path, const AudioBuffer& audio, SampleFormat format) {
  if (audio.channels < 1 || audio.sample_rate < 1 || audio.samples.size() % audio.channels) {
    throw InputError("write_wav " + path + ": inconsistent channel count or sample count");
  }
  SF_INFO info{};
  info.samplerate = audio.sample_rate;
  info.channels = audio.channels;
  info.format = SF_FORMAT_WAV | (format == SampleFormat::Float32 ? SF_FORMAT_FLOAT
                                 : format == SampleFormat::Pcm24 ? SF_FORMAT_PCM_24
                                                                 : SF_FORMAT_PCM_16);
  // Into a temporary beside the target, renamed over it once complete.
  const std::string tmp = temporary_path(path);
  SNDFILE* f = sf_open(tmp.c_str(), SFM_WRITE, &info);
  if (!f) throw InputError("cannot write " + path + ": " + sf_strerror(nullptr));
  if (format != SampleFormat::Float32) sf_command(f, SFC_SET_CLIPPING, nullptr, SF_TRUE);
  const sf_count_t frames = static_cast<sf_count_t>(audio.frames());
  const sf_count_t written = sf_writef_float(f, audio.samples.data(), frames);
  const std::string err = sf_strerror(f);
  sf_close(f);
  if (written != frames) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw InputError("cannot write " + path + ": short write (" + err + ")");
  }
  commit_temporary(tmp, path, "audio file");
}

AudioBuffer read_audio(const std::string& path) {
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (!f) throw InputError("cannot read audio file " + path + ": " + sf_strerror(nullptr));
  AudioBuffer out;
  out.sample_rate = info.samplerate;
  out.channels = info.channels;
  out.samples.resize(static_cast<std::size_t>(info.frames) * info.channels);
  const sf_count_t got = sf_readf_float(f, out.samples.data(), info.frames);
  sf_close(f);
  if (got != info.frames) throw InputError("audio file " + path + " is truncated");
  return out;
}

}  // namespace chladni
