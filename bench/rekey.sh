#!/usr/bin/env bash
# Refinement keyed on bounced light (issue 18, point 3): each SCENE:BUDGET baked with --refine adaptive
# --budget B --bounces 3 at --bounce-rekey 0, 0.5 and 0.25, each judged by one fixed reference.
# usage: bash bench/rekey.sh BUILD_DIR OUT_DIR SCENE:BUDGET ...
set -euo pipefail
build=$1 out=$2; shift 2
P=$build/prtsub
mkdir -p $out
for item in "$@"; do
  scene=${item%%:*} B=${item#*:}
  name=$(basename ${scene%.*})
  for s in 0 0.5 0.25; do
    $P bake $scene -o $out/${name}_$s.ply --refine adaptive --budget $B --bounces 3 --bounce-rekey $s --report $out/${name}_$s.json > /dev/null
    $P eval $out/${name}_$s.ply --source $scene --points 5000 --rays 2048 --paths 1024 --report $out/${name}_${s}_e.json > /dev/null
    python3 -c "import json,sys; b=json.load(open(sys.argv[1])); e=json.load(open(sys.argv[2])); print('| %s | %s | %s | %d | %.2f | %.3f | %.2f |' % (sys.argv[3], sys.argv[4], sys.argv[5], b['triangles_out'], b['seconds_total'], e['rms_percent'], e['noise_floor_percent']))" $out/${name}_$s.json $out/${name}_${s}_e.json $name $B $s
  done
done
