#!/usr/bin/env bash
# How simplification's time grows with the input (issue 12, point 5): bunny and its uniform
# (linear, so the same surface) refinements to 4x and 16x, each simplified to 10% of its own
# triangles; the collapse stage alone (seconds_simplify, point values, one ray per vertex so
# nothing else costs). Prints n, the seconds, and seconds / (n log2 n) relative to the first.
#   bench/simplify_scaling.sh BUILD_DIR SHARED_SCENES_DIR OUT_DIR
set -euo pipefail
B="$1/prtsub"; S="$2"; O="$3"
mkdir -p "$O"
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
cp "$S/bunny.ply" "$O/bunny_0.ply"
for k in 1 2; do
  "$B" bake "$S/bunny.ply" -o "$O/bunny_$k.ply" --rays 1 --fit point --refine uniform --levels "$k" > /dev/null
done
echo "| input triangles | output | simplify s | s / (n log2 n), relative |"
echo "|---:|---:|---:|---:|"
first=""
for k in 0 1 2; do
  "$B" bake "$O/bunny_$k.ply" -o "$O/count.ply" --rays 1 --fit point --report "$O/count.json" > /dev/null
  n=$(field "$O/count.json" triangles_out)
  "$B" bake "$O/bunny_$k.ply" -o "$O/s_$k.ply" --rays 1 --fit point --refine adaptive --budget $((n / 10)) --report "$O/s_$k.json" > /dev/null
  t=$(field "$O/s_$k.json" seconds_simplify)
  r=$(python3 -c "import math,sys; n=float(sys.argv[1]); t=float(sys.argv[2]); print(t/(n*math.log2(n)))" "$n" "$t")
  [ -z "$first" ] && first=$r
  echo "| $n | $(field "$O/s_$k.json" triangles_out) | $(printf %.2f "$t") | $(python3 -c "print('%.2f' % ($r/$first))") |"
done
