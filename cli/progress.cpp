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
  ++index_;
  t0_ = std::chrono::steady_clock::now();
  if (plain_) std::fprintf(stderr, "[%d] %s\n", index_, name.c_str());
  draw(-1);
}

void ProgressBar::fraction(double f) {
  const auto now = std::chrono::steady_clock::now();
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
  std::fprintf(stderr, "\r\033[K[%d] %-22s %s %6.1f s", index_, stage_.c_str(), bar, secs);
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
