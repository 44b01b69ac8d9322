#!/usr/bin/env bash
# Transfer estimators against rays per vertex (issue 15, point 1): each scene baked with point
# values (--fit point, so the estimator alone sets the vertices) by each estimator (cv, the
# default control variate; mc, plain Monte Carlo projection; pls and pls-cv, the progressive
# least-squares encoder on the whole integrand and on its blocked part) at each ray count, one
# fixed seed; every asset judged by eval against one fixed reference (--rays 8192, --points
# 10000, its seed fixed), so the columns compare the assets, not references.
# Usage: bench/estimators.sh BUILD SCENES OUT "scene files" ["estimators"] ["rays"] [extra bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3
names=$4
estimators=${5:-cv mc pls pls-cv}
counts=${6:-8 32 128 512 2048 4096}
extra=${7:-}
mkdir -p "$out"
printf '%-22s %-8s %6s %9s %9s %11s %9s\n' scene estimator rays eval_% p95_% transfer_s mrays/s
for s in $names; do
  src=$scenes/$s
  for e in $estimators; do
    for r in $counts; do
      name=${s%.*}_${e}_$r
      # shellcheck disable=SC2086
      "$build/prtsub" bake "$src" -o "$out/$name.ply" --fit point --rays "$r" --estimator "$e" $extra --report "$out/$name.json" > /dev/null
      "$build/prtsub" eval "$out/$name.ply" --source "$src" --rays 8192 --points 10000 --report "$out/$name.eval.json" > /dev/null
      /usr/bin/python3 - "$out/$name.json" "$out/$name.eval.json" "$s" "$e" "$r" <<'PY'
import json, sys
b, v = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
print(f"{sys.argv[3]:22s} {sys.argv[4]:8s} {int(sys.argv[5]):6d} {v['rms_percent']:9.3f} {v['p95_percent']:9.3f} {b['seconds_transfer']:11.3f} {b['mrays_per_second']:9.2f}",
      flush=True)
PY
    done
  done
done
