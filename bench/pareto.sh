#!/usr/bin/env bash
# Speed against error (issue 11, point 6): `prtsub compare --pareto` on each scene and signal, then
# one Markdown table of the default and --error runs against the grid's front at equal time, and
# each scene's plot as an SVG file.
# usage: bash bench/pareto.sh BUILD SCENES_DIR OUT_DIR "SCENE..." "SIGNAL..." [compare options...]
#   e.g. bash bench/pareto.sh build ../shared/scenes OUT "bunny.ply teapot.obj" "transfer ao" \
#          --grid-rays 64,128,256,512,1024
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4 signal_list=$5
shift 5
mkdir -p "$out"
for scene in $scene_list; do
  for signal in $signal_list; do
    dir="$out/${scene%.*}_$signal"
    if [ ! -f "$dir/pareto.json" ]; then
      "$build/prtsub" compare "$scenes/$scene" --pareto --signal "$signal" -o "$dir" "$@" > "$dir.log"
    fi
  done
done
python3 "$(dirname "$0")/pareto_table.py" "$out" $scene_list -- $signal_list
