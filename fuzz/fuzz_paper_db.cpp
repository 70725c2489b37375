// Bytes -> load_paper_database's index (paper_db.json); the folder holds two short valid WAVs
// (a.wav at 44.1 kHz, b.wav at 22.05 kHz) for entries to name.
#include "chladni/core/audio_file.hpp"
#include "chladni/runtime/paper/paper_database.hpp"
#include "fuzz_support.hpp"

namespace {

void write_audio() {
  chladni::AudioBuffer a;
  a.sample_rate = 44100;
  a.channels = 1;
  a.samples.assign(441, 0.25f);
  chladni::write_wav((chladni::fuzz::work_dir() / "a.wav").string(), a);
  a.sample_rate = 22050;
  chladni::write_wav((chladni::fuzz::work_dir() / "b.wav").string(), a);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = (write_audio(), true);
  (void)ready;
  const std::string path = chladni::fuzz::write_input("paper_db.json", data, size);
  chladni::fuzz::expect_clean(chladni::fuzz::work_dir().string(), [&] {
    (void)chladni::runtime::load_paper_database(chladni::fuzz::work_dir().string());
  });
  return 0;
}
