#!/usr/bin/env bash
# Per-vertex early stop against fixed ray counts (issue 15 point 2): each scene baked with every
# vertex at 1024 and at 512 rays (--rays-fixed), and with early stop from FIRST (default 32) up
# to 1024 rays (--first-rays FIRST --rays 1024) at several --ray-noise prices (NOISE, default
# "0.5 1 2"); every asset judged by eval against one fixed reference (--rays 8192, --points
# 20000, its seed fixed), so the columns compare the assets, not references.
# Usage: bench/early_stop.sh [build dir] [scenes...]; FIT=point (the default) or FIT=lsq; SEED (default 0)
# is every bake's --seed (eval's reference keeps its own); EXTRA more bake options (e.g. "--signal ao").
set -euo pipefail
build=${1:-build}; shift || true
scenes=${*:-bunny.ply armadillo.ply conference.ply sibenik.obj mori_knob.obj}
fit=${FIT:-point}
out=${OUT:-/tmp/prtsub_early_stop}
mkdir -p "$out"
printf '%-16s %-44s %12s %10s %8s %s\n' scene config rays eval_% bake_s distribution
for s in $scenes; do
  src=../shared/scenes/$s
  configs=("--rays-fixed 1024" "--rays-fixed 512")
  for n in ${NOISE:-0.5 1 2}; do configs+=("--first-rays ${FIRST:-32} --rays 1024 --ray-noise $n"); done
  for cfg in "${configs[@]}"; do
    name=${s%.*}_$(echo "$cfg ${EXTRA:-}" | tr -d ' -')_${fit}_s${SEED:-0}
    # shellcheck disable=SC2086
    "$build/prtsub" bake "$src" -o "$out/$name.ply" --fit "$fit" --seed "${SEED:-0}" ${EXTRA:-} $cfg --report "$out/$name.json" > /dev/null
    "$build/prtsub" eval "$out/$name.ply" --source "$src" --rays 8192 --points 20000 --report "$out/$name.eval.json" > /dev/null
    /usr/bin/python3 - "$out/$name.json" "$out/$name.eval.json" "$s" "$cfg" <<'PY'
import json, sys
b, e = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
print(f"{sys.argv[3]:16s} {sys.argv[4]:44s} {b['rays']:12d} {e['rms_percent']:10.3f} {b['seconds_total']:8.1f} {b['vertex_rays_distribution']}")
PY
  done
done
