#!/usr/bin/env bash
# Whole bakes by different builds (a before and an after), each judged by one build's eval against
# one fixed reference (2048 rays at eval's seeded points), so a change to the estimator does not
# move the yardstick. Configurations are "label=BUILD_DIR:options" words.
# usage: bash bench/compare_builds.sh EVAL_BUILD SCENES_DIR OUT_DIR "SCENE..." "SIGNAL..." LABEL=BUILD:OPTIONS...
#   e.g. bash bench/compare_builds.sh build ../shared/scenes OUT "bunny.ply" "transfer ao" \
#          "before=/tmp/old/build:" "after=build:" "after-p1=build:--pilot-samples 1"
set -euo pipefail
eval_build=$1 scenes=$2 out=$3 scene_list=$4 signal_list=$5
shift 5
mkdir -p "$out"
echo "| scene | signal | configuration | E % | rays per vertex | bake s |"
echo "|---|---|---|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for signal in $signal_list; do
    for config in "$@"; do
      label=${config%%=*} rest=${config#*=}
      build=${rest%%:*} opts=${rest#*:}
      stem="$out/${name}_${signal}_${label}"
      # shellcheck disable=SC2086
      "$build/prtsub" bake "$scenes/$scene" --signal "$signal" $opts -o "$stem.ply" --report "$stem.bake.json" > /dev/null
      "$eval_build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
      python3 - "$stem.bake.json" "$stem.eval.json" "$name" "$signal" "$label" <<'PY'
import json, sys
b, e = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
print('| %s | %s | %s | %.3f | %.1f | %.2f |' % (sys.argv[3], sys.argv[4], sys.argv[5], e['rms_percent'],
      b['rays'] / b['vertices_out'], b['seconds_total']))
PY
      rm -f "$stem.ply"
    done
  done
done
