#!/usr/bin/env bash
# Analytic against sampled mass matrix at low sample counts (and the analytic one without the
# control variate, as the paper estimates b), order-4 transfer, from eval --fits reports.
# usage: bash bench/fit_mass.sh BUILD_DIR SCENES_DIR GENERATED_DIR OUT_DIR
set -euo pipefail
build=$1 scenes=$2 gen=$3 out=$4
mkdir -p "$out"
for scene in "$scenes/cornell_box.obj" "$scenes/house_on_site.obj" "$gen/spot_on_ground.obj" "$scenes/teapot.obj" "$scenes/bunny.ply"; do
  name=$(basename "${scene%.*}")
  for n in 1 2 4 16; do
    for mass in analytic sampled plain; do
      opts="--mass $mass"
      [ "$mass" = plain ] && opts="--mass analytic --no-control-variate"
      "$build/prtsub" eval --fits "$scene" --sample-allocation area --samples-per-triangle $n $opts --points 10000 \
        --report "$out/${name}_${n}_${mass}.json" > /dev/null 2>&1
      python3 -c "import json,sys; r=json.load(open('$out/${name}_${n}_${mass}.json')); print('$name', $n, '$mass', '%.3f %.3f %.3f' % (r['e_avg_percent'], r['e_lsq_percent'], r['e_alpha_percent']))"
    done
  done
done
