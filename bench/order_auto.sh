#!/usr/bin/env bash
# --order auto (issue 15): each scene's choice, against the order at which image error stops
# improving. The choice is made three ways: eval's worst-light metric (the default), and under
# each of the two lights below (--order-light). Every scene is baked at orders 1-8 (default settings otherwise) and rendered
# (Gouraud, 320x240, auto camera) under two lights, a sky and a sun of 5 degrees; each frame is
# compared with the per-pixel reference at order 10 under the same light (512 rays a pixel), so
# what an order leaves out counts. "Stops improving" is the lowest order whose image error is
# within 5% of the best of orders 1-8.
# usage: bash bench/order_auto.sh BUILD_DIR SCENES_DIR OUT_DIR "scene.obj ..."
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
sky="sky" sun="sun:0.4,1,0.3,5"
echo "| scene | auto (worst light) | sky: image error % at orders 1-8 | sky: stops at | auto --order-light sky | sun: image error % at orders 1-8 | sun: stops at | auto --order-light sun | pilot s |"
echo "|---|---:|---|---:|---:|---|---:|---:|---:|"
for scene in $4; do
  name=${scene%.*}
  "$build/prtsub" bake "$scenes/$scene" -o "$out/${name}_auto.ply" --order auto --report "$out/${name}_auto.json" > /dev/null
  for light in sky sun; do
    "$build/prtsub" bake "$scenes/$scene" -o "$out/${name}_auto_$light.ply" --order auto --order-light "${!light}" --fit point \
      --report "$out/${name}_auto_$light.json" > /dev/null
    "$build/prtsub" render "$out/${name}_auto.ply" --light "${!light}" --size 320,240 --reference --reference-order 10 --rays 512 \
      -o "$out/${name}_ref_$light.exr" > /dev/null
  done
  for n in 1 2 3 4 5 6 7 8; do
    "$build/prtsub" bake "$scenes/$scene" -o "$out/${name}_$n.ply" --order $n > /dev/null
    for light in sky sun; do
      "$build/prtsub" render "$out/${name}_$n.ply" --light "${!light}" --size 320,240 -o "$out/${name}_${n}_$light.exr" > /dev/null
      "$build/prtsub" diff "$out/${name}_${n}_$light.exr" "$out/${name}_ref_$light.exr" --report "$out/${name}_${n}_$light.json" > /dev/null
    done
  done
  python3 - "$out" "$name" <<'PY'
import json, sys
out, name = sys.argv[1], sys.argv[2]
a = json.load(open("%s/%s_auto.json" % (out, name)))
cells = []
for light in ("sky", "sun"):
    e = [json.load(open("%s/%s_%d_%s.json" % (out, name, n, light)))["rmse_percent"] for n in range(1, 9)]
    stop = next(n for n in range(1, 9) if e[n - 1] <= 1.05 * min(e))
    cells += [" ".join("%.1f" % x for x in e), str(stop), str(json.load(open("%s/%s_auto_%s.json" % (out, name, light)))["order"])]
print("| %s | %d | %s | %.2f |" % (name, a["order"], " | ".join(cells), a["seconds_order"]))
PY
done
