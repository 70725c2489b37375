#!/usr/bin/env bash
# Every bundled mesh in steel with --max-modes 100 and otherwise default settings
# (docs/PERFORMANCE.md, "Precompute at defaults"): time, peak memory, the meshes the refinement
# solved, the error estimate, and the first 20 modes against a reference solve (see below). A
# run that fails prints its error as the row.
# Usage: bash bench/accuracy_bench.sh [path/to/chladni] [mesh names...]   (default: build/cli/chladni, all)
# shellcheck source=bench/bundled_meshes.sh
source "$(dirname "$0")/bundled_meshes.sh"

echo "| mesh | meshes solved | tets | DOFs | modes kept | time (s) | peak RSS (MB) | worst estimate, 100 modes | worst estimate, first 20 | first 20 against the reference | reference tets |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for name in "${names[@]}"; do
  mesh=meshes/$name.obj
  if ! "$chladni" precompute "$mesh" --material steel --max-modes 100 --no-transfer -q \
    -o "$out/d.chbank" --json "$out/d.json" 2>"$out/d.err"; then
    echo "| $name | failed: $(tail -n 1 "$out/d.err") |"
    continue
  fi
  # The reference: uniform tets a third the default run's mean volume where the default run
  # solved one mesh. A locally refined run's mean volume hides its small tets (a uniform mesh at
  # a third of it can need tens of GB: bell, rotor), so there the first 20 modes are refined
  # locally to a third of the default run's worst estimate over them instead, but not below 0.15 %
  # (an estimate of 0.15 % suffices to check 1 %, and the coupling's reference then fits 24 GB).
  ref=$(python3 -c "
import json, sys
j = json.load(open(sys.argv[1]))
if len(j['accuracy']['meshes']) > 1:
    print('--tolerance', max(1.5e-3, max(j['frequency_error_estimate'][:20]) / 3))
else:
    print('--max-tet-volume', j['surface']['volume_m3'] / j['volume_mesh']['tetrahedra'] / 3)
" "$out/d.json")
  # shellcheck disable=SC2086 # two words: the option and its value
  if ! "$chladni" precompute "$mesh" --material steel --max-modes 20 --no-transfer -q \
    $ref -o "$out/r.chbank" --json "$out/r.json" 2>"$out/r.err"; then
    echo "| $name | reference failed: $(tail -n 1 "$out/r.err") |"
    continue
  fi
  python3 - "$name" "$out/d.json" "$out/r.json" <<'PY'
import json, sys
name, d, r = sys.argv[1], json.load(open(sys.argv[2])), json.load(open(sys.argv[3]))
fd, fr, e = d["frequencies_hz"], r["frequencies_hz"], d["frequency_error_estimate"]
n = min(20, len(fd), len(fr))
actual = max(abs(fd[i] / fr[i] - 1) for i in range(n))
v = d["volume_mesh"]
ref = str(r["volume_mesh"]["tetrahedra"])
if len(r["accuracy"]["meshes"]) > 1:
    ref += f" (local, {100 * max(r['frequency_error_estimate'][:20]):.2f} %)"
print(f"| {name} | {len(d['accuracy']['meshes'])} | {v['tetrahedra']} | {v['dofs']} | {d['modes']['kept']} "
      f"| {d['total_seconds']:.1f} | {d['peak_rss_mb']:.0f} | {100 * max(e):.2f} % | {100 * max(e[:20]):.2f} % "
      f"| {100 * actual:.2f} % | {ref} |", flush=True)
PY
done
