#!/usr/bin/env bash
# Coloured interreflection (issue 18, point 2). For each scene and albedo, three bakes at the same
# bounces and rays: grey at albedo G, the same albedo in colour (RGB transfer), and the grey
# one again judged against the coloured reference (eval --reference-albedo: the same transfer
# in every channel), which is what baking a coloured scene without colour costs. Each coloured
# eval uses one fixed reference (--points, --rays, --paths, the default seed). Then the cost of
# colour: the bounce stage's seconds grey against RGB in the same run, and the asset's bytes.
# usage: [BAKE="more bake options"] bash bench/colour.sh BUILD_DIR OUT_DIR BOUNCES "scene.ply|obj:ALBEDO:GREY ..."
#   ALBEDO is what --albedo takes (vertex, or R,G,B); GREY the grey albedo of the grey bake.
set -euo pipefail
build=$1 out=$2 bounces=$3 more=${BAKE:-}
mkdir -p "$out"
echo "| scene | albedo | bake s grey / RGB | bounce s grey / RGB | asset MB grey / RGB | eval % grey vs grey ref | eval % RGB vs RGB ref | eval % grey vs RGB ref | ref noise % |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
for item in $4; do
  scene=${item%%:*} rest=${item#*:}
  albedo=${rest%%:*} grey=${rest#*:}
  name=$(basename "${scene%.*}")
  ev="--points 5000 --rays 2048 --paths 1024"
  "$build/prtsub" bake "$scene" -o "$out/${name}_grey.ply" --bounces "$bounces" --albedo "$grey" $more --report "$out/${name}_grey.json" > /dev/null
  "$build/prtsub" bake "$scene" -o "$out/${name}_rgb.ply" --bounces "$bounces" --albedo "$albedo" $more --report "$out/${name}_rgb.json" > /dev/null
  "$build/prtsub" eval "$out/${name}_grey.ply" --source "$scene" $ev --report "$out/${name}_e_grey.json" > /dev/null
  "$build/prtsub" eval "$out/${name}_rgb.ply" --source "$scene" $ev --report "$out/${name}_e_rgb.json" > /dev/null
  "$build/prtsub" eval "$out/${name}_grey.ply" --source "$scene" $ev --reference-albedo "$albedo" --report "$out/${name}_e_cross.json" > /dev/null
  python3 - "$out" "$name" "$albedo" <<'PY'
import json, os, sys
out, name, albedo = sys.argv[1:4]
j = lambda s: json.load(open(os.path.join(out, name + s)))
g, c, eg, ec, ex = j("_grey.json"), j("_rgb.json"), j("_e_grey.json"), j("_e_rgb.json"), j("_e_cross.json")
mb = lambda s: os.path.getsize(os.path.join(out, name + s)) / 1e6
print("| %s | %s | %.2f / %.2f | %.3f / %.3f | %.2f / %.2f | %.2f | %.2f | %.2f | %.2f |" % (name, albedo, g["seconds_total"], c["seconds_total"],
      g["seconds_bounce"], c["seconds_bounce"], mb("_grey.ply"), mb("_rgb.ply"), eg["rms_percent"], ec["rms_percent"], ex["rms_percent"],
      ec["noise_floor_percent"]))
PY
done
