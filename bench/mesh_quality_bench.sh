#!/usr/bin/env bash
# The volume meshes precompute makes at defaults (steel, --no-transfer, MODES modes, default 20):
# per bundled mesh, the first mesh and the last (tetrahedra, estimate), the shape of the last
# (mean radius-edge ratio, dihedral angles), the meshes solved, time and peak memory
# (docs/PERFORMANCE.md, "Quality tetrahedra"). A run that fails prints its error as the row.
# Usage: [MODES=N] bash bench/mesh_quality_bench.sh [path/to/chladni] [mesh names...]
# shellcheck source=bench/bundled_meshes.sh
source "$(dirname "$0")/bundled_meshes.sh"
modes=${MODES:-20}

echo "| mesh | modes | first mesh: tets, estimate | meshes solved | last mesh: tets | mean radius-edge | dihedral angles | worst estimate | time (s) | peak RSS (MB) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for name in "${names[@]}"; do
  if ! "$chladni" precompute "meshes/$name.obj" --material steel --max-modes "$modes" --no-transfer \
    -q -o "$out/d.chbank" --json "$out/d.json" 2>"$out/d.err"; then
    echo "| $name | failed: $(tail -n 1 "$out/d.err") |"
    continue
  fi
  python3 - "$name" "$out/d.json" <<'PY'
import json, sys
name, d = sys.argv[1], json.load(open(sys.argv[2]))
m, v = d["accuracy"]["meshes"], d["volume_mesh"]
print(f"| {name} | {d['modes']['kept']} | {m[0]['tetrahedra']}, {100 * m[0]['worst_error']:.2g} % | {len(m)} "
      f"| {v['tetrahedra']} | {v['mean_radius_edge']:.2f} | {v['min_dihedral_deg']:.1f}-{v['max_dihedral_deg']:.1f} deg "
      f"| {100 * m[-1]['worst_error']:.2f} % | {d['total_seconds']:.1f} | {d['peak_rss_mb']:.0f} |", flush=True)
PY
done
