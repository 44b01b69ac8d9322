#!/usr/bin/env bash
# Which edge estimate wins: every scene refined adaptively to 2x and 4x its triangles with each
# estimate, point-sampled values at 64 rays per vertex, against uniform level 1 (4x).
# usage: bash bench/estimates.sh BUILD_DIR SCENES_DIR OUT_DIR
#        (then: python3 bench/summarize.py OUT_DIR --estimates-only)
set -euo pipefail
B="$1/prtsub"; S="$2"; O="$3"
mkdir -p "$O/estimates"
triangles() {  # input triangle count, from a one-ray bake's report
  "$B" bake "$1" -o "$O/count.ply" --rays 1 --fit point --report "$O/count.json" > /dev/null
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['triangles_out'])" "$O/count.json"
}
for f in "$S"/*.obj "$S"/*.ply; do
  n=$(basename "${f%.*}"); F=$(triangles "$f")
  echo "== estimates: $n ($F triangles)"
  "$B" compare "$f" --budgets $((2 * F)),$((4 * F)) --max-levels 1 --rays 64 --eval-points 20000 --fit point \
    --frame-size 320,240 --frame-rays 64 -o "$O/estimates/$n" > "$O/estimates/$n.log"
done
