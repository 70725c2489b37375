#!/usr/bin/env bash
# Times the CI (scripts/test.sh) from a fresh clone of HEAD, stage by stage: a clone has no build
# folder, no ccache and no ctest cost data, as CI has none. Prints each stage's start and the
# total; the whole log goes to DIR/ci.log.
#   bash bench/ci_time.sh [DIR]     (default /tmp/chladni_ci_time; about 30 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-/tmp/chladni_ci_time}
rm -rf "$dir"
git clone -q . "$dir/src"
start=$(date +%s)
stamp() { echo "$(($(date +%s) - start)) s"; }
set +e
(cd "$dir/src" && bash scripts/test.sh) 2>&1 | tee "$dir/ci.log" | while IFS= read -r line; do
  case "$line" in
    "== "* | "100% tests"* | *"tests failed out of"* | "Total Test time"*) echo "$(stamp): $line" ;;
  esac
done
code=${PIPESTATUS[0]}
echo "$(stamp): end, exit $code"
exit "$code"
