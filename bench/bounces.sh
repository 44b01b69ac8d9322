#!/usr/bin/env bash
# Interreflection (issue 18): each scene baked with 0-4 bounces (default settings otherwise,
# albedo 0.8), the time of the bounce passes against the direct transfer stage's rays per second
# in the same bake, the rays they trace, and how much brighter the asset is under a constant
# light (the Gouraud frame's mean radiance, the same camera), and the eval error of each asset
# against light bounced as often (eval's path-traced reference, 5000 points, the same seed), and
# that of the direct-only asset against the same reference: what ignoring the bounces costs.
# Then the light-leak check: a closed room baked with 4 bounces must stay black.
# usage: bash bench/bounces.sh BUILD_DIR SCENES_DIR OUT_DIR "scene.obj ..."
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
echo "| scene | bounces | bake s | bounce s | bounce rays | bounce Mrays/s | transfer Mrays/s | last pass added % | mean radiance | brighter | eval % | direct-only asset's eval % | reference noise % |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for scene in $4; do
  name=${scene%.*}
  base=""
  for k in 0 1 2 3 4; do
    "$build/prtsub" bake "$scenes/$scene" -o "$out/${name}_$k.ply" --bounces $k --report "$out/${name}_$k.json" > /dev/null
    "$build/prtsub" render "$out/${name}_$k.ply" --light const:1 --size 320,240 -o "$out/${name}_$k.exr" --report "$out/${name}_${k}_render.json" > /dev/null
    "$build/prtsub" eval "$out/${name}_$k.ply" --source "$scenes/$scene" --points 5000 --report "$out/${name}_${k}_eval.json" > /dev/null
    "$build/prtsub" eval "$out/${name}_0.ply" --source "$scenes/$scene" --points 5000 --reference-bounces $k --report "$out/${name}_${k}_eval0.json" > /dev/null
    python3 - "$out/${name}_$k.json" "$out/${name}_${k}_render.json" "$name" "$k" "$out/${name}_0_render.json" "$out/${name}_${k}_eval.json" "$out/${name}_${k}_eval0.json" <<'PY'
import json, sys
b, r, base = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), json.load(open(sys.argv[5]))
e, e0 = json.load(open(sys.argv[6])), json.load(open(sys.argv[7]))
k = int(sys.argv[4])
bs = b.get("seconds_bounce", 0.0)
br = b.get("bounce_rays", 0)
vr = b["vertices_out"] * b["rays_per_vertex"]
tr = vr / max(b["seconds_transfer"], 1e-9) / 1e6
print("| %s | %d | %.2f | %.3f | %d | %s | %.2f | %s | %.4f | %+.1f%% | %.2f | %.2f | %.2f |" % (sys.argv[3], k, b["seconds_total"], bs, br,
      "%.2f" % (br / bs / 1e6) if bs > 0 else "-", tr, "%.3f" % b["bounce_change_percent"] if k else "-",
      r["mean_radiance"], 100 * (r["mean_radiance"] / base["mean_radiance"] - 1), e["rms_percent"], e0["rms_percent"],
      e["noise_floor_percent"]))
PY
  done
done
# The light-leak check: a closed unit cube wound inwards.
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3\nf 1 3 4\nf 5 8 7\nf 5 7 6\nf 1 5 6\nf 1 6 2\nf 2 6 7\nf 2 7 3\nf 3 7 8\nf 3 8 4\nf 4 8 5\nf 4 5 1\n' > "$out/room.obj"
"$build/prtsub" bake "$out/room.obj" -o "$out/room.ply" --bounces 4 --albedo 1 --crease-angle 0 > /dev/null
"$build/prtsub" inspect "$out/room.ply" --report "$out/room_inspect.json" > /dev/null
python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print('closed room, 4 bounces at albedo 1: energy in band 0 = %s' % r.get('energy_fraction_band_0'))" "$out/room_inspect.json"
