#!/usr/bin/env bash
# Batch size: refinement time and error at 64x the input on two contact-shadow scenes, point-
# sampled values at 64 rays per vertex.
# usage: bash bench/batch.sh BUILD_DIR SCENES_DIR GENERATED_DIR OUT_DIR   (GENERATED_DIR from make_scenes.py)
#        (then: python3 bench/summarize.py OUT_DIR --batch-only)
set -euo pipefail
B="$1/prtsub"; S="$2"; G="$3"; O="$4"
mkdir -p "$O"
for spec in "$S/house_on_site.obj:2710" "$G/spot_on_ground.obj:374"; do
  f=${spec%%:*} F=${spec##*:} n=$(basename "${f%.*}")
  for b in 16 64 256 1024 4096; do
    "$B" bake "$f" -o "$O/${n}_b$b.ply" --refine adaptive --budget $((64 * F)) --rays 64 --batch $b --fit point \
      --report "$O/batch_${n}_$b.json" > /dev/null
    "$B" eval "$O/${n}_b$b.ply" --source "$f" --points 20000 --report "$O/batch_eval_${n}_$b.json" > /dev/null
  done
done
