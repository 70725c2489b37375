#include "peak_memory.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>

namespace chladni::precompute {
namespace {

std::atomic<bool> g_reset_ok{false};
std::atomic<double> g_child{0}, g_process{0};

void raise(std::atomic<double>& a, double v) {
  double now = a.load();
  while (v > now && !a.compare_exchange_weak(now, v)) {
  }
}

// VmHWM from /proc/self/status, bytes; 0 where it cannot be read.
double high_water_mark() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  double kib = 0;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, "VmHWM:", 6) == 0) {
      kib = std::strtod(line + 6, nullptr);
      break;
    }
  std::fclose(f);
  return kib * 1024;
}

}  // namespace

bool reset_peak_memory() {
  raise(g_process, high_water_mark());  // what the reset is about to forget
  g_child = 0;
  std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
  bool ok = f && std::fputs("5", f) >= 0;
  if (f) ok = std::fclose(f) == 0 && ok;
  g_reset_ok = ok;
  return ok;
}

double peak_memory_bytes() {
  const double self = high_water_mark();
  raise(g_process, self);
  if (!g_reset_ok) return 0;
  return std::max(self, g_child.load());
}

double process_peak_bytes() {
  raise(g_process, high_water_mark());
  return g_process;
}

void note_child_peak(const rusage& child) {
  const double bytes = double(child.ru_maxrss) * 1024;  // KiB on Linux
  raise(g_child, bytes);
  raise(g_process, bytes);
}

}  // namespace chladni::precompute
