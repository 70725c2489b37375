// Peak resident memory per precompute stage: a stage sees what it allocated, the next one does
// not, and a child's peak counts toward the stage that waited for it.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <vector>

#include "../precompute/src/peak_memory.hpp"

using namespace chladni::precompute;

namespace {

constexpr std::size_t kBlock = 256u << 20;

// The sanitizers' allocators hold freed blocks in quarantine instead of unmapping them.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kPagesReturned = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool kPagesReturned = false;
#else
constexpr bool kPagesReturned = true;
#endif
#else
constexpr bool kPagesReturned = true;
#endif

// Allocates and touches kBlock bytes, then frees them (a block this large is mapped, and its
// pages go back to the kernel on free).
void touch_block() {
  std::vector<char> v(kBlock);
  std::memset(v.data(), 1, v.size());
  asm volatile("" : : "r"(v.data()) : "memory");
}

}  // namespace

TEST(PeakMemory, AStageSeesWhatItAllocatedAndTheNextStageDoesNot) {
  if (!kPagesReturned) GTEST_SKIP() << "a sanitizer's allocator keeps freed pages";
  if (!reset_peak_memory()) GTEST_SKIP() << "the kernel does not let a process reset VmHWM";
  const double before = peak_memory_bytes();
  touch_block();
  const double first = peak_memory_bytes();
  EXPECT_GE(first, before + 0.9 * double(kBlock));
  ASSERT_TRUE(reset_peak_memory());
  const double second = peak_memory_bytes();
  EXPECT_LT(second, first - 0.8 * double(kBlock));
  // The process's peak remembers what the reset forgot.
  EXPECT_GE(process_peak_bytes(), first);
}

TEST(PeakMemory, AChildWaitedForCountsTowardTheStage) {
  if (!reset_peak_memory()) GTEST_SKIP() << "the kernel does not let a process reset VmHWM";
  const double own = peak_memory_bytes();
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    touch_block();
    _exit(0);
  }
  int status = 0;
  rusage usage{};
  ASSERT_EQ(wait4(pid, &status, 0, &usage), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_LT(peak_memory_bytes(), own + 0.5 * double(kBlock));  // not yet noted
  note_child_peak(usage);
  EXPECT_GE(peak_memory_bytes(), 0.9 * double(kBlock));
  // A new stage starts without it.
  ASSERT_TRUE(reset_peak_memory());
  EXPECT_LT(peak_memory_bytes(), own + 0.5 * double(kBlock));
}
