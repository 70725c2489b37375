# Sourced by the benchmarks that run every bundled mesh: `chladni` (the binary, $1, default
# build/cli/chladni), `names` (the meshes, the other arguments, default all bundled) and `out`
# (a scratch folder, removed on exit), with the working directory at the repository root.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
chladni=${1:-build/cli/chladni}
shift || true
names=("$@")
((${#names[@]})) || names=(bar bowl bell spot rotor pinion_gear coupling sphere)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
