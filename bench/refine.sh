#!/usr/bin/env bash
# The refinement measurements behind BENCHMARKS.md (issue 4). Takes ~10 minutes on 2 cores.
#   bench/refine.sh BUILD_DIR SHARED_SCENES_DIR OUT_DIR
# then: python3 bench/summarize.py OUT_DIR
set -euo pipefail
B="$1/prtsub"; S="$2"; O="$3"
here="$(cd "$(dirname "$0")" && pwd)"
mkdir -p "$O"
python3 "$here/make_scenes.py" "$S" "$O/scenes"

triangles() {  # input triangle count, from a one-ray bake's report
  "$B" bake "$1" -o "$O/count.ply" --rays 1 --report "$O/count.json" > /dev/null
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['triangles_out'])" "$O/count.json"
}

# 1. Which estimate wins, on every scene.
bash "$here/estimates.sh" "$1" "$S" "$O"

# 2. The targets: contact-shadow scenes at the triangle count of uniform level 3.
for f in "$S/cornell_box.obj" "$S/house_on_site.obj" "$O/scenes/spot_on_ground.obj" "$O/scenes/icosphere_on_plane.obj"; do
  n=$(basename "${f%.*}"); F=$(triangles "$f")
  echo "== target: $n ($F triangles, level 3 = $((64 * F)))"
  "$B" compare "$f" --budgets $((64 * F)) --max-levels 3 --rays 128 --eval-points 20000 -o "$O/targets/$n"
done

# 3. Refinement overhead and scaling: four budgets up to 200k on the teapot.
bash "$here/refine_scaling.sh" "$1" "$S" "$O"

# 4. Batch size: time and error at 64x the input on two contact-shadow scenes.
bash "$here/batch.sh" "$1" "$S" "$O/scenes" "$O"
rm -f "$O/count.ply" "$O/count.json"
echo "done: python3 bench/summarize.py $O"
