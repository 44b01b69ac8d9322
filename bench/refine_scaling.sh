#!/usr/bin/env bash
# Refinement overhead and scaling: the teapot refined to four budgets up to 200k, at 64 and 256
# rays per vertex, with point-sampled values (the fit does not change refinement's times).
# usage: bash bench/refine_scaling.sh BUILD_DIR SCENES_DIR OUT_DIR
#        (then: python3 bench/summarize.py OUT_DIR --scaling-only)
set -euo pipefail
B=$1/prtsub S=$2 O=$3
mkdir -p "$O"
for T in 25000 50000 100000 200000; do
  "$B" bake "$S/teapot.obj" -o "$O/teapot_$T.ply" --refine adaptive --budget $T --rays 64 --fit point --report "$O/scaling_$T.json" > /dev/null
  "$B" bake "$S/teapot.obj" -o "$O/teapot_$T.ply" --refine adaptive --budget $T --fit point --report "$O/scaling256_$T.json" > /dev/null
done
