#!/usr/bin/env bash
# Spherical-Gaussian assets against SH assets in relit frames (issue 15, point 3): storage against
# image error. Each scene is baked five ways at the same rays per vertex, point values, no
# refinement: SH orders 3 and 4, and 9 and 12 non-negative lobes, and 12 signed lobes. Each asset is
# rendered as a GPU shows it (Gouraud) under five lights taken at order 10 (`--light-order 10`: every
# asset sees the bands it has of one light): the studio environment map, a 5-degree sun, and random
# unit-power lights 1-3. Each frame is judged by `prtsub diff` against the per-pixel reference
# (order-10 transfer at every pixel, REF_RAYS rays): RMSE in percent of the reference's RMS radiance
# (`rmse_rms_relative`; random lights shade negative in places, so their mean is no scale). A second reference with another seed gives the
# references' own noise: "floor" is diff(ref, ref2)/sqrt(2), and each error is also given without it,
# sqrt(rmse^2 - floor^2).
# usage: bash bench/sg_frames.sh BUILD_DIR SCENES_DIR OUT_DIR RAYS REF_RAYS "scene.obj:UP:BUDGET ..."
#        (UP y or z: a z-up scene has the environment and the sun turned to its up; BUDGET > 0 refines
#        every variant adaptively to that many triangles first, for inputs too coarse to interpolate)
set -euo pipefail
build=$1 scenes=$2 out=$3 rays=$4 ref_rays=$5
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
size=320,240
variants="sh3:--order,3 sh4:--order,4 sg9:--basis,sg:9 sg12:--basis,sg:12 sg12s:--basis,sg:12,--sg-signed"
echo "| scene | light | floor % | SH-3 (36 B) | SG-9 (36 B) | SG-12 (48 B) | SG-12 signed (48 B) | SH-4 (64 B) |"
echo "|---|---|---:|---:|---:|---:|---:|---:|"
for item in $6; do
  IFS=: read -r scene up budget <<< "$item"
  name=${scene%.*} rotate=() refine=()
  [[ $up == z ]] && rotate=(--light-rotate x,90)
  [[ $budget -gt 0 ]] && refine=(--refine adaptive --budget "$budget")
  for v in $variants; do
    tag=${v%%:*} flags=${v#*:}
    # shellcheck disable=SC2086
    "$build/prtsub" bake "$scenes/$scene" -o "$out/${name}_$tag.ply" --fit point --rays "$rays" "${refine[@]}" ${flags//,/ } \
      --report "$out/${name}_$tag.json" > /dev/null
  done
  for light in "env:$root/viewer/assets/studio.png" "sun:0.4,1,0.3,5" random:1 random:2 random:3; do
    lname=${light%%:*}; [[ $lname == random ]] && lname=$light
    base="$out/${name}_${lname//:/}"
    for seed in 1 2; do
      "$build/prtsub" render "$out/${name}_sh4.ply" --light "$light" "${rotate[@]}" --size $size --reference --reference-order 10 \
        --rays "$ref_rays" --seed "$seed" -o "${base}_ref$seed.exr" > /dev/null 2>&1
    done
    "$build/prtsub" diff "${base}_ref2.exr" "${base}_ref1.exr" --report "${base}_floor.json" > /dev/null
    row="| $name | $lname |"
    floor=$(python3 -c "import json,math; print(json.load(open('${base}_floor.json'))['rmse_rms_relative']/math.sqrt(2))")
    row+=$(python3 -c "print(' %.2f |' % (100 * $floor))")
    for tag in sh3 sg9 sg12 sg12s sh4; do
      "$build/prtsub" render "$out/${name}_$tag.ply" --light "$light" "${rotate[@]}" --size $size --light-order 10 \
        -o "${base}_$tag.exr" > /dev/null 2>&1
      "$build/prtsub" diff "${base}_$tag.exr" "${base}_ref1.exr" --report "${base}_$tag.json" > /dev/null
      row+=$(python3 -c "
import json, math
e = json.load(open('${base}_$tag.json'))['rmse_rms_relative']
print(' %.2f (%.2f) |' % (100 * e, 100 * math.sqrt(max(0.0, e * e - $floor ** 2))))")
    done
    echo "$row"
  done
done
