#!/usr/bin/env bash
# examples/renderer headless: a virtual X server (xvfb-run) for its Vulkan window, SDL's dummy
# audio driver for its sound, 3.5 s of falling bodies. The program checks itself (a frame read
# back from the swapchain shows the bodies; every logged impact sounds within one audio block of
# being posted, and each body's first landing starts a sound there) and exits 0 when both hold.
# Usage: renderer_test.sh RENDERER
set -euo pipefail
renderer=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
SDL_AUDIODRIVER=dummy SDL_VIDEODRIVER=x11 xvfb-run -a -s "-screen 0 800x600x24" \
  "$renderer" --frame frame.ppm --wav out.wav --log impacts.csv | tee out.txt
grep -q '^runtime: gpu' out.txt  # on the window's device, not a CPU fallback
[ -s frame.ppm ] && [ -s out.wav ] && [ "$(wc -l < impacts.csv)" -gt 5 ]
