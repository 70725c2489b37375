#pragma once
// Transparent huge pages for the precompute's large buffers (the factor, the Lanczos basis, the
// assembled matrices). Each 4 KB page of a fresh allocation costs a page fault on first touch; on
// virtual machines a fault costs microseconds, and spot.obj's eigen-solve faulted 1.2 GB in
// 310,000 of them. Where THP is in "madvise" mode (/sys/kernel/mm/transparent_hugepage/enabled,
// as on this project's machines), asking for huge pages cuts that 512-fold; where it is "always"
// or "never", or off Linux, it changes nothing.
#include <cstddef>

namespace chladni::precompute {

/// Advise the kernel to back the 2 MB-aligned part of [p, p + bytes) with huge pages, before it
/// is first touched. Small ranges, systems without THP and CHLADNI_HUGE_PAGES=0 leave it alone;
/// never fails.
void advise_huge_pages(void* p, std::size_t bytes);

/// The same for a dense matrix's (or a sized vector's) elements.
template <class Dense>
void advise_huge_pages(Dense& m) {
  advise_huge_pages(m.data(), sizeof(*m.data()) * std::size_t(m.size()));
}

/// Route SuiteSparse's (CHOLMOD's) allocations of 4 MB and more through advise_huge_pages.
/// Idempotent and thread-safe; call before the first CHOLMOD call.
void use_huge_pages_in_suitesparse();

}  // namespace chladni::precompute
