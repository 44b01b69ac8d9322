#!/usr/bin/env bash
# The daemon-free recipe (examples/slurm/parallel.sh): the bundled example in 3 shards with GNU
# parallel, merged, must be byte for byte the one-process bake (with per-vertex early stop, whose
# rounds are phases of their own). Without GNU parallel the test
# skips (77), except in CI, whose .ci/deps installs it.
#   parallel_test.sh PRTSUB WORK_DIR
set -euo pipefail
prtsub=$1 work=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
if ! command -v parallel > /dev/null; then
  echo "GNU parallel is not installed (apt-get install parallel)"
  [ "${CI:-}" = true ] && exit 1
  exit 77
fi
rm -rf "$work" && mkdir -p "$work" && cd "$work"
mesh=$root/examples/spot/spot_control_mesh.obj
options=(--rays 64 --order 3 --first-rays 16)
"$prtsub" bake "$mesh" "${options[@]}" -o single.ply > single.log
PRTSUB=$prtsub JOBS=2 bash "$root/examples/slurm/parallel.sh" 3 parts sharded.ply "$mesh" "${options[@]}" > sharded.log
ls parts
phases=$("$prtsub" bake "$mesh" "${options[@]}" --shard-phases)
[ "$(ls parts/*.part | wc -l)" -eq $((3 * phases)) ] || { echo "expected $((3 * phases)) parts"; exit 1; }
cmp single.ply sharded.ply
echo "sharded (3 shards, $phases phases, GNU parallel) = one process, byte for byte"
