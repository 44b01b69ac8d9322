#!/usr/bin/env bash
# The bake's own error estimate (measured on the pilot's held-out samples) against what
# `prtsub eval --rays 2048` then measures with an independent reference, for default bakes.
# eval's figure includes its reference's own noise: "eval, floor removed" is √(E² − floor²).
# usage: bash bench/predicted_error.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE..." [extra bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4
shift 4
mkdir -p "$out"
echo "| scene | signal | predicted % (± s.e.) | eval % | eval, floor removed % | predicted / eval |"
echo "|---|---|---:|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for signal in transfer ao; do
    stem="$out/${name}_${signal}"
    "$build/prtsub" bake "$scenes/$scene" --signal "$signal" "$@" -o "$stem.ply" --report "$stem.bake.json" > /dev/null
    "$build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
    python3 - "$stem.bake.json" "$stem.eval.json" "$name" "$signal" <<'PY'
import json, math, sys
b, e = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
p, m, floor = b['predicted_error_percent'], e['rms_percent'], e['noise_floor_percent']
print('| %s | %s | %.3f (± %.3f) | %.3f | %.3f | %.2f |' % (sys.argv[3], sys.argv[4], p, b['predicted_error_standard_error'], m,
      math.sqrt(max(0.0, m * m - floor * floor)), p / m))
PY
    rm -f "$stem.ply"
  done
done
