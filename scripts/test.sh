#!/usr/bin/env bash
# Installs dependencies, builds Chladni twice (optimised, and Debug with AddressSanitizer +
# UndefinedBehaviorSanitizer + Vulkan validation layers) and runs the whole test suite in each,
# runs the multi-threaded tests under ThreadSanitizer (scripts/tsan.sh), then fuzzes every file
# reader for a bounded time (scripts/fuzz.sh, clang + libFuzzer).
# The GPU tests run on whatever Vulkan device is present; in CI that is Mesa lavapipe.
# Usage: bash scripts/test.sh            (from the repository root, as root on Debian 12)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh tests
jobs=$(nproc)

echo "== release build and tests"
# configure.sh names tests and benchmarks explicitly: the demo configures the same folder without
# them, and a cached OFF must not turn this into a run of no tests (--no-tests=error).
bash scripts/configure.sh tests build/release
cmake --build build/release -j "$jobs"
ctest --test-dir build/release --output-on-failure --no-tests=error -j "$jobs"

echo "== sanitizer build (ASan + UBSan, Debug, Vulkan validation) and tests"
# The CGAL units are built optimised and uninstrumented in both builds: this one links the
# release build's (precompute/CMakeLists.txt, CHLADNI_PREBUILT_CGAL_UNITS).
bash scripts/configure.sh asan build/asan -DCHLADNI_PREBUILT_CGAL_UNITS="$PWD/build/release"
cmake --build build/asan -j "$jobs"
# Lavapipe leaks a little per VkInstance and is dlclose'd before LeakSanitizer reports, which
# leaves the leak unattributable; preloading it (after libasan, which must come first) keeps it
# mapped so tests/lsan.supp can name it. Leak checking stays on for everything of ours.
# Twenty tests that take 20-190 s each under the sanitizers run in the release stage only: their
# code (FEM, the Lanczos solver, the error estimate, local and uniform refinement, BEM with
# GMRES, radiate, the alpha wrap retried with a wider ball, the thin spheroid's BEM and wave
# solves, the wave solve's sphere harmonics and convergence, precompute at extreme scales) runs
# under the sanitizers in smaller tests too (all but the retry of a refinement step over the
# memory budget, plain control flow), and keeping them here would push CI past its 30 minutes.
heavy='^(ModalFem\.(SteelBarMatchesTimoshenkoWithinOnePercent|MaxModesMeshesForTheModesAskedFor)|'
heavy+='CliRadiate\.SphereHarmonicMatchesTheExactSolution|'
heavy+='ModeError\.(BracketsTheBarsErrorAndRefinementMeetsTheTolerance|'
heavy+='LocalRefinementMeetsTheToleranceOnAThinFin|RefinementOverTheBudgetTakesASmallerStep)|'
heavy+='BemAssets\.BowlLowestModesByBemAndAudibleAtTheirPredictedLevel|ThinRadiator\..*|'
heavy+='BemThinBody\.RigidOblateSpheroidRadiatesLambsDipole|'
heavy+='WaveTransfer\.(SphereHarmonicsAtKa30|SphereHarmonicsMatchTheExactField|ErrorHalvesAsTheCellsHalve|'
heavy+='TangentialMotionRadiatesNothing)|'
heavy+='ThinBody\.(PoorlyShapedFirstMeshIsReplacedByAQualityMesh|ThinWalledBowlIsRefinedByBisectionWhereThatIsSmaller)|'
heavy+='CliHostile\.(TinySolidsGetTheirModesOrAClearRefusal|HugeSolidsKeepTheModesAskedForOrAreRefusedNamingTheUnit)|'
heavy+='RepairLadder\.(SelfIntersectingSoupBecomesASolidOrIsRefused|WrappedBarRingsLikeTheCleanBar))$'
preload=""
lvp=$(ls /usr/lib/*/libvulkan_lvp.so 2>/dev/null | head -n 1 || true)
if [[ -n "$lvp" ]]; then preload="$(gcc -print-file-name=libasan.so) $lvp"; fi
LD_PRELOAD="$preload" \
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build/asan --output-on-failure --no-tests=error -j "$jobs" -E "$heavy"

echo "== ThreadSanitizer: the multi-threaded tests (scripts/tsan.sh)"
bash scripts/tsan.sh build/tsan

echo "== fuzzing every reader for ${CHLADNI_FUZZ_SECONDS:-10} s each (scripts/fuzz.sh)"
bash scripts/fuzz.sh "${CHLADNI_FUZZ_SECONDS:-10}"
