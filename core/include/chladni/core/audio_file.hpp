#pragma once
// Audio file I/O through libsndfile.
#include <string>
#include <vector>

namespace chladni {

enum class SampleFormat { Float32, Pcm24, Pcm16 };

struct AudioBuffer {
  int sample_rate = 48000;
  int channels = 1;
  std::vector<float> samples;  ///< interleaved, frames * channels
  std::size_t frames() const { return channels ? samples.size() / channels : 0; }
};

/// Writes a WAV file; throws InputError if the file cannot be opened, InternalError on a short
/// write.
void write_wav(const std::string& path, const AudioBuffer& audio,
               SampleFormat format = SampleFormat::Float32);

/// Reads any file libsndfile understands (WAV, FLAC, ...) as float samples.
AudioBuffer read_audio(const std::string& path);

}  // namespace chladni
