#!/usr/bin/env bash
# The main job: install dependencies, build Chladni, and render the demo sound to out/.
# Usage: bash scripts/demo.sh            (from the repository root, as root on Debian 12)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
jobs=$(nproc)
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DCHLADNI_BUILD_TESTS=OFF \
  -DCHLADNI_BUILD_BENCH=OFF
cmake --build build/release --target chladni -j "$jobs"
mkdir -p out
# Analytic struck steel bar (Euler-Bernoulli modes) until the precompute pipeline lands.
./build/release/cli/chladni demo -o out/struck_bar.wav
./build/release/cli/chladni render examples/two_bars.json -o out/two_bars.wav
echo "demo: wrote out/struck_bar.wav and out/two_bars.wav"
