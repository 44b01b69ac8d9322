#!/usr/bin/env bash
# What keeping the fit non-negative costs: the default fit's eval error (E_default of
# `prtsub eval --fits`) with --non-negative off, constant (the default) and directions, and how
# many vertices each limit changed (under "off", the constant limit's count is what would have
# gone negative under a constant light).
# usage: bash bench/fit_non_negative.sh BUILD_DIR SCENES_DIR OUT_DIR
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
echo "| scene | signal | E off | E constant | vertices limited (constant) | E directions | vertices limited (directions) |"
echo "|---|---|---:|---:|---:|---:|---:|"
for scene in cornell_box.obj house_on_site.obj spot_control_mesh.obj sibenik.obj chinese_dragon.obj bunny.ply; do
  name=${scene%.*}
  for signal in transfer ao; do
    row="| $name | $signal"
    for mode in off constant directions; do
      "$build/prtsub" eval --fits "$scenes/$scene" --signal "$signal" --sample-allocation area --non-negative "$mode" --report "$out/${name}_${signal}_$mode.json" > /dev/null
      row="$row | $(python3 -c "import json; r=json.load(open('$out/${name}_${signal}_$mode.json')); print('%.3f' % r['e_default_percent'] + ('' if '$mode' == 'off' else ' | %d' % r['limited_vertices']))")"
    done
    echo "$row |"
  done
done
