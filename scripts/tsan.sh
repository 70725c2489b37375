#!/usr/bin/env bash
# The multi-threaded tests (tests/test_threads.cpp: the C API's game and audio threads, the CPU
# filterbank's workers, the shakers' excitation threads) under ThreadSanitizer, which fails them
# on any data race. Builds only that target and what it links (core, gpu, runtime, capi).
# Usage: bash scripts/tsan.sh [DIR]   (default build/tsan; deps.sh first)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build/tsan}
bash scripts/configure.sh tsan "$dir"
cmake --build "$dir" -j "$(nproc)" --target chladni_thread_tests
# halt_on_error: the first race fails the run, with both stacks.
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" "$dir/tests/chladni_thread_tests"
