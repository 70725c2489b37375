#!/usr/bin/env bash
# The example host: builds Chladni, installs it into build/prefix, builds
# examples/falling-objects against the installed package, and runs it: Bullet drops objects onto
# a floor and into each other, their contacts strike them through the C API, and the audio and a
# frame-by-frame event log go to out/falling_objects.wav and out/falling_objects.csv. It uses the
# demo's soundbanks (out/bar.chbank, out/bowl.chbank) when they are there, else inline modes.
# Usage: bash scripts/falling_objects.sh [--seconds S]   (from the repository root, as root)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
if [[ ! -f build/release/build.ninja ]]; then bash scripts/configure.sh demo build/release; fi
cmake --build build/release --target chladni chladni_capi -j "$(nproc)"
cmake --install build/release --prefix build/prefix > /dev/null
cmake -S examples/falling-objects -B build/falling -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$PWD/build/prefix" > /dev/null
cmake --build build/falling
mkdir -p out
banks=()
for b in out/bar.chbank out/bowl.chbank; do [[ -f $b ]] && banks+=("$b"); done
build/falling/falling_objects "${banks[@]}" "$@" -o out/falling_objects.wav \
  --log out/falling_objects.csv
