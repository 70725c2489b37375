// Bytes -> load_paper_animation. The folder holds a valid two-frame sheet both as OBJ frames
// (sheet_0000.obj, sheet_0001.obj) and as sheet.chpaper, so fuzzed JSON can refer to either.
#include "chladni/core/paper_animation.hpp"
#include "fuzz_support.hpp"

namespace {

void write_frames() {
  chladni::PaperAnimation anim;
  anim.vertex_count = 4;
  anim.triangles = {{0, 1, 2}, {0, 2, 3}};
  anim.positions = {0, 0, 0, 0.1f, 0, 0,     0.1f, 0.1f, 0,     0, 0.1f, 0,
                    0, 0, 0, 0.1f, 0, 0.01f, 0.1f, 0.1f, 0.01f, 0, 0.1f, 0};
  chladni::write_paper_frames_binary((chladni::fuzz::work_dir() / "sheet.chpaper").string(), anim);
  for (int f = 0; f < 2; ++f) {
    std::string obj;
    for (int v = 0; v < 4; ++v)
      obj += "v " + std::to_string(anim.positions[12 * f + 3 * v]) + " " +
             std::to_string(anim.positions[12 * f + 3 * v + 1]) + " " +
             std::to_string(anim.positions[12 * f + 3 * v + 2]) + "\n";
    obj += "f 1 2 3\nf 1 3 4\n";
    const std::string name = "sheet_000" + std::to_string(f) + ".obj";
    chladni::fuzz::write_input(name, reinterpret_cast<const uint8_t*>(obj.data()), obj.size());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = (write_frames(), true);
  (void)ready;
  const std::string path = chladni::fuzz::write_input("animation.json", data, size);
  chladni::fuzz::expect_clean(path, [&] { (void)chladni::load_paper_animation(path); });
  return 0;
}
