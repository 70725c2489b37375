#!/usr/bin/env bash
# `chladni precompute MESH --repair --max-modes 20` on meshes nobody tuned for, each scaled so
# that its bounding-box diagonal is SIZE metres: per mesh the exit status, wall seconds, peak
# memory, the repair's rung, distance and volume change, and the lowest mode, or the one-line
# reason it was refused. Extra precompute options follow `--` (e.g. -- --no-transfer).
# Usage: bash bench/repair_models.sh [path/to/chladni] SIZE MESH.obj... [-- OPTIONS...]
set -uo pipefail
cd "$(dirname "$0")/.."
chladni=$1 size=$2
shift 2
meshes=()
while (($#)) && [[ $1 != -- ]]; do meshes+=("$1"); shift; done
[[ ${1:-} == -- ]] && shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

echo "| mesh | exit | seconds | peak RSS (GB) | rung | moved (% of size) | volume change | lowest mode (Hz) | reason |"
echo "|---|---|---|---|---|---|---|---|---|"
for mesh in "${meshes[@]}"; do
  # The scale that makes the diagonal SIZE, from the OBJ's vertex lines.
  scale=$(awk -v s="$size" '$1 == "v" { for (k = 2; k <= 4; ++k) { if (n == 0 || $k < lo[k]) lo[k] = $k;
          if (n == 0 || $k > hi[k]) hi[k] = $k } n = 1 }
          END { d = 0; for (k = 2; k <= 4; ++k) d += (hi[k] - lo[k]) ^ 2; print s / sqrt(d) }' "$mesh")
  /usr/bin/time -o "$out/time" -f "%e %M" "$chladni" precompute "$mesh" --repair --max-modes 20 \
    --scale "$scale" -q -o "$out/m.chbank" --json "$out/m.json" "$@" > "$out/log" 2>&1
  status=$?
  read -r seconds kb < <(tail -n 1 "$out/time")
  /usr/bin/python3 - "$mesh" "$status" "$seconds" "$kb" "$out/m.json" "$out/log" <<'PY'
import json, os, sys
mesh, status, seconds, kb, path, log = sys.argv[1:7]
name = os.path.basename(mesh)
row = [name, status, seconds, f"{int(kb) / 1048576:.2f}"]
if status == "0":
    j = json.load(open(path))
    r = j.get("repair") or {}
    moved = 100 * r.get("input_to_repaired_m", 0) / r["size_m"] if r.get("size_m") else 0
    row += [r.get("rung", "none"), f"{moved:.2f}", f"{100 * r.get('volume_change', 0):+.2f} %",
            f"{j['frequencies_hz'][0]:.1f}" if j["frequencies_hz"] else "-", ""]
else:
    lines = [l for l in open(log).read().splitlines() if l.strip()]
    reason = next((l for l in lines if "error" in l or ":" in l), lines[-1] if lines else "")
    row += ["", "", "", "", reason.replace("|", "/")[:200]]
print("| " + " | ".join(row) + " |")
PY
  rm -f "$out/m.json" "$out/m.chbank"
done
