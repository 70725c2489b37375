#!/usr/bin/env bash
# What the figures and the report cost: best wall time of 3 runs of each command with and
# without its figure (the difference is the figure), and the report's size.
# Usage: bash bench/figures_bench.sh [BANK] [path/to/chladni]
#   BANK: default out/bowl.chbank (the demo's), else the bar precomputed here without transfer.
set -euo pipefail
cd "$(dirname "$0")/.."
chladni=${2:-build/release/cli/chladni}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
bank=${1:-out/bowl.chbank}
if [[ ! -f "$bank" ]]; then
  bank=$out/bar.chbank
  "$chladni" precompute meshes/bar.obj -o "$bank" --no-transfer -q
fi
best() {  # best of 3 wall times of "$@", in seconds
  local b=1e9 t0
  for _ in 1 2 3; do
    t0=$(date +%s.%N)
    "$@" >/dev/null 2>&1
    b=$(awk -v a="$t0" -v c="$(date +%s.%N)" -v m="$b" 'BEGIN { t = c - a; print (t < m ? t : m) }')
  done
  echo "$b"
}
row() {  # name, time without, time with
  awk -v n="$1" -v a="$2" -v b="$3" 'BEGIN { printf "| %s | %.3f | %.3f | %.3f |\n", n, a, b, b - a }'
}
echo "bank: $bank"
echo
echo "| command | without (s) | with the figure (s) | the figure (s) |"
echo "|---|---|---|---|"
scene=examples/bowl_and_bar.json
row "render $scene (8 s) --spectrogram" \
  "$(best "$chladni" render "$scene" -o "$out/r.wav")" \
  "$(best "$chladni" render "$scene" -o "$out/r.wav" --spectrogram "$out/r.png")"
row "shake tambourine --duration 30 --spectrogram" \
  "$(best "$chladni" shake tambourine -o "$out/s.wav" --duration 30)" \
  "$(best "$chladni" shake tambourine -o "$out/s.wav" --duration 30 --spectrogram "$out/s.png")"
row "info BANK --plot" \
  "$(best "$chladni" info "$bank")" \
  "$(best "$chladni" info "$bank" --plot "$out/i.png")"
row "report BANK (against info)" \
  "$(best "$chladni" info "$bank")" \
  "$(best "$chladni" report "$bank" -o "$out/report")"
echo
"$chladni" report "$bank" -o "$out/report" | head -n 1
du -sh "$out/report" | awk '{ print "report folder: " $1 }'
