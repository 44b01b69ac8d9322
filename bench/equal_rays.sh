#!/usr/bin/env bash
# Issue 11, point 1: the default bake against point sampling given every ray the default traced
# (its vertices, pilot, samples and second round), all at the vertices: --fit point --rays R with
# R = the default's rays per vertex. Both judged by one fixed reference (eval --rays 2048 at its
# seeded points), so the comparison measures the assets, not the reference.
# usage: bash bench/equal_rays.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE..." "SIGNAL..." [bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4 signal_list=$5
shift 5
mkdir -p "$out"
echo "| scene | signal | rays per vertex | E_default % | E_point at equal rays % | default / point |"
echo "|---|---|---:|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for signal in $signal_list; do
    stem="$out/${name}_${signal}"
    "$build/prtsub" bake "$scenes/$scene" --signal "$signal" "$@" -o "$stem.default.ply" --report "$stem.default.json" > /dev/null
    rays=$(python3 -c "import json; r=json.load(open('$stem.default.json')); print(round(r['rays'] / r['vertices_out']))")
    "$build/prtsub" bake "$scenes/$scene" --signal "$signal" --fit point --rays "$rays" -o "$stem.point.ply" > /dev/null
    for v in default point; do
      "$build/prtsub" eval "$stem.$v.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.$v.eval.json" > /dev/null
      rm -f "$stem.$v.ply"
    done
    python3 -c "
import json; a=json.load(open('$stem.default.eval.json')); b=json.load(open('$stem.point.eval.json'))
print('| $name | $signal | $rays | %.3f | %.3f | %.3f |' % (a['rms_percent'], b['rms_percent'], a['rms_percent'] / b['rms_percent']))"
  done
done
