#!/usr/bin/env bash
# How the fit's time and memory grow with the mesh (issue 11, point 4): one scene, uniformly
# refined 0, 1 and 2 times (×4 triangles each), baked with every face sampled (the fit's worst
# case: every vertex an unknown) and with the pilot (the default). Per row: vertices, the fit's
# unknowns, assembly + solve seconds of the fit kept, the whole fit stage (the unshadowed
# projection and alpha's trials with it) per 100k vertices, the solve's memory, the bake's peak
# memory and seconds.
# usage: bash bench/fit_scaling.sh BUILD_DIR SCENES_DIR OUT_DIR SCENE
set -euo pipefail
build=$1 scenes=$2 out=$3 scene=$4
mkdir -p "$out"
echo "| levels | allocation | vertices | unknowns | fit s (assemble + solve) | fit s per 100k unknowns | fit stage s | fit stage s per 100k vertices | solve MiB | peak MiB | bake s |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for levels in 0 1 2; do
  refine=(--refine none)
  [ "$levels" -gt 0 ] && refine=(--refine uniform --levels "$levels")
  for allocation in area pilot; do
    r="$out/${scene%.*}_${levels}_${allocation}.json"
    "$build/prtsub" bake "$scenes/$scene" "${refine[@]}" --sample-allocation "$allocation" -o "$out/a.ply" --report "$r" > /dev/null
    python3 - "$r" "$levels" "$allocation" <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
unknowns = b['vertices_out'] - b['fit_unsupported_vertices']
fit = b['seconds_fit_assemble'] + b['seconds_fit_factor'] + b['seconds_fit_solve']
print('| %s | %s | %d | %d | %.2f | %.3f | %.2f | %.3f | %.1f | %.0f | %.1f |' % (sys.argv[2], sys.argv[3], b['vertices_out'], unknowns, fit,
      fit / max(unknowns, 1) * 1e5, b['seconds_fit'], b['seconds_fit'] / b['vertices_out'] * 1e5, b['solve_memory_mib'],
      b['peak_memory_mib'], b['seconds_total']))
PY
  done
done
rm -f "$out/a.ply"
