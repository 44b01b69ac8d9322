#!/usr/bin/env bash
# Issue 11, point 3: what `--error E` predicts for its asset (the hold-out estimate the bake stops
# on, and the hold-out's rays per sample after --error sharpened it) against `prtsub eval --rays
# 2048` with its independent reference. eval's figure includes its reference's own noise: "eval,
# floor removed" is √(E² − floor²), and the ratio is eval (floor removed) over predicted. "rays"
# is every ray the bake traced.
# usage: bash bench/target_prediction.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE:SIGNAL:E:SEED..." [extra bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3 runs=$4
shift 4
mkdir -p "$out"
echo "| scene | signal | E | seed | predicted % (± s.e.) | hold-out rays per sample | eval % | eval, floor removed % | eval / predicted | rays (M) | bake s |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for run in $runs; do
  IFS=: read -r scene signal target seed <<< "$run"
  name=${scene%.*}
  stem="$out/${name}_${signal}_${target}_${seed}"
  /usr/bin/time -f "%e" -o "$stem.time" "$build/prtsub" bake "$scenes/$scene" --signal "$signal" --error "$target" --seed "$seed" "$@" \
    -o "$stem.ply" --report "$stem.bake.json" > /dev/null
  "$build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
  python3 - "$stem.bake.json" "$stem.eval.json" "$stem.time" "$name" "$signal" "$target" "$seed" <<'PY'
import json, math, sys
b, e = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
seconds = float(open(sys.argv[3]).read().split()[0])
p, m, floor = b['predicted_error_percent'], e['rms_percent'], e['noise_floor_percent']
clean = math.sqrt(max(0.0, m * m - floor * floor))
print('| %s | %s | %s | %s | %.3f (± %.3f) | %d | %.3f | %.3f | %.2f | %.1f | %.1f |' % (sys.argv[4], sys.argv[5], sys.argv[6], sys.argv[7], p,
      b['predicted_error_standard_error'], b.get('holdout_rays_per_sample', 0), m, clean, clean / max(p, 1e-12), b['rays'] / 1e6, seconds))
PY
  rm -f "$stem.ply"
done
