#!/usr/bin/env bash
# How each build folder is configured, in one place: demo.sh and test.sh both come here and name
# every option they rely on, so whichever of them runs first, the other still gets its build
# (the demo turning tests off must not leave test.sh with a folder of no tests).
#   bash scripts/configure.sh demo|tests|asan|tsan DIR [MORE CMAKE OPTIONS...]
set -euo pipefail
cd "$(dirname "$0")/.."
kind=$1 dir=$2
shift 2
case "$kind" in
  demo)
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCHLADNI_BUILD_TESTS=OFF \
      -DCHLADNI_BUILD_BENCH=OFF "$@" ;;
  tests)
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCHLADNI_BUILD_TESTS=ON \
      -DCHLADNI_BUILD_BENCH=ON "$@" ;;
  # The sanitizer builds carry line tables only (-g1): their reports name file and line, and the
  # full debug information of CGAL's and Eigen's templates cost a third of their compile time.
  asan)
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCHLADNI_SANITIZE=ON \
      -DCHLADNI_BUILD_TESTS=ON -DCHLADNI_BUILD_BENCH=OFF "-DCMAKE_CXX_FLAGS_DEBUG=-g1 -O1" "$@" ;;
  tsan)
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCHLADNI_TSAN=ON \
      -DCHLADNI_BUILD_TESTS=ON -DCHLADNI_BUILD_BENCH=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-g1 -O1" "$@" ;;
  *)
    echo "usage: configure.sh demo|tests|asan|tsan DIR" >&2
    exit 2 ;;
esac
