#pragma once
// Peak resident memory per stage of a precompute. Linux keeps a process's high-water mark of
// resident memory (VmHWM) and lets the process reset it (clear_refs, since 4.0), so a stage's
// peak is the mark read at its end after a reset at its start. A forked child's peak (TetGen's,
// the second BEM solver's) comes from wait4; its resident set includes the pages it shares with
// this process, so the larger of the two is the stage's footprint.
#include <sys/resource.h>

namespace chladni::precompute {

/// Starts a stage: resets the high-water mark. False where the kernel does not allow it; the
/// stage's peak is then unknown (peak_memory_bytes returns 0).
bool reset_peak_memory();
/// The stage's peak since reset_peak_memory (bytes), children noted since included; 0: unknown.
double peak_memory_bytes();
/// The largest resident memory seen by any stage of this process so far (bytes): the resets
/// lower getrusage's ru_maxrss, which reports only the mark since the last one.
double process_peak_bytes();
/// A child waited for with wait4: its ru_maxrss counts toward the running stage's peak.
void note_child_peak(const rusage& child);

}  // namespace chladni::precompute
