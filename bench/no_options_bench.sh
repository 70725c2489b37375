#!/usr/bin/env bash
# Every bundled mesh with no options at all (`chladni precompute MESH -o BANK`: steel, every mode
# below 20 kHz, with transfer): each either succeeds or is refused before the heavy work, with
# the memory it would need and the option to change (docs/PERFORMANCE.md, "With no options").
# Usage: bash bench/no_options_bench.sh [path/to/chladni] [mesh names...]
# shellcheck source=bench/bundled_meshes.sh
source "$(dirname "$0")/bundled_meshes.sh"

echo "| mesh | exit | time (s) | peak RSS (MB) | modes kept | meshes | worst estimate | outcome |"
echo "|---|---|---|---|---|---|---|---|"
for name in "${names[@]}"; do
  set +e
  /usr/bin/time -f "%e %M" -o "$out/time" "$chladni" precompute "meshes/$name.obj" -q \
    -o "$out/b.chbank" --json "$out/s.json" 2>"$out/err"
  code=$?
  set -e
  read -r secs kb < <(tail -n 1 "$out/time") || true
  if ((code == 0)); then
    python3 - "$name" "$secs" "$kb" "$out/s.json" <<'PY'
import json, sys
name, secs, kb, j = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), json.load(open(sys.argv[4]))
e = j.get("frequency_error_estimate") or [0]
print(f"| {name} | 0 | {secs:.1f} | {kb / 1024:.0f} | {j['modes']['kept']} | {len(j['accuracy']['meshes'])} "
      f"| {100 * max(e):.2f} % | soundbank written |")
PY
  else
    # The refusal in short: what it needs, when it was found, the budget, the modes in the band.
    msg=$(grep -v '^\[' "$out/err" | tail -n 1)
    short=$(python3 - "$msg" <<'PY'
import re, sys
m = sys.argv[1]
need = re.search(r"would need (at least|about) ([0-9.]+ GB)", m)
budget = re.search(r"memory budget of ([0-9.]+ GB)", m)
modes = re.search(r"about ([0-9]+) modes lie below", m)
if not (need and budget):
    print(m[:300].replace("|", "\\|"))
else:
    when = "before meshing" if "before meshing" in m else "after meshing, before assembly"
    print(f"refused {when}: needs {need.group(1)} {need.group(2)}, budget {budget.group(1)}"
          + (f"; about {modes.group(1)} modes below 20 kHz" if modes else ""))
PY
)
    echo "| $name | $code | $secs | $((kb / 1024)) | | | | $short |"
  fi
done
