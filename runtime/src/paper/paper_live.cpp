// PaperRenderer's output window and live side: frames from the caller, audio taken as it becomes
// final. The output is a window from out_base_ that grows ahead as sounds start and shrinks from
// the front as it is read, so a live sheet holds about one crumple clip of audio however long it
// plays; offline it is the whole sound, taken once by finish().
#include <algorithm>
#include <cmath>
#include <string>

#include "chladni/core/error.hpp"
#include "chladni/runtime/paper/paper_synth.hpp"

namespace chladni::runtime {

float* PaperRenderer::window(int ch, std::int64_t from, std::int64_t to) {
  std::vector<float>& out = out_[ch];
  const std::size_t need = static_cast<std::size_t>(to - out_base_);
  if (out.size() < need) out.resize(need, 0.0f);
  return out.data() + (from - out_base_);
}

void PaperRenderer::add_interleaved(std::int64_t at, const float* x, std::int64_t frames) {
  float* left = window(0, at, at + frames);
  float* right = window(1, at, at + frames);
  for (std::int64_t i = 0; i < frames; ++i) {
    left[i] += x[2 * i];
    right[i] += x[2 * i + 1];
  }
}

// A non-finite sample is a bug: reported, naming its frame, before anything moves.
void PaperRenderer::take(float* out, std::size_t frames) {
  const std::int64_t n = static_cast<std::int64_t>(frames);
  const float* left = window(0, out_base_, out_base_ + n);
  const float* right = window(1, out_base_, out_base_ + n);
  for (std::size_t t = 0; t < frames; ++t)
    if (!std::isfinite(left[t]) || !std::isfinite(right[t]))
      throw InternalError("paper synthesis produced a non-finite sample at frame " +
                          std::to_string(out_base_ + std::int64_t(t)));
  for (std::size_t t = 0; t < frames; ++t) {
    out[2 * t] = left[t];
    out[2 * t + 1] = right[t];
  }
  for (auto& ch : out_) ch.erase(ch.begin(), ch.begin() + n);
  out_base_ += n;
}

const PaperFrameAnalysis& PaperRenderer::step(std::span<const float> xyz,
                                              const std::vector<std::uint32_t>* held) {
  if (!opt_.live) throw InternalError("PaperRenderer::step(xyz) on an offline renderer");
  if (ended_ >= 0) throw InputError("paper synthesis: a frame after the sheet's end");
  return step_at(xyz, held);
}

void PaperRenderer::end() {
  if (!opt_.live || ended_ >= 0) return;
  // Where the offline renderer of the same frames ends: the frames' duration and the tail.
  ended_ = static_cast<std::int64_t>(
      std::ceil((next_frame_ / anim_.frame_rate + opt_.tail_seconds) * opt_.sample_rate));
  limit_ = ended_;
  render_tail(ended_);
  report_.audio_seconds = double(ended_) / opt_.sample_rate;
}

void PaperRenderer::set_listener(const PaperListener& listener) {
  ears_ = ear_positions(listener);
  head_ = listener.position;
}

std::size_t PaperRenderer::ready() const {
  // Final: every path has rendered past it, and no frame to come can start a sound before it
  // (a crumple clip starts at its frame's sample or later).
  std::int64_t final = ended_ >= 0 ? ended_ : sample_of(next_frame_);
  if (noise_) final = std::min(final, friction_pos_);
  if (synth_) final = std::min(final, modal_pos_);
  return static_cast<std::size_t>(std::max<std::int64_t>(0, final - out_base_));
}

void PaperRenderer::read(float* out, std::size_t frames) {
  if (frames > ready()) throw InternalError("PaperRenderer::read past the final samples");
  take(out, frames);
}

}  // namespace chladni::runtime
