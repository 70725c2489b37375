#!/usr/bin/env bash
# A dense surface, as a scan or a sculpt brings it: spot.obj split by midpoint subdivision into
# 4^L times the triangles (the same solid, exactly), precomputed for 20 modes at defaults, which
# simplify it (--max-surface-triangles 20000), and with --max-surface-triangles 0 (every triangle
# kept; pass "keep" as the third argument, it takes minutes and up to 18 GB at L = 2). Prints
# time, peak memory, the surface and volume meshes, and the largest difference of the 20 modes
# from spot.obj's own.
# Usage: bash bench/dense_surface_bench.sh [path/to/chladni] [levels, e.g. "2 3"] [keep]
set -euo pipefail
cd "$(dirname "$0")/.."
chladni=${1:-build/cli/chladni}
levels=${2:-"2 3"}
keep=${3:-}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

run() {  # name mesh extra-options...
  local name=$1 mesh=$2
  shift 2
  /usr/bin/time -o "$out/time" -f "%e %M" "$chladni" precompute "$mesh" --max-modes 20 \
    --no-transfer -q -o "$out/$name.chbank" --json "$out/$name.json" "$@"
  read -r secs kb <"$out/time"
  python3 - "$name" "$out/$name.json" "$out/spot.json" "$secs" "$kb" <<'PY'
import json, os, sys
name, path, ref, secs, kb = sys.argv[1:6]
j = json.load(open(path))
s, v = j["surface"], j["volume_mesh"]
diff = "-"
if os.path.exists(ref) and path != ref:
    a, b = j["frequencies_hz"], json.load(open(ref))["frequencies_hz"]
    diff = f"{100 * max(abs(x / y - 1) for x, y in zip(a, b)):.2f} %"
print(f"| {name} | {s['simplified_from'] or s['triangles']} | {s['triangles']} | {v['tetrahedra']} "
      f"| {100 * max(j['frequency_error_estimate']):.2f} % | {float(secs):.1f} "
      f"| {int(kb) / 1024:.0f} | {diff} |")
PY
}

echo "| mesh | triangles read | triangles meshed | tetrahedra | worst estimate | time (s) | peak RSS (MB) | largest difference from spot.obj |"
echo "|---|---|---|---|---|---|---|---|"
run spot meshes/spot.obj
for level in $levels; do
  python3 - meshes/spot.obj "$level" "$out/spot_x$level.obj" <<'PY'
import sys
src, levels, dst = sys.argv[1], int(sys.argv[2]), sys.argv[3]
V, F = [], []
for line in open(src):
    p = line.split()
    if p and p[0] == "v":
        V.append(tuple(map(float, p[1:4])))
    elif p and p[0] == "f":
        F.append(tuple(int(x.split("/")[0]) - 1 for x in p[1:4]))
for _ in range(levels):
    mid, G = {}, []
    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            mid[k] = len(V)
            V.append(tuple((x + y) / 2 for x, y in zip(V[a], V[b])))
        return mid[k]
    for a, b, c in F:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        G += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    F = G
with open(dst, "w") as o:
    o.writelines("v %.17g %.17g %.17g\n" % p for p in V)
    o.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in F)
PY
  run "spot x4^$level" "$out/spot_x$level.obj"
  [[ -n $keep ]] && run "spot x4^$level, kept" "$out/spot_x$level.obj" --max-surface-triangles 0
done
