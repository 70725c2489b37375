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
# A struck steel bar (analytic Euler-Bernoulli modes, until the precompute pipeline lands) and a
# glass, rendered on the CPU reference and on the GPU filterbank (Vulkan; lavapipe without a GPU).
./build/release/cli/chladni render examples/struck_bar.json -o out/struck_bar.wav --normalize -1
./build/release/cli/chladni render examples/struck_bar.json -o out/struck_bar_gpu.wav --normalize -1 \
  --backend gpu --block 1024
echo "demo: wrote out/struck_bar.wav and out/struck_bar_gpu.wav"
