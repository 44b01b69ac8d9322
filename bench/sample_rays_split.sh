#!/usr/bin/env bash
# How the same sample rays are best split: --sample-rays Q with --samples-per-triangle 256/Q
# (Q = 4, 8, 16, 32, 64: 256 sample rays per sampled face on average, as the default's 16 × 16),
# under several seeds; every asset judged by one fixed reference (eval --rays 2048).
# usage: bash bench/sample_rays_split.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE..." "SIGNAL..." "SEED..."
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4 signal_list=$5 seed_list=$6
mkdir -p "$out"
echo "| scene | signal | seed | E % at Q = 4 | 8 | 16 | 32 | 64 |"
echo "|---|---|---:|---:|---:|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for signal in $signal_list; do
    for seed in $seed_list; do
      row="| $name | $signal | $seed |"
      for q in 4 8 16 32 64; do
        stem="$out/${name}_${signal}_${seed}_$q"
        "$build/prtsub" bake "$scenes/$scene" --signal "$signal" --seed "$seed" --sample-rays "$q" --samples-per-triangle $((256 / q)) \
          -o "$stem.ply" > /dev/null
        "$build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
        rm -f "$stem.ply"
        row="$row $(python3 -c "import json; print('%.3f' % json.load(open('$stem.eval.json'))['rms_percent'])") |"
      done
      echo "$row"
    done
  done
done
