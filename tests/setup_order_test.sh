#!/usr/bin/env bash
# The README's two commands in either order: configuring a folder the demo's way and then the
# tests' way must give a folder with the whole suite (and ctest must refuse an empty one).
set -euo pipefail
# The sanitizer run preloads libasan into every process; CMake and the compiler are not ours.
unset LD_PRELOAD ASAN_OPTIONS LSAN_OPTIONS UBSAN_OPTIONS
src=$1 dir=$2
rm -rf "$dir"
bash "$src/scripts/configure.sh" demo "$dir" >/dev/null
bash "$src/scripts/configure.sh" tests "$dir" >/dev/null
grep -q '^CHLADNI_BUILD_TESTS:BOOL=ON$' "$dir/CMakeCache.txt"
grep -q '^CHLADNI_BUILD_BENCH:BOOL=ON$' "$dir/CMakeCache.txt"
# Without a build only the tests ctest knows before gtest discovery are listed; there must be some.
count=$(ctest --test-dir "$dir" -N | sed -n 's/^Total Tests: //p')
[[ ${count:-0} -gt 0 ]]
grep -q -- '--no-tests=error' "$src/scripts/test.sh"
grep -q 'configure.sh tests build/release' "$src/scripts/test.sh"
grep -q 'configure.sh demo build/release' "$src/scripts/demo.sh"
rm -rf "$dir"
echo "demo then tests: $count tests configured before building"
