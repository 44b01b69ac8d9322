#!/usr/bin/env bash
# Issue 4's contact-shadow targets again, now with point and fitted values side by side:
# uniform level 3 against adaptive (the default estimate, root) at the same count, 128 rays per vertex.
# usage: bash bench/fit_targets.sh BUILD_DIR SCENES_DIR GENERATED_DIR OUT_DIR
set -euo pipefail
build=$1 scenes=$2 gen=$3 out=$4
for sc in "$scenes/cornell_box.obj:2048" "$scenes/house_on_site.obj:173440" "$gen/spot_on_ground.obj:23936" "$gen/icosphere_on_plane.obj:5248"; do
  scene=${sc%%:*} count=${sc##*:} name=$(basename "${scene%.*}")
  "$build/prtsub" compare "$scene" --budgets "$count" --estimates root --rays 128 --max-levels 3 -o "$out/$name" > "$out/$name.log"
  grep -E "(uniform|root) +(point|lsq) +$count " "$out/$name.log" | sed "s|^|$name |"
done
