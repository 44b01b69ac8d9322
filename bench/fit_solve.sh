#!/usr/bin/env bash
# The fit's assembly and solve alone (issue 11, point 4) on each scene, every vertex an unknown,
# order-4 transfer (16 right-hand sides), best of REPEAT runs of `prtsub bench --solve`; with a
# second build, the two alternate scene by scene (the machine is shared: compare within a run).
# SOLVERS="auto cg multigrid cholmod" runs each of those --solver choices in turn (default: auto).
# A SCENE with a slash is a path of its own (a refined mesh from `bake --stage refine`).
# usage: bash bench/fit_solve.sh SCENES_DIR OUT_DIR REPEAT "SCENE..." BUILD_DIR [BUILD_DIR...]
set -euo pipefail
scenes=$1 out=$2 repeat=$3 scene_list=$4
shift 4
mkdir -p "$out"
echo "| scene | build | unknowns | total s | assemble s | factor s | solve s | solver | CG iterations | stiff rows | factor entries | peak MiB |"
echo "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|"
solvers=${SOLVERS:-auto}
for scene in $scene_list; do
  name=$(basename "${scene%.*}")
  path=$scene
  [[ $scene == */* ]] || path=$scenes/$scene
  for build in "$@"; do
   for solver in $solvers; do
    label=$build
    [[ $solvers == auto ]] || label="$build --solver $solver"
    r="$out/${name}_$(echo "$build" | tr '/' '_')_$solver.json"
    "$build/prtsub" bench "$path" --solve --solver "$solver" --repeat "$repeat" --report "$r" > /dev/null
    python3 - "$r" "$name" "$label" <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
stiff = b.get('fit_stiff_share')
solver = b['fit_solver']
if b.get('fit_multigrid_levels'):
    solver += ' (%d levels, complexity %.2f)' % (b['fit_multigrid_levels'], b['fit_multigrid_operator_complexity'])
print('| %s | %s | %d | %.3f | %.3f | %.3f | %.3f | %s | %d | %s | %d | %.0f |' % (
    sys.argv[2], sys.argv[3], b['vertices'] if 'vertices' in b else -1, b['seconds_fit_best'], b['seconds_fit_assemble'],
    b['seconds_fit_factor'], b['seconds_fit_solve'], solver, b['fit_cg_iterations'],
    '–' if stiff is None else '%.1f%%' % (100 * stiff), b['fit_factor_nonzeros'], b['peak_memory_mib']))
PY
   done
  done
done
