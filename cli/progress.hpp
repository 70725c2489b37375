#pragma once
// Progress on stderr for long commands: a redrawn bar with the time left on a terminal, plain
// lines (each stage, each tenth of a stage that reports its fraction, each note) otherwise;
// warnings are printed even when quiet.
#include <chrono>
#include <string>

namespace chladni::cli {

class ProgressBar {
 public:
  /// enabled (the bar) = !quiet && stderr is a terminal; plain lines when not a terminal.
  explicit ProgressBar(bool quiet);
  ~ProgressBar();
  void stage(const std::string& name);
  void fraction(double f);  ///< 0..1 of the current stage
  void note(const std::string& text);
  void finish();
  bool enabled() const { return enabled_; }

 private:
  void draw(double f);
  bool enabled_, plain_;
  std::string stage_;
  int index_ = 0;
  int tenths_ = 0;  ///< of the current stage, printed as plain lines
  std::chrono::steady_clock::time_point t0_, last_draw_;
  bool open_line_ = false;
};

}  // namespace chladni::cli
