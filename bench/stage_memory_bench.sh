#!/usr/bin/env bash
# Time and peak resident memory per precompute stage at defaults (steel, --no-transfer, MODES
# modes, default 20), per bundled mesh, from --json's "seconds" and "peak_memory_mb"
# (docs/PERFORMANCE.md, "Memory per stage"). A run that fails prints its error as the row.
# Usage: [MODES=N] bash bench/stage_memory_bench.sh [path/to/chladni] [mesh names...]
# shellcheck source=bench/bundled_meshes.sh
source "$(dirname "$0")/bundled_meshes.sh"
modes=${MODES:-20}

stages=("tetrahedralize" "assemble" "eigen-solve" "error estimate")
header="| mesh | meshes | last mesh: DOFs, factor (MB) |"
for s in "${stages[@]}"; do header+=" $s: s, peak MB |"; done
echo "$header total s | peak MB |"
echo "|---|---|---|---|---|---|---|---|---|"
for name in "${names[@]}"; do
  if ! "$chladni" precompute "meshes/$name.obj" --material steel --max-modes "$modes" --no-transfer \
    -q -o "$out/d.chbank" --json "$out/d.json" 2>"$out/d.err"; then
    echo "| $name | failed: $(tail -n 1 "$out/d.err") |"
    continue
  fi
  python3 - "$name" "$out/d.json" "${stages[@]}" <<'PY'
import json, sys
name, d, stages = sys.argv[1], json.load(open(sys.argv[2])), sys.argv[3:]
row = f"| {name} | {len(d['accuracy']['meshes'])} | {d['volume_mesh']['dofs']}, {d['eigen']['factor_bytes'] / 2**20:.0f} |"
peaks = d.get("peak_memory_mb", {})
for s in stages:
    row += f" {d['seconds'].get(s, 0):.1f}, {peaks.get(s, float('nan')):.0f} |"
print(row + f" {d['total_seconds']:.1f} | {d['peak_rss_mb']:.0f} |", flush=True)
PY
done
