#!/usr/bin/env bash
# The least-squares paper's Table 1 on every scene: E_point, E_avg, E_lsq (alpha 0) and E(alpha)
# for ambient occlusion and order-4 transfer, with ray-casting and solve time and memory. Every
# face is sampled by area, as in the paper (the bake's default pilot samples fewer: fit_budget.sh).
# usage: bash bench/fit_table.sh BUILD_DIR SCENES_DIR OUT_DIR   (then: python3 bench/summarize_fits.py OUT_DIR)
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
for scene in "$scenes"/*.obj "$scenes"/*.ply; do
  name=$(basename "${scene%.*}")
  for signal in ao transfer; do
    echo "== $name $signal"
    "$build/prtsub" eval --fits "$scene" --signal "$signal" --sample-allocation area --report "$out/${name}_${signal}.json" | tail -6
  done
done
