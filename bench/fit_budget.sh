#!/usr/bin/env bash
# Whole bakes, one row per configuration: the eval error against one fixed reference (2048 rays
# at eval's seeded points, whatever the bake traced), the rays traced and the bake's seconds.
# Configurations are "label=options" words; the first is the baseline the others are compared with.
# usage: bash bench/fit_budget.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE..." "SIGNAL..." LABEL=OPTIONS...
#   e.g. bash bench/fit_budget.sh build ../shared/scenes OUT "bunny.ply" "transfer ao" \
#          "area=--sample-allocation area" "pilot=" "pilot-1=--pilot-vertex-share 1"
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4 signal_list=$5
shift 5
mkdir -p "$out"
echo "| scene | signal | configuration | E % | rays (M) | bake s | E / baseline | s / baseline |"
echo "|---|---|---|---:|---:|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for signal in $signal_list; do
    base_e="" base_s=""
    for config in "$@"; do
      label=${config%%=*} opts=${config#*=}
      stem="$out/${name}_${signal}_${label}"
      # shellcheck disable=SC2086
      "$build/prtsub" bake "$scenes/$scene" --signal "$signal" $opts -o "$stem.ply" --report "$stem.bake.json" > /dev/null
      "$build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
      row=$(python3 - "$stem.bake.json" "$stem.eval.json" "$base_e" "$base_s" <<'PY'
import json, sys
b, e = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
err, sec = e['rms_percent'], b['seconds_total']
be = float(sys.argv[3]) if sys.argv[3] else err
bs = float(sys.argv[4]) if sys.argv[4] else sec
print('%.4f %.3f %.3f | %.1f | %.2f | %.3f | %.2f' % (err, sec, err, b['rays'] / 1e6, sec, err / be, sec / bs))
PY
)
      read -r e s rest <<< "$row"
      [ -n "$base_e" ] || { base_e=$e; base_s=$s; }
      echo "| $name | $signal | $label | $rest |"
      rm -f "$stem.ply"
    done
  done
done
