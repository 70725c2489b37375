#pragma once
// A recording of one strike, read for analysis: mono, checked, and cut to the part to analyse.
#include <string>
#include <vector>

namespace chladni::estimate {

struct Recording {
  std::string origin;           ///< the file, for messages
  double sample_rate = 0;       ///< Hz
  std::vector<double> samples;  ///< mono (the mean of the file's channels), full scale 1
  int channels = 1;             ///< channels of the file
  std::size_t clipped = 0;      ///< samples at full scale in runs of three or more
};

struct RecordingOptions {
  double start = 0;  ///< seconds into the file where analysis may begin
  double end = 0;    ///< seconds into the file where it stops (0: the end)
};

/// Documented limits (docs/estimate.md): at most an hour of audio, 4 kHz to 768 kHz.
inline constexpr double kMaxRecordingSeconds = 3600;

/// Reads WAV, FLAC or anything libsndfile reads. Throws InputError naming the file when it is
/// missing, a directory, unreadable, longer than the limit, holds non-finite samples, or when
/// start/end leave nothing.
Recording read_recording(const std::string& path, const RecordingOptions& options = {});

/// Checks that `r` holds a strike to analyse: not silent, not DC alone, and with at least
/// 50 ms of sound after its peak. Throws InputError naming r.origin otherwise.
void check_recording(const Recording& r);

}  // namespace chladni::estimate
