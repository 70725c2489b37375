#!/usr/bin/env bash
# Local against uniform refinement on a thin fin (docs/validation.md, "A thin fin"): an L-section
# steel prism, a 40 x 40 mm block with a 4 mm fin reaching 120 mm, 40 mm deep; its first 6
# modes at the default tolerance, each way, and locally at 0.3 %. One table row per run.
# Usage: bash bench/refinement_bench.sh [path/to/chladni]   (default: build/release/cli/chladni)
set -euo pipefail
cd "$(dirname "$0")/.."
chladni=${1:-build/release/cli/chladni}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
{
  printf 'v %s\n' "0 0 0" "0.04 0 0" "0.12 0 0" "0.12 0 0.004" "0.04 0 0.004" "0.04 0 0.04" \
    "0 0 0.04" "0 0.04 0" "0.04 0.04 0" "0.12 0.04 0" "0.12 0.04 0.004" "0.04 0.04 0.004" \
    "0.04 0.04 0.04" "0 0.04 0.04"
  printf 'f %s\n' "1 2 5" "8 12 9" "1 5 6" "8 13 12" "1 6 7" "8 14 13" "2 3 4" "9 11 10" \
    "2 4 5" "9 12 11" "1 9 2" "1 8 9" "2 10 3" "2 9 10" "3 11 4" "3 10 11" "4 12 5" "4 11 12" \
    "5 13 6" "5 12 13" "6 14 7" "6 13 14" "7 8 1" "7 14 8"
} >"$out/fin.obj"

echo "| refinement | meshes | tetrahedra | DOFs | worst estimate | f1 (Hz) | radius-edge max | min dihedral | time (s) |"
echo "|---|---|---|---|---|---|---|---|---|"
for run in "local" "uniform" "local --tolerance 0.003"; do
  # shellcheck disable=SC2086
  "$chladni" precompute "$out/fin.obj" --max-modes 6 --no-transfer -q --refinement $run \
    -o "$out/fin.chbank" --json "$out/s.json"
  python3 - "$run" "$out/s.json" <<'PY'
import json, sys
run, path = sys.argv[1], sys.argv[2]
j = json.load(open(path))
v, a = j["volume_mesh"], j["accuracy"]
print(f"| {run} | {len(a['meshes'])} | {v['tetrahedra']} | {v['dofs']} "
      f"| {100 * a['meshes'][-1]['worst_error']:.2f} % | {j['frequencies_hz'][0]:.1f} "
      f"| {v['max_radius_edge']:.2f} | {v['min_dihedral_deg']:.1f} | {j['total_seconds']:.1f} |")
PY
done
