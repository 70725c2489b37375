#!/usr/bin/env bash
# Batch throughput on the bundled meshes (docs/PERFORMANCE.md, "Batch"): bench/batch_bundled.json
# (8 meshes in steel, 20 modes, no transfer, plus the 2 broken meshes, which fail in a fraction of a
# second) with --force, on 1 core, on 2 cores (2 jobs of 1 thread, and 1 job of 2 threads), and on
# 2 MPI ranks of 1 thread. Prints a table row per configuration, from the batch's summary.
# Usage: bash bench/batch_bench.sh [path/to/chladni]     (default: build/release/cli/chladni)
set -euo pipefail
cd "$(dirname "$0")/.."
chladni=$(realpath "${1:-build/release/cli/chladni}")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
mpi_root=""
if [[ $(id -u) -eq 0 ]]; then mpi_root="--allow-run-as-root"; fi

row() {  # label, then the command that runs the batch (its summary goes to $out/s.json)
  local label=$1
  shift
  "$@" >/dev/null 2>&1 || true  # the broken meshes make it exit 2
  /usr/bin/python3 - "$label" "$out/s.json" <<'PY'
import json, sys
label, path = sys.argv[1], sys.argv[2]
j = json.load(open(path))
ok = [a for a in j["assets"] if a["status"] == "ok"]
bad = [a for a in j["assets"] if a["status"] == "bad input"]
cpu = sum(a["seconds"] for a in ok)
peak = max(a["peak_memory_mb"] for a in ok)
print(f"| {label} | {len(ok)} ok, {len(bad)} bad input | {j['seconds']:.1f} | {cpu:.1f} "
      f"| {60 * len(ok) / j['seconds']:.2f} | {peak:.0f} |")
PY
}

m=bench/batch_bundled.json
common=(--force -o "$out/banks" --summary "$out/s.json" -q)
echo "| configuration | assets | wall (s) | sum of asset times (s) | assets per minute | largest peak (MB) |"
echo "|---|---|---|---|---|---|"
row "1 core: -j 1 --threads 1 (taskset -c 0)" taskset -c 0 "$chladni" batch $m "${common[@]}" -j 1 --threads 1
row "2 cores: -j 1 --threads 2" "$chladni" batch $m "${common[@]}" -j 1 --threads 2
row "2 cores: -j 2 --threads 1 (default -j)" "$chladni" batch $m "${common[@]}" -j 2 --threads 1
row "2 MPI ranks: mpirun -np 2, -j 1 --threads 1" mpirun $mpi_root --oversubscribe -np 2 "$chladni" batch $m "${common[@]}" -j 1 --threads 1
