#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang + ASan + UBSan (build/fuzz) and fuzzes each reader
# for SECONDS (default 30), two at a time. Every run starts from the committed seeds
# (fuzz/corpus/NAME) plus what earlier runs here found (build/fuzz/corpus/NAME). A crash, leak,
# timeout or memory blow-up fails the script and its input is copied to fuzz/regressions/NAME/,
# where ctest replays it from then on. Prints executions and coverage per harness.
#   bash scripts/fuzz.sh [SECONDS] [NAME ...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
shift || true
bash scripts/deps.sh
cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCHLADNI_BUILD_FUZZERS=ON -DCHLADNI_BUILD_TESTS=OFF -DCHLADNI_BUILD_BENCH=OFF >/dev/null
cmake --build build/fuzz --target chladni_fuzzers -j "$(nproc)"

names=("$@")
if ((${#names[@]} == 0)); then
  names=(mesh_obj mesh_off mesh_ply mesh_stl soundbank scene chpaper paper_animation paper_db
         number_table)
fi
mkdir -p build/fuzz/logs
export ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

fuzz_one() {
  local name=$1 seconds=$2
  local work=build/fuzz/corpus/$name findings=build/fuzz/findings/$name
  rm -rf "$findings"  # only this run's findings are reported and kept
  mkdir -p "$work" "$findings"
  # -rss_limit_mb: a reader that allocates past 2 GB for a small file is a finding;
  # -timeout: one input taking over 10 s is a hang.
  if build/fuzz/fuzz/fuzz_"$name" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -print_final_stats=1 -artifact_prefix="$findings/" \
      "$work" "fuzz/corpus/$name" >"build/fuzz/logs/$name.log" 2>&1; then
    echo "ok $name"
  else
    echo "FAIL $name"
  fi
}
export -f fuzz_one
printf '%s\n' "${names[@]}" | xargs -P 2 -I{} bash -c "fuzz_one {} $seconds" | sort >build/fuzz/results

status=0
printf '%-16s %10s %8s %8s %7s  %s\n' harness executions cov features corpus result
for name in "${names[@]}"; do
  log=build/fuzz/logs/$name.log
  runs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | awk '{print $2}' | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | awk '{print $2}')
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -1 | awk '{print $2}')
  units=$(find "build/fuzz/corpus/$name" "fuzz/corpus/$name" -type f | wc -l)
  result=$(grep -E "^(ok|FAIL) $name\$" build/fuzz/results | cut -d' ' -f1)
  printf '%-16s %10s %8s %8s %7s  %s\n' "$name" "${runs:-?}" "${cov:-?}" "${ft:-?}" "$units" "$result"
  if [[ $result != ok ]]; then
    status=1
    mkdir -p "fuzz/regressions/$name"
    find "build/fuzz/findings/$name" -type f -exec cp {} "fuzz/regressions/$name/" \;
    echo "--- $name: findings copied to fuzz/regressions/$name/; the log ends:"
    tail -n 40 "$log"
  fi
done
exit $status
