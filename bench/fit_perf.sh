#!/usr/bin/env bash
# Speed of the fit: the solve alone on armadillo (173k vertices, 16 right-hand sides) for each
# regulariser, the sample transfer against a bare Embree loop, and a whole default bake.
# usage: bash bench/fit_perf.sh BUILD_DIR SCENES_DIR OUT_DIR
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
p="$build/prtsub"
$p bench "$scenes/armadillo.ply" --solve --repeat 3 --report "$out/solve_edge.json" | tail -2
$p bench "$scenes/armadillo.ply" --solve --repeat 3 --regularizer gradient --report "$out/solve_gradient.json" | tail -2
$p bench "$scenes/armadillo.ply" --solve --repeat 3 --alpha 0 --report "$out/solve_alpha0.json" | tail -2
for s in armadillo.ply conference.ply bunny.ply; do
  $p bench "$scenes/$s" --at samples --rays 16 --repeat 2 --report "$out/samples_${s%.*}.json" | tail -3
done
$p bake "$scenes/armadillo.ply" -o "$out/armadillo_prt.ply" --report "$out/bake_armadillo.json" | tail -6
