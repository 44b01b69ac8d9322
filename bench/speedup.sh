#!/usr/bin/env bash
# Issue 11, point 3: whole bakes by two builds in the same run (configurations alternate scene by
# scene), each timed by wall clock and judged by one build's eval against one fixed reference
# (2048 rays at eval's seeded points). "label=BUILD_DIR:options" words, as bench/compare_builds.sh.
# usage: bash bench/speedup.sh EVAL_BUILD SCENES_DIR OUT_DIR "SCENE..." LABEL=BUILD:OPTIONS...
set -euo pipefail
eval_build=$1 scenes=$2 out=$3 scene_list=$4
shift 4
mkdir -p "$out"
echo "| scene | configuration | E % | bake s (wall) | peak MiB |"
echo "|---|---|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for config in "$@"; do
    label=${config%%=*} rest=${config#*=}
    build=${rest%%:*} opts=${rest#*:}
    stem="$out/${name}_${label}"
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e %M" -o "$stem.time" "$build/prtsub" bake "$scenes/$scene" $opts -o "$stem.ply" > /dev/null
    "$eval_build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
    python3 -c "
import json; e=json.load(open('$stem.eval.json')); t=open('$stem.time').read().split()
print('| $name | $label | %.3f | %.2f | %.0f |' % (e['rms_percent'], float(t[0]), float(t[1]) / 1024))"
    rm -f "$stem.ply"
  done
done
