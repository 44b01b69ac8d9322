#!/usr/bin/env bash
# --error with bounces (issue 18, point 3): each "scene:E" baked with --error E --bounces 3, then
# judged by eval against light bounced as often (1,024 rays and paths per point, 5,000 points,
# the same seed for every asset). eval's RMS holds its reference's own noise, so the table also
# gives √(RMS² − floor²), the asset's error, which the bake's prediction should match.
# usage: bash bench/bounce_target.sh BUILD_DIR SCENES_DIR OUT_DIR "scene.obj:E ..."
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
echo "| scene | E % | predicted, bounced % (± se) | predicted, direct % | eval RMS % | floor % | eval without floor % | bounce rays/vertex: chosen, last | rounds (bounce, direct) | rays M | of them bounce M | measuring M | bake s |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for item in $4; do
  scene=${item%%:*} E=${item##*:} name=${scene%.*}_$E
  "$build/prtsub" bake "$scenes/$scene" -o "$out/$name.ply" --error "$E" --bounces 3 --report "$out/$name.json" > /dev/null 2> "$out/$name.err"
  "$build/prtsub" eval "$out/$name.ply" --source "$scenes/$scene" --points 5000 --rays 1024 --report "$out/${name}_eval.json" > /dev/null
  python3 - "$out/$name.json" "$out/${name}_eval.json" "${scene%.*}" "$E" <<'PY'
import json, math, sys
b, e = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
rms, floor = e["rms_percent"], e["noise_floor_percent"]
print("| %s | %s | %.2f (± %.2f) | %.2f | %.2f | %.2f | %.2f | %d, %d | %d, %d | %.1f | %.1f | %.1f | %.1f |" % (sys.argv[3], sys.argv[4],
      b["predicted_error_percent"], b["predicted_error_standard_error"], b["predicted_direct_error_percent"], rms, floor,
      math.sqrt(max(0.0, rms * rms - floor * floor)), b["bounce_rays_chosen"], b["bounce_rays_per_vertex"], b["target_bounce_rounds"], b["target_direct_rounds"],
      b["rays"] / 1e6, b["bounce_rays"] / 1e6, b["target_holdout_rays"] / 1e6, b["seconds_total"]))
PY
done
