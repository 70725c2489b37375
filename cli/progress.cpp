#include "progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace chladni::cli {

ProgressBar::ProgressBar(bool quiet)
    : enabled_(!quiet && isatty(STDERR_FILENO)), plain_(!quiet && !enabled_) {}
ProgressBar::~ProgressBar() {
  finish();
}

void ProgressBar::stage(const std::string& name) {
  finish();
  stage_ = name;
  tenths_ = 0;
  ++index_;
  t0_ = std::chrono::steady_clock::now();
  if (plain_) std::fprintf(stderr, "[%d] %s\n", index_, name.c_str());
  draw(-1);
}

void ProgressBar::fraction(double f) {
  const auto now = std::chrono::steady_clock::now();
  // Plain lines (a log, a batch's child) get one line per tenth of a stage, with the time left.
  if (plain_ && f < 1 && int(f * 10) > tenths_) {
    tenths_ = int(f * 10);
    const double secs = std::chrono::duration<double>(now - t0_).count();
    std::fprintf(stderr, "  %s: %d %% (%.0f s, about %.0f s left)\n", stage_.c_str(), 10 * tenths_,
                 secs, secs * (1 - f) / f);
  }
  if (now - last_draw_ < std::chrono::milliseconds(100) && f < 1) return;
  last_draw_ = now;
  draw(f);
}

void ProgressBar::note(const std::string& text) {
  if (!enabled_) {
    if (plain_ || text.rfind("warning:", 0) == 0) std::fprintf(stderr, "  %s\n", text.c_str());
    return;
  }
  std::fprintf(stderr, "\r\033[K  %s\n", text.c_str());
  open_line_ = false;
  draw(-1);
}

void ProgressBar::draw(double f) {
  if (!enabled_ || stage_.empty()) return;
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  char bar[32] = "";
  if (f >= 0) {
    const int filled = static_cast<int>(f * 20 + 0.5);
    int k = 0;
    bar[k++] = '[';
    for (int i = 0; i < 20; ++i) bar[k++] = i < filled ? '#' : '.';
    bar[k++] = ']';
    bar[k] = 0;
  }
  // The time left, by the rate so far, once the rate means something.
  char left[32] = "";
  if (f >= 0.02 && f < 1 && secs >= 1)
    std::snprintf(left, sizeof left, ", about %.0f s left", secs * (1 - f) / f);
  std::fprintf(stderr, "\r\033[K[%d] %-22s %s %6.1f s%s", index_, stage_.c_str(), bar, secs, left);
  std::fflush(stderr);
  open_line_ = true;
}

void ProgressBar::finish() {
  if (enabled_ && open_line_) {
    draw(-1);
    std::fprintf(stderr, "\n");
  }
  open_line_ = false;
  stage_.clear();
}

}  // namespace chladni::cli
