#!/usr/bin/env bash
# The same sharded bake without a scheduler: GNU parallel runs each phase's shards (JOBS at a
# time, default 2), one phase after another, then the merge. The asset is byte for byte the
# one `prtsub bake INPUT [options] -o ASSET` writes.
#
#   examples/slurm/parallel.sh SHARDS PARTS_DIR ASSET INPUT [bake options...]
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 SHARDS PARTS_DIR ASSET INPUT [bake options...]" >&2
  exit 2
fi
shards=$1 parts=$2 asset=$3 input=$4
shift 4
PRTSUB=${PRTSUB:-prtsub}
phases=$("$PRTSUB" bake "$input" "$@" --shard-phases)
for phase in $(seq 1 "$phases"); do
  parallel --will-cite -q --halt now,fail=1 -j "${JOBS:-2}" "$PRTSUB" bake "$input" "$@" --shard "{}/$shards" --parts "$parts" --phase "$phase" \
    ::: $(seq 1 "$shards")
done
"$PRTSUB" merge "$parts" -o "$asset"
