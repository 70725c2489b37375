#pragma once
// A C API runtime at 44.1 kHz with one paper sheet, the shipped crumpling animation's, in modal
// mode (no database): for the tests that post its frames from one thread and render on another.
#include <gtest/gtest.h>

#include <string>

#include "chladni/chladni.h"
#include "chladni/core/paper_animation.hpp"

namespace chladni::test {

struct CApiPaperSheet {
  CApiPaperSheet() {
    chladni_config c;
    chladni_config_default(&c);
    c.threads = 1;
    c.sample_rate = 44100;
    c.max_papers = 1;
    EXPECT_EQ(chladni_runtime_create(&c, &rt), CHLADNI_OK) << chladni_last_error();
    desc.animation = path.c_str();
    if (rt) {
      EXPECT_EQ(chladni_paper_add(rt, &desc, &sheet), CHLADNI_OK) << chladni_last_error();
    }
  }
  ~CApiPaperSheet() { chladni_runtime_destroy(rt); }
  CApiPaperSheet(const CApiPaperSheet&) = delete;
  CApiPaperSheet& operator=(const CApiPaperSheet&) = delete;
  /// Posts frame `f` of the animation.
  chladni_status post(std::uint32_t f) {
    return chladni_paper_post_frame(rt, sheet, anim.frame(f).data(), anim.vertex_count, nullptr, 0);
  }
  /// Whether the sheet's place is free again (retired by the audio thread, freed here): a new
  /// sheet fits in max_papers = 1.
  bool place_given_back() {
    chladni_paper again{0};
    return chladni_paper_add(rt, &desc, &again) == CHLADNI_OK;
  }

  const std::string path = CHLADNI_SOURCE_DIR "/meshes/paper/crumple.json";
  const PaperAnimation anim = load_paper_animation(path);
  chladni_paper_desc desc{};
  chladni_runtime* rt = nullptr;
  chladni_paper sheet{0};
};

}  // namespace chladni::test
