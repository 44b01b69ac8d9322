#!/usr/bin/env bash
# The default fit against point sampling given the same total rays (issue 11, point 1): the
# default spends 256 rays per vertex plus 16 per sample; point sampling gets all of them at the
# vertices, R = 256 + 16·samples/vertices per vertex. Both are judged by one fixed reference
# (2048 rays at the same seeded points), so the comparison measures the assets, not the reference.
# usage: bash bench/fit_equal_rays.sh BUILD_DIR SCENES_DIR OUT_DIR SCENE...
set -euo pipefail
build=$1 scenes=$2 out=$3
shift 3
mkdir -p "$out"
echo "| scene | signal | E_default (256 + samples) | E_point (256) | rays per vertex at equal total | E_point (equal total) |"
echo "|---|---|---:|---:|---:|---:|"
for scene in "$@"; do
  name=${scene%.*}
  for signal in transfer ao; do
    a="$out/${name}_${signal}_default.json" b="$out/${name}_${signal}_point.json"
    "$build/prtsub" eval --fits "$scenes/$scene" --signal "$signal" --reference-rays 2048 --sample-allocation area --report "$a" > /dev/null
    rays=$(python3 -c "import json; r=json.load(open('$a')); print(256 + round(16 * r['samples'] / r['vertices']))")
    "$build/prtsub" eval --fits "$scenes/$scene" --signal "$signal" --rays "$rays" --reference-rays 2048 \
      --samples-per-triangle 1 --sample-allocation area --report "$b" > /dev/null
    python3 -c "
import json; a=json.load(open('$a')); b=json.load(open('$b'))
print('| $name | $signal | %.3f | %.3f | $rays | %.3f |' % (a['e_default_percent'], a['e_point_percent'], b['e_point_percent']))"
  done
done
