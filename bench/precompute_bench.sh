#!/usr/bin/env bash
# Precompute speed on the bundled meshes (docs/PERFORMANCE.md, "Precompute"). Each case runs
# `chladni precompute --json --no-transfer` (the modes only; transfer has its own benchmarks) and
# one table row is printed from its summary.
# Usage: bash bench/precompute_bench.sh [path/to/chladni]     (default: build/cli/chladni)
set -euo pipefail
cd "$(dirname "$0")/.."
chladni=${1:-build/cli/chladni}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

row() {  # name, then the precompute arguments
  local name=$1
  shift
  "$chladni" precompute "$@" -o "$out/bank.chbank" --json "$out/s.json" -q --no-transfer
  python3 - "$name" "$out/s.json" <<'PY'
import json, sys
name, path = sys.argv[1], sys.argv[2]
j = json.load(open(path))
v, e, s = j["volume_mesh"], j["eigen"], j["seconds"]
f = j["frequencies_hz"]
g = lambda k: s.get(k, 0.0)
err = j["frequency_error_estimate"]
meshes = len(j["accuracy"]["meshes"])
print(f"| {name} | P{v['element_order']} | {v['tetrahedra']} | {v['dofs']} | {j['modes']['kept']} "
      f"| {f[0]:.1f} | {meshes} | {g('tetrahedralize'):.2f} | {g('assemble'):.2f} "
      f"| {g('eigen-solve'):.2f} | {g('error estimate'):.2f} | {j['total_seconds']:.2f} "
      f"| {j['peak_rss_mb']:.0f} | {100 * max(err[:20]):.2f} % |")
PY
}

echo "| case | order | tets (last mesh) | DOFs | modes | f1 (Hz) | meshes solved | TetGen (s) | assembly (s) | eigen-solve (s) | error estimate (s) | total (s) | peak RSS (MB) | estimated error, first 20 |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
row "bar.obj, defaults (steel, all modes < 20 kHz)" meshes/bar.obj
row "bar.obj, 100 modes" meshes/bar.obj --max-modes 100
row "spot.obj x0.1, 100 modes, defaults" meshes/spot.obj --scale 0.1 --max-modes 100
row "spot.obj as is (1.7 m), 100 modes, --max-freq 5000" meshes/spot.obj --max-modes 100 --max-freq 5000
row "spot.obj as is (1.7 m), 100 modes, defaults" meshes/spot.obj --max-modes 100
row "bell.obj brass, 100 modes" meshes/bell.obj --material brass --max-modes 100
row "bowl.obj brass, defaults" meshes/bowl.obj --material brass
row "spot.obj x0.1, 20k tets, P1, 100 modes" meshes/spot.obj --scale 0.1 --order 1 --max-tet-volume 2e-7 --max-modes 100
row "spot.obj x0.1, meshed for P2 (auto, 20 kHz), 100 modes" meshes/spot.obj --scale 0.1 --order 2 --max-modes 100
row "spot.obj x0.1, the same 20k tets, P2, 100 modes" meshes/spot.obj --scale 0.1 --order 2 --max-tet-volume 2e-7 --max-modes 100
row "spot.obj x0.1, 200k tets, P1, 100 modes" meshes/spot.obj --scale 0.1 --order 1 --max-tet-volume 5e-9 --max-modes 100
