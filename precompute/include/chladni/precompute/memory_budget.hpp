#pragma once
// The memory the precompute's large solves (CHOLMOD's factor, the BEM system) may take by default.

namespace chladni::precompute {

/// The default memory budget: 80 % of the memory available now (Linux /proc/meminfo), else of
/// the physical memory.
double default_memory_budget();

}  // namespace chladni::precompute
