#!/usr/bin/env bash
# Installs every Debian package Chladni needs to build, test and run, skipping what is present.
# Idempotent; needs root (or sudo) on Debian 12.   Usage: bash scripts/deps.sh [tests]
set -euo pipefail

# jackd2 (the JACK server `chladni play` is tested against) and libjack-jackd2-dev: named so that
# apt satisfies libstk-dev's JACK dependency with JACK 2 instead of JACK 1, which conflicts with
# the server.
PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers glslang-tools
  libeigen3-dev nlohmann-json3-dev libcli11-dev libsndfile1-dev
  libxxhash-dev openmpi-bin libopenmpi-dev
  libgtest-dev libgmock-dev libbenchmark-dev libstk-dev
  zlib1g-dev libfftw3-dev libkissfft-dev libnlopt-dev libcairo2-dev fonts-dejavu-core libpng-dev libspectra-dev libtet1.5-dev libcgal-dev libsuitesparse-dev libopenblas-dev
  libhmat-oss-dev
  librtaudio-dev libjack-jackd2-dev jackd2 libbullet-dev libsdl2-dev
  clang-format clang libclang-rt-14-dev llvm
  time  # /usr/bin/time: peak memory in bench/no_options_bench.sh
)
# `deps.sh tests` adds what only the tests need: Chromium, for the browser tests of the HTML
# report (driven over the DevTools pipe; its WebGL runs on SwiftShader, no GPU needed), and a
# virtual X server for the windowed renderer example (xvfb-run needs xauth).
if [[ "${1:-}" == "tests" ]]; then
  PACKAGES+=(chromium xvfb xauth)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
  echo "deps: installing ${missing[*]}"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "deps: all ${#PACKAGES[@]} packages present"
fi
