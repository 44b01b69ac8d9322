#!/usr/bin/env bash
# How the fit's time and memory grow with the mesh (issue 11, point 4): one scene, uniformly
# refined 0, 1 and 2 times (×4 triangles each), baked with every face sampled (the fit's worst
# case: every vertex an unknown) and with the pilot (the default). Per row: vertices, the fit's
# unknowns, assembly + solve seconds of the fit kept, the whole fit stage (the unshadowed
# projection and alpha's trials with it) per 100k vertices, the solve's memory, the bake's peak
# memory and seconds; then the system itself: alpha, CG's iterations, and the assembly and the
# solve per 100k unknowns (the assembly also by part, the solve also per iteration), which say
# whether a row's cost grows.
# LEVELS (default "0 1 2") and ALLOCATIONS (default "area pilot") choose the rows; further
# arguments go to every bake (e.g. --alpha 0.04 to hold the system's weights fixed).
# usage: bash bench/fit_scaling.sh BUILD_DIR SCENES_DIR OUT_DIR SCENE [bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3 scene=$4
shift 4
mkdir -p "$out"
echo "| levels | allocation | vertices | unknowns | fit s (assemble + solve) | fit s per 100k unknowns | fit stage s | fit stage s per 100k vertices | solve MiB | peak MiB | bake s | alpha | CG iterations | assemble s per 100k unknowns | of it: sums, edges, rows | solve s per 100k unknowns | solve s per 100k unknowns per iteration |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|"
for levels in ${LEVELS:-0 1 2}; do
  refine=(--refine none)
  [ "$levels" -gt 0 ] && refine=(--refine uniform --levels "$levels")
  for allocation in ${ALLOCATIONS:-area pilot}; do
    r="$out/${scene%.*}_${levels}_${allocation}.json"
    "$build/prtsub" bake "$scenes/$scene" "${refine[@]}" --sample-allocation "$allocation" "$@" -o "$out/a.ply" --report "$r" > /dev/null
    python3 - "$r" "$levels" "$allocation" <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
unknowns = b['vertices_out'] - b['fit_unsupported_vertices']
fit = b['seconds_fit_assemble'] + b['seconds_fit_factor'] + b['seconds_fit_solve']
per = 1e5 / max(unknowns, 1)
its = b.get('fit_cg_iterations', 0)
parts = ', '.join('%.3f' % (b.get('seconds_fit_assemble_' + w, 0) * per) for w in ('sums', 'edges', 'rows'))
print('| %s | %s | %d | %d | %.2f | %.3f | %.2f | %.3f | %.1f | %.0f | %.1f | %g | %d | %.3f | %s | %.3f | %s |' % (sys.argv[2], sys.argv[3], b['vertices_out'], unknowns, fit,
      fit * per, b['seconds_fit'], b['seconds_fit'] / b['vertices_out'] * 1e5, b['solve_memory_mib'],
      b['peak_memory_mib'], b['seconds_total'], b['alpha'], its, b['seconds_fit_assemble'] * per, parts, b['seconds_fit_solve'] * per,
      '%.4f' % (b['seconds_fit_solve'] * per / its) if its else '–'))
PY
  done
done
rm -f "$out/a.ply"
