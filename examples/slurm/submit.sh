#!/usr/bin/env bash
# Submits a sharded prtsub bake to Slurm: one job array per phase (one array task per shard,
# each phase after the one before it with --dependency=afterok), then the merge.
#
#   examples/slurm/submit.sh SHARDS PARTS_DIR ASSET INPUT [bake options...]
#
# Prints the merge job's id (the last line), so a caller can wait for it. PRTSUB names the
# binary (default: prtsub on PATH); SBATCH_ARGS adds options to every sbatch (a partition, time).
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 SHARDS PARTS_DIR ASSET INPUT [bake options...]" >&2
  exit 2
fi
shards=$1 parts=$2 asset=$3 input=$4
shift 4
here=$(cd "$(dirname "$0")" && pwd)
export PRTSUB=${PRTSUB:-prtsub}
mkdir -p "$parts"
# The phases of this bake (1 to 3: the pilot's stages and the samples depend on what came before).
phases=$("$PRTSUB" bake "$input" "$@" --shard-phases)
previous=""
for phase in $(seq 1 "$phases"); do
  # shellcheck disable=SC2086
  previous=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name="prtsub-phase$phase" --array="1-$shards" \
    --output="$parts/slurm-phase$phase-%a.log" ${previous:+--dependency=afterok:$previous} \
    "$here/shard.sbatch" "$phase" "$shards" "$parts" "$input" "$@")
  echo "phase $phase of $phases: job array $previous ($shards tasks)"
done
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_ARGS:-} --job-name=prtsub-merge --output="$parts/slurm-merge.log" \
  --dependency="afterok:$previous" "$here/merge.sbatch" "$parts" "$asset")
echo "merge: job $merge -> $asset"
echo "$merge"
