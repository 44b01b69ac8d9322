#!/usr/bin/env bash
# The bake's load stage alone (reading, parsing and building the mesh: the report's
# `seconds_load`), each scene N times by each build in turn (alternating, so load on a shared
# machine falls on both); the bake itself is one ray per vertex with point values, so the runs
# are short. Prints the median and the range of each.
# usage: bash bench/load.sh N SCENES_DIR "SCENE..." BUILD_DIR...
#   e.g. bash bench/load.sh 7 ../shared/scenes "armadillo.ply conference.ply" /tmp/before build
set -euo pipefail
n=$1 scenes=$2 scene_list=$3
shift 3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| scene | build | median load s | range s |"
echo "|---|---|---:|---|"
for scene in $scene_list; do
  for ((i = 0; i < n; ++i)); do
    for build in "$@"; do
      tag=$(echo "$build" | tr '/' '_')
      "$build/prtsub" bake "$scenes/$scene" -o "$out/x.ply" --rays 1 --fit point --report "$out/r.json" > /dev/null
      python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['seconds_load'])" "$out/r.json" >> "$out/$tag.$scene"
    done
  done
  for build in "$@"; do
    tag=$(echo "$build" | tr '/' '_')
    python3 - "$out/$tag.$scene" "${scene%.*}" "$build" <<'PY'
import statistics, sys
t = [float(x) for x in open(sys.argv[1])]
print('| %s | %s | %.3f | %.3f–%.3f |' % (sys.argv[2], sys.argv[3], statistics.median(t), min(t), max(t)))
PY
  done
done
