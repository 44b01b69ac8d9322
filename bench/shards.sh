#!/usr/bin/env bash
# A sharded bake against the one-process bake of the same scene and options, in the same run
# (issue 17, point 3): every shard of every phase run one after another with --threads 2 (the
# machine's cores), so each shard's seconds are what one node of that size would spend; then
# the merge. Prints per-phase shard seconds (/usr/bin/time wall, the slowest and the sum), the
# merge's seconds and peak memory, the parts' bytes, and whether the asset is byte-identical.
# usage: bash bench/shards.sh BUILD_DIR MESH OUT_DIR SHARDS [bake options...]
set -euo pipefail
build=$1 mesh=$2 out=$3 shards=$4
shift 4
prtsub=$build/prtsub
rm -rf "$out" && mkdir -p "$out"
/usr/bin/time -f "%e %M" -o "$out/single.time" "$prtsub" bake "$mesh" "$@" --threads 2 -o "$out/single.ply" > "$out/single.log"
phases=$("$prtsub" bake "$mesh" "$@" --threads 2 --shard-phases)
echo "| phase | shards | slowest shard s | sum of shards s | points | parts MB |"
echo "|---:|---:|---:|---:|---:|---:|"
total=0
for p in $(seq 1 "$phases"); do
  slowest=0 sum=0 points=0
  for i in $(seq 1 "$shards"); do
    /usr/bin/time -f "%e" -o "$out/t" "$prtsub" bake "$mesh" "$@" --threads 2 --shard "$i/$shards" --parts "$out/parts" --phase "$p" \
      --report "$out/r.json" > /dev/null
    t=$(cat "$out/t")
    n=$(python3 -c "import json; print(json.load(open('$out/r.json'))['points'])")
    slowest=$(python3 -c "print(max($slowest, $t))") sum=$(python3 -c "print($sum + $t)") points=$((points + n))
  done
  mb=$(python3 -c "import glob, os; print('%.1f' % (sum(os.path.getsize(f) for f in glob.glob('$out/parts/phase$p-*.part')) / 1e6))")
  echo "| $p | $shards | $slowest | $(python3 -c "print('%.2f' % $sum)") | $points | $mb |"
  total=$(python3 -c "print($total + $sum)")
done
/usr/bin/time -f "%e %M" -o "$out/merge.time" "$prtsub" merge "$out/parts" -o "$out/merged.ply" > "$out/merge.log"
read -r sw sm < "$out/single.time"
read -r mw mm < "$out/merge.time"
echo
echo "| run | wall s | peak MiB |"
echo "|---|---:|---:|"
echo "| one process | $sw | $((sm / 1024)) |"
echo "| all shards, one after another | $(python3 -c "print('%.2f' % $total)") | |"
echo "| merge | $mw | $((mm / 1024)) |"
cmp -s "$out/single.ply" "$out/merged.ply" && echo "merged asset byte-identical to the one-process bake: yes" || echo "merged asset byte-identical: NO"
