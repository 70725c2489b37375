#!/usr/bin/env bash
# The main job: install dependencies, build Chladni, precompute soundbanks for two bundled meshes
# and render a scene that strikes them, two paper animations and two particle sounds, to out/,
# with a labelled spectrogram of each sound and an HTML report of the bowl.
# Usage: bash scripts/demo.sh            (from the repository root, as root on Debian 12)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
jobs=$(nproc)
bash scripts/configure.sh demo build/release
cmake --build build/release --target chladni -j "$jobs"
chladni=./build/release/cli/chladni
mkdir -p out
# Mesh -> checked surface -> TetGen -> quadratic FEM -> modes below 20 kHz -> damping -> soundbank.
$chladni precompute meshes/bar.obj -o out/bar.chbank --material steel --json out/bar.json
$chladni precompute meshes/bowl.obj -o out/bowl.chbank --material brass --json out/bowl.json
$chladni info out/bowl.chbank --plot out/bowl_info.png > out/bowl_info.txt
head -n 24 out/bowl_info.txt
# The bowl as an HTML report: mode table, 3-D mode shapes, directivity, click-to-strike audio.
$chladni report out/bowl.chbank -o out/bowl_report
# The bowl struck on its rim twice and the bar at an end and at its centre, on the CPU reference
# and on the GPU filterbank (Vulkan; Mesa lavapipe when there is no GPU).
$chladni render examples/bowl_and_bar.json -o out/bowl_and_bar.wav --normalize -1 \
  --spectrogram out/bowl_and_bar.png
$chladni render examples/bowl_and_bar.json -o out/bowl_and_bar_gpu.wav --normalize -1 \
  --backend gpu --block 1024 --spectrogram out/bowl_and_bar_gpu.png
# The analytic-bar example of the runtime (no precompute).
$chladni render examples/struck_bar.json -o out/struck_bar.wav --normalize -1 \
  --spectrogram out/struck_bar.png
# Paper sound: a sheet slid on a table and curled (database mode, default database generated in
# memory) and a crumpled sheet as modal voices on the GPU filterbank, with spectrograms.
$chladni paper meshes/paper/slide.json -o out/paper_slide.wav --spectrogram out/paper_slide.png
$chladni paper meshes/paper/crumple.json -o out/paper_crumple.wav --paper-mode both --backend gpu \
  --spectrogram out/paper_crumple.png
# Particle sounds (PhISEM): a tambourine on the GPU (excitation and filterbank), gravel and coins
# poured into the precomputed bowl beside a maraca (a scene with shake events).
$chladni shake tambourine -o out/tambourine.wav --duration 3 --shakes-per-second 5 --backend gpu \
  --normalize -1 --spectrogram out/tambourine.png
$chladni render examples/gravel_in_bowl.json -o out/gravel_in_bowl.wav --normalize -1 \
  --spectrogram out/gravel_in_bowl.png
# Continuous contact: the bar dragged across the bowl's rim, then a ball rolling inside it.
$chladni render examples/scrape_and_roll.json -o out/scrape_and_roll.wav --normalize -1 \
  --spectrogram out/scrape_and_roll.png
# Estimation: a recorded glockenspiel note's partials and the damping curve through them (the
# steel preset's), its resynthesis, and the spectrograms with the curve.
$chladni estimate recordings/glockenspiel_C6.wav --end 0.798 --json out/glockenspiel.json \
  --resynth out/glockenspiel_resynth.wav --plot out/glockenspiel.png
echo "demo: wrote out/bowl_and_bar.wav, out/bowl_and_bar_gpu.wav, out/struck_bar.wav," \
  "out/paper_slide.wav, out/paper_crumple.wav, out/tambourine.wav, out/gravel_in_bowl.wav," \
  "out/scrape_and_roll.wav and" \
  "out/glockenspiel_resynth.wav, each with its labelled spectrogram (.png beside it);" \
  "out/bowl_info.png and the bowl's HTML report, out/bowl_report/index.html"
