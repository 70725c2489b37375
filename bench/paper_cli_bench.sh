#!/usr/bin/env bash
# `chladni paper` end to end on the shipped animations with the default database: the first run
# generates it and caches it (in a fresh cache folder), every later run reads the snapshot.
# Prints one table row per animation: audio length, best wall time of 3 runs, x real time.
# Usage: bash bench/paper_cli_bench.sh [path/to/chladni]   (default: build/release/cli/chladni)
set -euo pipefail
cd "$(dirname "$0")/.."
chladni=${1:-build/release/cli/chladni}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
export CHLADNI_CACHE_DIR=$out/cache
start=$(date +%s.%N)
"$chladni" paper meshes/paper/slide.json -o "$out/first.wav" | head -n 1
echo "first run (generates and caches the database): $(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }') s"
echo
echo "| animation | audio (s) | best of 3 (s) | x real time |"
echo "|---|---|---|---|"
for name in slide crumple flap shake; do
  best=1e9
  for _ in 1 2 3; do
    t0=$(date +%s.%N)
    line=$("$chladni" paper "meshes/paper/$name.json" -o "$out/$name.wav" | grep '^wrote')
    best=$(awk -v a="$t0" -v b="$(date +%s.%N)" -v m="$best" 'BEGIN { t = b - a; print (t < m ? t : m) }')
  done
  audio=$(echo "$line" | sed -E 's/.*: ([0-9.]+) s .*/\1/')
  awk -v n="$name" -v a="$audio" -v t="$best" 'BEGIN { printf "| %s | %s | %.3f | %.0f |\n", n, a, t, a / t }'
done
