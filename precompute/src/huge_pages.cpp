#include "huge_pages.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>

#if defined(__linux__)
#include <sys/mman.h>
#endif
#ifdef CHLADNI_HAVE_CHOLMOD
#include <SuiteSparse_config.h>
#endif

namespace chladni::precompute {
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kWorthIt = 2 * kHugePage;

// CHLADNI_HUGE_PAGES=0 opts out: where THP's defrag setting makes faults on advised memory
// compact memory synchronously, a fragmented machine could stall on them instead.
bool wanted() {
  static const bool on = [] {
    const char* v = std::getenv("CHLADNI_HUGE_PAGES");
    return !(v && std::strcmp(v, "0") == 0);
  }();
  return on;
}

#ifdef CHLADNI_HAVE_CHOLMOD
void* huge_malloc(std::size_t bytes) {
  void* p = std::malloc(bytes);
  if (p && bytes >= kWorthIt) advise_huge_pages(p, bytes);
  return p;
}

// calloc would zero (and so fault in) the block before it could be advised.
void* huge_calloc(std::size_t count, std::size_t size) {
  if (size != 0 && count > SIZE_MAX / size) return nullptr;
  const std::size_t bytes = count * size;
  if (bytes < kWorthIt) return std::calloc(count, size);
  void* p = huge_malloc(bytes);
  if (p) std::memset(p, 0, bytes);
  return p;
}

void* huge_realloc(void* old, std::size_t bytes) {
  void* p = std::realloc(old, bytes);
  if (p && bytes >= kWorthIt) advise_huge_pages(p, bytes);
  return p;
}
#endif

}  // namespace

void advise_huge_pages(void* p, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (!p || bytes < kWorthIt || !wanted()) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t last = (begin + bytes) & ~(kHugePage - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

void use_huge_pages_in_suitesparse() {
#ifdef CHLADNI_HAVE_CHOLMOD
  static std::once_flag once;
  std::call_once(once, [] {
    SuiteSparse_config.malloc_func = huge_malloc;
    SuiteSparse_config.calloc_func = huge_calloc;
    SuiteSparse_config.realloc_func = huge_realloc;
    SuiteSparse_config.free_func = [](void* p) { std::free(p); };
  });
#endif
}

}  // namespace chladni::precompute
