#!/usr/bin/env bash
# Refinement at non-manifold edges (issue 12, point 6): the generated voxel world (104,556
# triangles, 4,235 edges of four faces) refined to 10x its triangles, the faces' angles counted
# from the asset, and the surface error against one fixed reference. OLD_PRTSUB, if given, is a
# build from before non-manifold edges were split, run on the same input in the same run.
#   bench/non_manifold.sh BUILD_DIR SHARED_SCENES_DIR OUT_DIR [OLD_PRTSUB]
set -euo pipefail
B="$1/prtsub"; S="$2"; O="$3"; OLD="${4:-}"
here="$(cd "$(dirname "$0")" && pwd)"
mkdir -p "$O"
python3 "$here/make_scenes.py" "$S" "$O/scenes" > /dev/null
in="$O/scenes/voxel_world.obj"
for run in new ${OLD:+old}; do
  bin="$B"; [ "$run" = old ] && bin="$OLD"
  /usr/bin/time -f "  $run: %e s wall, %M KiB peak" "$bin" bake "$in" -o "$O/voxel_$run.ply" --rays 64 \
    --refine adaptive --budget 1045560 --report "$O/voxel_$run.json" | grep -E "refine:|min angle|non-manifold edges,"
  PYTHONPATH="$1/python" /usr/bin/python3 "$here/mesh_angles.py" "$O/voxel_$run.ply"
  "$B" eval "$O/voxel_$run.ply" --source "$in" --rays 1024 --points 20000 | grep -E "error|RMS" | head -2
done
